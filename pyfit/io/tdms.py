"""The channels of an NI TDMS file (what LabVIEW, NI-DAQmx logging, SignalExpress and FlexLogger write), read
with npTDMS: each numeric channel by 'group/channel', and by its bare name where no other group holds one of
that name, with the properties a measurement needs: the unit NI's `unit_string` gives and the waveform's
sample spacing `wf_increment` [s] and start `wf_start_offset` [s].
"""
from __future__ import annotations

import collections
import pathlib
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TdmsChannel:
    """One numeric channel: its samples, its unit as the file writes it ('' when it has none), and its waveform
    timing (increment_s None for a channel that is not a waveform)."""

    data: np.ndarray
    unit: str
    increment_s: float | None
    offset_s: float


class TdmsFileError(ValueError):
    """The file is not a TDMS file npTDMS can read."""


def tdms_channels(path: str | pathlib.Path) -> dict[str, TdmsChannel]:
    """The numeric channels of a TDMS file by 'group/channel' and, where unique in the file, by channel name;
    raises TdmsFileError for a file that is not one."""
    from nptdms import TdmsFile

    try:
        f = TdmsFile.read(str(path))
    except Exception as exc:  # npTDMS raises ValueError, KeyError, struct.error ... on a file that is not TDMS
        raise TdmsFileError(f"{type(exc).__name__}: {exc}") from exc
    found = []  # (group, channel, its samples and properties)
    for group in f.groups():
        for ch in group.channels():
            data = np.asarray(ch[:])
            if data.dtype.kind not in "biuf" or data.ndim != 1:
                continue  # text, timestamps, complex values
            p = ch.properties
            increment = p.get("wf_increment")
            found.append((group.name, ch.name, TdmsChannel(data, str(p.get("unit_string", "")),
                                                           float(increment) if increment else None,
                                                           float(p.get("wf_start_offset", 0.0)))))
    bare = collections.Counter(name for _, name, _ in found)
    return {**{f"{g}/{name}": c for g, name, c in found}, **{name: c for _, name, c in found if bare[name] == 1}}
