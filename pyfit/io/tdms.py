"""The channels of an NI TDMS file (what LabVIEW, NI-DAQmx logging, SignalExpress and FlexLogger write), read
with npTDMS: each numeric channel by 'group/channel', and by its bare name where no other group holds one of
that name, with the properties a measurement needs: the unit NI's `unit_string` gives and the waveform's
sample spacing `wf_increment` [s] and start `wf_start_offset` [s]. A channel of time stamps (LabVIEW's: whole
seconds and 2^-64 s fractions) reads as the seconds from its first stamp, so that a sidecar's time_column can
name it.
"""
from __future__ import annotations

import pathlib

import numpy as np

from pyfit.io.waveform import NamedWaveforms, Waveform, by_names


class TdmsFileError(ValueError):
    """The file is not a TDMS file npTDMS can read."""


def tdms_channels(path: str | pathlib.Path) -> NamedWaveforms:
    """The numeric channels of a TDMS file by 'group/channel' and, where unique in the file, by channel name;
    raises TdmsFileError for a file that is not one."""
    from nptdms import TdmsFile

    try:
        f = TdmsFile.read(str(path), raw_timestamps=True)
    except Exception as exc:  # npTDMS raises ValueError, KeyError, struct.error ... on a file that is not TDMS
        raise TdmsFileError(f"{type(exc).__name__}: {exc}") from exc
    entries = []
    for group in f.groups():
        for ch in group.channels():
            data = ch[:]
            if hasattr(data, "second_fractions") and len(data):  # time stamps: seconds from the first, exactly
                data = ((data.seconds - data.seconds[0]).astype(float)
                        + (data.second_fractions.astype(float) - float(data.second_fractions[0])) * 2.0**-64)
            data = np.asarray(data)
            if data.dtype.kind not in "biuf" or data.ndim != 1:
                continue  # text, complex values
            p = ch.properties
            increment = p.get("wf_increment")
            entries.append((f"{group.name}/{ch.name}", [ch.name],
                            Waveform(data, str(p.get("unit_string", "")), float(increment) if increment else None,
                                     float(p.get("wf_start_offset", 0.0)))))
    return by_names(entries)
