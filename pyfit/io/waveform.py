"""Channels of the binary measurement files that carry their own timing (NI TDMS, universal file dataset 58):
the samples, the unit the file writes, the waveform's sample spacing and start, and the names a sidecar may
use for each (a name two channels share picks neither, and is listed so that the refusal can name both)."""
from __future__ import annotations

import collections
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Waveform:
    """One numeric channel: its samples, its unit as the file writes it ('' when it has none), and its timing:
    the spacing increment_s [s] (None for a channel without one) and the first sample's time offset_s [s]."""

    data: np.ndarray
    unit: str
    increment_s: float | None
    offset_s: float


@dataclass(frozen=True)
class NamedWaveforms:
    """A file's channels by every name that picks out one of them, and each name that several channels share
    with the unique names of those channels."""

    channels: dict[str, Waveform]
    ambiguous: dict[str, list[str]]


def by_names(entries: list[tuple[str, list[str], Waveform]]) -> NamedWaveforms:
    """Channels from (unique name, other names, waveform) entries: each unique name, and each other name that
    one channel alone holds."""
    holders = collections.defaultdict(list)
    for full, others, _ in entries:
        for name in dict.fromkeys(others):
            if name and name != full:
                holders[name].append(full)
    channels = {full: w for full, _, w in entries}
    for full, others, w in entries:
        channels.update({n: w for n in others if n and holders.get(n) == [full] and n not in channels})
    return NamedWaveforms(channels, {n: fulls for n, fulls in holders.items() if len(fulls) > 1})
