"""The time records of a universal file (UFF/UNV, dataset 58: what modal and vibration test software such as
Simcenter Testlab, m+p, PULSE and Dewesoft export), read with pyuff. A record of real values whose abscissa is
time (function type 1, time response, or an abscissa of specific data type 17, time) at even spacing, in ASCII
or binary (58b, either byte order, single or double precision), is a channel, named by its position in the file
('#3'), by its first ID line (id1, what the test software calls the channel) and by its response node and
direction ('101:+Z'), each where no other record holds that name; its unit is the ordinate's unit label, its
timing the abscissa's minimum and increment (increment_of: the header holds six significant digits). Spectra,
FRFs, complex and unevenly spaced records are left aside.
"""
from __future__ import annotations

import pathlib

import numpy as np

from pyfit.io.waveform import NamedWaveforms, Waveform, by_names

TIME_RESPONSE, TIME_ABSCISSA, EVEN = 1, 17, 1  # function type, abscissa specific data type, spacing codes
REAL = (2, 4)  # ordinate data types: real single and double precision (5, 6: complex)
DIRECTIONS = {0: "S", 1: "+X", 2: "+Y", 3: "+Z", 4: "+RX", 5: "+RY", 6: "+RZ", -1: "-X", -2: "-Y", -3: "-Z",
              -4: "-RX", -5: "-RY", -6: "-RZ"}  # response direction codes (0: a scalar point)
INCREMENT_DIGITS = 6  # the abscissa increment's significant digits in the dataset's header (E13.5)


def increment_of(written: float) -> float:
    """The sample spacing [s] a header's increment, rounded to INCREMENT_DIGITS significant digits, stands for:
    that of the rate with the fewest significant digits (the rate a DAQ is set to) whose spacing rounds to the
    written value (1.33333e-03 s: 750 Hz, not 750.0019 Hz, which would put the 26 251st sample of a 35 s record
    0.07 samples off); the written value where no rate of up to INCREMENT_DIGITS digits does."""
    for digits in range(1, INCREMENT_DIGITS + 1):
        rate = float(f"{1.0 / written:.{digits}g}")
        if float(f"{1.0 / rate:.{INCREMENT_DIGITS - 1}e}") == float(f"{written:.{INCREMENT_DIGITS - 1}e}"):
            return 1.0 / rate
    return written


class UffFileError(ValueError):
    """The file is not a universal file pyuff can read."""


def _label(text) -> str:
    """A UFF text field, '' where the writer left it 'NONE'."""
    text = str(text or "").strip()
    return "" if text.upper() == "NONE" else text


def uff_channels(path: str | pathlib.Path) -> NamedWaveforms:
    """The time records (dataset 58) of a universal file by '#k', id1 and 'node:direction'; raises UffFileError
    for a file that is not one."""
    import pyuff

    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises Exception, ValueError, IndexError ... on a file that is not a UFF
        raise UffFileError(f"{type(exc).__name__}: {exc}") from exc
    entries = []
    for k, s in enumerate([sets] if isinstance(sets, dict) else sets, start=1):
        timed = s.get("func_type") == TIME_RESPONSE or s.get("abscissa_spec_data_type") == TIME_ABSCISSA
        if s.get("type") != 58 or not timed or s.get("ord_data_type") not in REAL or \
                s.get("abscissa_spacing") != EVEN:
            continue
        direction = DIRECTIONS.get(int(s.get("rsp_dir", 0)), str(s.get("rsp_dir")))
        entries.append((f"#{k}", [_label(s.get("id1")), f"{s.get('rsp_node')}:{direction}"],
                        Waveform(np.asarray(s["data"], float), _label(s.get("ordinate_axis_units_lab")),
                                 increment_of(float(s["abscissa_inc"])), float(s.get("abscissa_min", 0.0)))))
    return by_names(entries)
