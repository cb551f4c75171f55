"""Measurement files (theory §5): a CSV (or .txt, .dat, .tsv, .asc; any case) plus a TOML sidecar of the same stem,
or a MATLAB .mat file (any format, v4 to v7.3: pyfit.io.matlab) whose vectors, a struct's fields ('s.x') or one
matrix's columns (named by the sidecar's `columns`) are the columns, or an NI TDMS file (pyfit.io.tdms) whose channels
('group/channel', or the channel's name where unique) are, timed by their waveform properties, or a universal file
(.uff, .unv; pyfit.io.uff) whose time records (dataset 58) are, or a sheet of an Excel workbook (.xlsx, .xlsm;
pyfit.io.excel) read as the text of its CSV export.

Sidecar keys: model, sample_rate_hz (optional where the file has a time column: its rate, rate_of), [inputs]
and [outputs] mapping column -> {unit, model_variable[, weight, sensitivity, invert]} (sensitivity: a voltage
column's sensor, e.g. "100 mV/g": read as what the sensor measures; invert = true: a sensor whose sign convention
is the model's opposite, read with its sign changed);
optional level, level_value, excitation, notes, time_column (default "t"), time_unit ("s", "ms" or "clock":
wall-clock stamps, the record's time counted from its first), columns (the
names of the columns of a file without a header line, in order), sheet (an Excel workbook's sheet; default:
its first), [[segments]] (a file holding several levels or
runs: from_s, to_s and optionally level, level_value, excitation each; read as one measurement per segment).

The reader takes files as lab software writes them, wherever that is still unambiguous:
- files without a header line (a numeric export: MATLAB's `save -ascii`, a logger's raw dump) whose sidecar
  names their columns (`columns = [...]`);
- a preamble before the header without '#' (an export's settings, date, channel list): the header is the
  first line that names every column the sidecar uses;
- `#` comment lines before the header, quoted column names (commas inside quotes included) and quoted
  numbers, ',', tab or ';' between columns (the one the header holds most of outside quotes), or columns
  aligned by spaces (a header and a row below it that split at spaces into as many fields), a trailing
  delimiter, extra columns (never parsed);
- decimal commas where the columns are separated by ';', a tab or spaces (a spreadsheet's export in a locale that
  writes them): a comma inside a field can then only be the decimal mark;
- a units row under the header (every field non-numeric, e.g. `s,mm,kN`): skipped; where it names a known
  unit for a used column or the time column, that unit must be the sidecar's;
- unit spellings: `[mm]`, `m/s^2`, `m/s²`, `µm`, `μm` are the same as mm, m/s2, um;
- a time column rounded to as few as 6 significant digits, or none at all (then sample_rate_hz gives the
  time); the samples are put on the exact grid t0 + k/fs;
- units converted to SI on reading (see TO_SI); a voltage (V, mV) is read as the model's own unit: a signal
  proportional to the model variable with a gain nobody measured (a shaker's drive voltage for its force, an
  electronic oscillator's node voltage), which a model whose every parameter is fitted takes up
  (check_quantities says where it may stand).
and refuses, with one error naming file, row and value, what is not: a gap, a repeated or decreasing
time, a time column that disagrees with sample_rate_hz by more than MAX_TIME_SLIP samples, decimal commas
between ',' separators, a number with both a '.' and a decimal comma (digit grouping), a header and rows
that split at spaces into different numbers of fields, a units row that contradicts the sidecar, non-numeric
or non-finite values in a used column.
"""
from __future__ import annotations

import csv
import functools
import io
import itertools
import math
import pathlib
import re
import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from pyfit.io.excel import ExcelFileError, sheet_text
from pyfit.io.matlab import MatlabFileError, mat_variables
from pyfit.io.schema import ConfigError, check_table, fail, read_text, read_toml
from pyfit.io.tdms import TdmsFileError, tdms_channels
from pyfit.io.uff import UffFileError, uff_channels
from pyfit.io.units import FOOT, G0, INCH, NUMBER, POUND, parse_unit

TO_SI = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "in": INCH, "ft": FOOT, "rad": 1.0, "deg": np.pi / 180,
         "m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3, "in/s": INCH, "ft/s": FOOT,
         "m/s2": 1.0, "cm/s2": 1e-2, "mm/s2": 1e-3, "in/s2": INCH, "ft/s2": FOOT, "g": G0, "mg": 1e-3 * G0,
         "N": 1.0, "mN": 1e-3, "daN": 10.0, "kN": 1e3, "lbf": POUND * G0, "V": 1.0, "mV": 1e-3}
QUANTITY = {**{u: "length" for u in ("m", "cm", "mm", "um", "in", "ft")}, "rad": "angle", "deg": "angle",
            **{u: "velocity" for u in ("m/s", "cm/s", "mm/s", "in/s", "ft/s")},
            **{u: "acceleration" for u in ("m/s2", "cm/s2", "mm/s2", "in/s2", "ft/s2", "g", "mg")},
            **{u: "force" for u in ("N", "mN", "daN", "kN", "lbf")}, "V": "voltage", "mV": "voltage"}  # of TO_SI
TIME_UNITS = {"s": 1.0, "ms": 1e-3}
CLOCK = "clock"  # time_unit of a time column of wall-clock stamps (clock_seconds): the record's time from its first
MAX_ABS_SI = 1e100  # largest magnitude of a measured value in SI units: its square over a million samples,
#                      and its derivatives at MHz rates, stay far inside double precision (1.8e308)
MAX_TIME_SLIP = 0.25  # largest allowed distance [samples] of a time stamp from the uniform grid
SIDECAR = {"model": (str, True, None), "sample_rate_hz": ("number", False, None), "inputs": (dict, False, {}),
           "outputs": (dict, True, None), "level": (str, False, ""), "level_value": ("number", False, None),
           "excitation": (dict, False, {}), "notes": (str, False, ""), "time_column": (str, False, "t"),
           "time_unit": (str, False, "s"), "columns": ("strings", False, None), "segments": (list, False, []),
           "sheet": (str, False, None)}
SEGMENT = {"from_s": ("number", True, None), "to_s": ("number", True, None), "level": (str, False, ""),
           "level_value": ("number", False, None), "excitation": (dict, False, {})}  # one [[segments]] table


ALIASES = {"G": "g", "gn": "g", "ips": "in/s"}  # spellings DAQ software and US reports use for units of TO_SI
_SECONDS = re.compile(r"(?<![A-Za-z])(m?)sec(?![A-Za-z])")  # 'sec', 'msec' as in 'm/sec', 'Time [msec]'


def unit_key(unit: str) -> str:
    """A unit as TO_SI (or TIME_UNITS) spells it: brackets and spaces dropped, '^2', '**2' and '²' as '2',
    'µ'/'μ' as 'u', 'sec' as 's', ALIASES ('[m/s^2]' -> 'm/s2', 'm/sec' -> 'm/s', 'G' -> 'g'); a unit of the same
    quantity and size as one of TO_SI written another way ('m/s/s', 'm s^-2', 'm·s⁻²': pyfit.io.units) as that
    one; an unknown unit is returned as it is (after the same clean-up)."""
    spaced = _SECONDS.sub(r"\1s", unit.strip().strip("[]()").strip())
    u = spaced.replace(" ", "")
    for a, b in (("**2", "2"), ("^2", "2"), ("²", "2"), ("µ", "u"), ("μ", "u")):
        u = u.replace(a, b)
    u = ALIASES.get(u, u)
    return u if u in TO_SI or u in TIME_UNITS else _same_as(spaced) or u


_DIMENSION = {q: parse_unit(u).dimension for q, u in (("length", "m"), ("velocity", "m/s"), ("acceleration", "m/s2"),
                                                     ("force", "N"), ("voltage", "V"), ("angle", "rad"))}
# of QUANTITY's names


@functools.lru_cache(maxsize=None)
def _same_as(text: str) -> str | None:
    """The key of TO_SI whose quantity and size `text` has (pyfit.io.units grammar), or None."""
    try:
        wanted = parse_unit(text)
    except ValueError:
        return None
    for key in TO_SI:
        try:
            unit = parse_unit(key)
        except ValueError:
            continue
        if unit.dimension == _DIMENSION[QUANTITY[key]] == wanted.dimension and \
                math.isclose(unit.factor, wanted.factor, rel_tol=1e-12):
            return key
    return None


class MeasurementError(ConfigError):
    """A measurement file that cannot be used; names the file, the row or field, and what is allowed."""


@dataclass
class Channel:
    """One measured column: its unit in the file, the model variable it corresponds to, its weight, and for a
    sensor's voltage its sensitivity: `volts_per_unit` volts per one `measures` (e.g. 0.1 V per g)."""

    column: str
    unit: str
    model_variable: str
    weight: float = 1.0
    volts_per_unit: float | None = None
    measures: str | None = None  # the unit the sensitivity is per (None: the column's own unit)
    invert: bool = False  # the sensor's sign convention is the model's opposite: read with its sign changed

    @property
    def quantity_unit(self) -> str:
        """The unit of what the column measures: the sensitivity's, or the column's own."""
        return self.measures or self.unit

    @property
    def to_si(self) -> float:
        """SI units of the measured quantity, in the model's sign convention, per number in the file."""
        sign = -1.0 if self.invert else 1.0
        if self.volts_per_unit is None:
            return sign * TO_SI[self.unit]
        return sign * TO_SI[self.unit] / self.volts_per_unit * TO_SI[self.measures]


SENSITIVITY = re.compile(rf"^\s*({NUMBER})\s*(V|mV)\s*/\s*(\S+)\s*$")


def _sensitivity(side, where: str, text: str, unit: str) -> tuple[float, str]:
    """A sensor's sensitivity written as '100 mV/g' (a positive number, V or mV, per a unit of TO_SI that is
    no voltage) on a voltage column: (volts per unit, unit)."""
    allowed = ("'<number> V/<unit>' or '<number> mV/<unit>', e.g. '100 mV/g', '2.25 mV/N', '10 V/mm', on a V or "
               "mV column")
    if QUANTITY[unit] != "voltage":
        fail(side, where, f"on a column in '{unit}', not a voltage", allowed, MeasurementError)
    match = SENSITIVITY.match(text)
    per = unit_key(match.group(3)) if match else ""
    if not match or per not in TO_SI or QUANTITY[per] == "voltage" or not float(match.group(1)) > 0:
        fail(side, where, f"{text!r} is not a sensitivity", allowed, MeasurementError)
    return float(match.group(1)) * TO_SI[match.group(2)], per


@dataclass
class Measurement:
    """Signals in SI units on a uniform grid, keyed by column name."""

    path: pathlib.Path
    model: str
    t: np.ndarray
    inputs: dict[str, Channel]
    outputs: dict[str, Channel]
    values: dict[str, np.ndarray]
    level: str = ""
    level_value: float | None = None
    excitation: dict = field(default_factory=dict)
    notes: str = ""
    segment: str = ""  # which of the file's [[segments]] (1, 2, ...; "" for the whole file)
    segments: list = field(default_factory=list)  # the sidecar's [[segments]] tables, checked (split_segments)

    @property
    def name(self) -> str:
        """The file's stem, and '#k' for its k-th segment: how every table and figure names the record."""
        return f"{self.path.stem}#{self.segment}" if self.segment else self.path.stem

    @property
    def sample_rate_hz(self) -> float:
        return 1.0 / (self.t[1] - self.t[0])

    @property
    def samples_per_period(self) -> int:
        """Samples per period of a periodic record (excitation kind multisine), 0 otherwise."""
        exc = self.excitation or {}
        return int(exc.get("samples_per_period", 0)) if exc.get("kind") == "multisine" else 0

    def by_variable(self, kind: str = "outputs") -> dict[str, np.ndarray]:
        """Signals keyed by model variable name."""
        return {ch.model_variable: self.values[c] for c, ch in getattr(self, kind).items()}


def _channels(side, table, section) -> dict[str, Channel]:
    out = {}
    for col, spec in table.items():
        c = check_table(spec, side, f"{section}.{col}", {"unit": (str, True, None), "model_variable": (str, True, None),
                                                         "weight": ("number", False, 1.0),
                                                         "sensitivity": (str, False, None),
                                                         "invert": (bool, False, False)}, MeasurementError)
        c["unit"] = unit_key(c["unit"])
        if c["unit"] not in TO_SI:
            fail(side, f"{section}.{col}.unit", f"'{c['unit']}' unknown", ", ".join(TO_SI), MeasurementError)
        if c["weight"] <= 0:
            fail(side, f"{section}.{col}.weight", f"{c['weight']} is not > 0", error=MeasurementError)
        volts, per = (_sensitivity(side, f"{section}.{col}.sensitivity", c["sensitivity"], c["unit"])
                      if c["sensitivity"] is not None else (None, None))
        out[col] = Channel(col, c["unit"], c["model_variable"], c["weight"], volts, per, c["invert"])
    return out


def _fields(line: str, delimiter: str) -> list[str]:
    """The fields of one CSV line (quotes removed, a delimiter inside quotes kept), stripped; a trailing empty
    field (a line that ends in the delimiter) dropped; with SPACES, any run of spaces one delimiter."""
    fields = [f.strip() for f in next(csv.reader([line.strip()], delimiter=delimiter, skipinitialspace=True))]
    return fields[:-1] if len(fields) > 1 and fields[-1] == "" else fields


def _numeric(field: str, delimiter: str = ",") -> bool:
    try:
        float(_decimal_point(field, delimiter))
        return True
    except ValueError:
        return False


def _decimal_point(text: str, delimiter: str) -> str:
    """`text` with its decimal commas as points, where the columns are not separated by commas (';', a tab or
    spaces: a comma can then only be a decimal mark); as it is where they are."""
    return text if delimiter == "," else text.replace(",", ".")


DELIMITERS = (",", "\t", ";")  # between columns; of as many in a header, the first
SPACES = " "  # columns aligned by spaces (a text export): any run of spaces between fields


def _delimiter(header: str, below: str) -> str:
    """The column delimiter of a header line: of DELIMITERS, the one it holds most of outside quoted names;
    when it holds none, SPACES if it and the line below it (`below`: a units row or the first data row) split
    at spaces into as many fields, more than one; else ',' (a single column, whose name may hold spaces)."""
    bare = re.sub(r'"[^"]*"', "", header)
    if not any(d in bare for d in DELIMITERS) and len(_fields(header, SPACES)) == len(_fields(below, SPACES)) > 1:
        return SPACES
    return max(DELIMITERS, key=lambda d: (bare.count(d), -DELIMITERS.index(d)))


@dataclass
class _Header:
    """Column names, the number of lines before the data (comments, header, units row), the delimiter, and
    the units row (column -> unit as written; {} if the file has none)."""

    names: list[str]
    skip: int
    delimiter: str
    units: dict[str, str]


def _lines(text: str) -> io.StringIO:
    """The decoded file as lines, whatever its line ends (LF, CRLF or CR)."""
    return io.StringIO(text, newline=None)


PREAMBLE_LINES = 100  # lines looked through for the header (or a header-less file's first data line)


def _content(text: str):
    """(row number, line) of each line with content that is no '#' comment."""
    with _lines(text) as f:
        for number, line in enumerate(f, 1):
            if line.strip() and not line.lstrip().startswith("#"):
                yield number, line


def _first_row(lines: list[tuple[int, str]], wanted: list[str], columns: list[str] | None) -> int:
    """Where the header is among `lines` (_content's; a file without a header line: its first data line), past
    a preamble without '#' (an export's settings, its date, its channel list): the first line that names every
    `wanted` column in as many fields as the line below it holds, or that splits into as many numbers as
    `columns` has names; the first line when none does (which is then refused, naming its row)."""
    for k, (_, line) in enumerate(lines[:PREAMBLE_LINES]):
        if columns and _splitting(line, len(columns)) is not None:
            return k
        below = lines[k + 1][1] if k + 1 < len(lines) else ""
        delimiter = _delimiter(line, below)
        names = _fields(line, delimiter)
        if not columns and wanted and set(wanted) <= set(names) and len(names) == len(_fields(below, delimiter)):
            return k
    return 0


def _header(csv_path: pathlib.Path, text: str, wanted: list[str] = (), columns: list[str] | None = None) -> _Header:
    """Read the lines before the data: '#' comments, a preamble (_first_row: where the `wanted` columns are
    named), the header, and a units row if there is one; with `columns` (the sidecar's names of a file without
    a header line), the comments and the preamble only."""
    lines = list(itertools.islice(_content(text), PREAMBLE_LINES + 3))
    if not lines:
        raise MeasurementError(f"{csv_path}: no {'data' if columns else 'header'} line (only comments or empty)")
    k = _first_row(lines, list(wanted), columns)
    (skip, line), rest = lines[k], lines[k + 1:k + 3]
    first = rest[0][1] if rest else ""
    if columns:
        return _unnamed(csv_path, line, skip, columns, lines[k - 1] if k else None)
    delimiter = _delimiter(line, first)
    names = _fields(line, delimiter)
    if all(_numeric(v, delimiter) for v in names):
        raise MeasurementError(f"{csv_path}: row {skip} holds numbers, not column names; allowed: a header line of "
                               "column names above the data, or the sidecar's `columns = [...]` naming the columns "
                               "of a file without one")
    if len(names) == 1 and len(first.split()) > 1 and delimiter not in first:
        raise MeasurementError(f"{csv_path}: row {skip + 1}: {len(first.split())} fields separated by spaces under "
                               f"{len(_fields(line, SPACES))} name(s) in row {skip}; allowed: as many names as fields, "
                               "separated by ',', a tab, ';' or spaces (a name that holds a space quoted)")
    units = {}
    if first.strip() and not any(_numeric(v, delimiter) for v in _fields(first, delimiter)):
        units = dict(zip(names, _fields(first, delimiter)))  # a units row under the header
        skip, first = rest[0][0], rest[1][1] if len(rest) > 1 else ""
    fields = len(_fields(first, delimiter)) if first.strip() else len(names)
    if fields != len(names):
        hint = (" (decimal commas? allowed with ';', a tab or spaces between columns, or '.' as the decimal mark)"
                if fields > len(names) else "")
        raise MeasurementError(f"{csv_path}: row {skip + 1}: {fields} fields but {len(names)} column names{hint}")
    return _Header(names, skip, delimiter, units)


def _splitting(line: str, n: int) -> str | None:
    """The first of ',', a tab, ';' and spaces that splits `line` into `n` numbers (None when none does)."""
    return next((d for d in DELIMITERS + (SPACES,)
                 if len(f := _fields(line, d)) == n and all(_numeric(v, d) for v in f)), None)


def _unnamed(csv_path: pathlib.Path, line: str, row: int, columns: list[str], above=None) -> _Header:
    """The header of a file without a header line whose first data line is `line` (row `row`): the sidecar's
    `columns`, and the delimiter that splits that line into as many numbers (_splitting). The line `above` it
    ((row, line), None when there is none) must not be a header: as many fields, none a number (the columns it
    names could be in another order than the sidecar's)."""
    delimiter = _splitting(line, len(columns))
    if delimiter is None:
        raise MeasurementError(f"{csv_path}: row {row} does not split into {len(columns)} numbers (the sidecar's "
                               f"columns: {', '.join(columns)}); allowed: one number per named column, separated by "
                               "',', a tab, ';' or spaces (a file with a header line: no `columns` in the sidecar)")
    names = _fields(above[1], delimiter) if above else []
    if len(names) == len(columns) and not any(_numeric(v, delimiter) for v in names):
        raise MeasurementError(f"{csv_path}: row {above[0]} names the columns ({', '.join(names)}) but the "
                               f"sidecar's `columns` names them too ({', '.join(columns)}); allowed: one of "
                               "the two (a file with a header line: no `columns` in the sidecar)")
    return _Header(list(columns), row - 1, delimiter, {})


def clock_seconds(field: str) -> float:
    """A wall-clock time stamp as seconds: an ISO 8601 date and time ('2026-05-04 10:15:32.123456', a 'T' or a
    space between) since 1970, or a time of day ('10:15:32.125') since midnight. ValueError otherwise."""
    text = field.strip().strip('"').strip()
    if re.fullmatch(r"\d{4}-\d\d-\d\d[T ]\d\d:\d\d:\d\d(\.\d+)?", text):
        stamp = np.datetime64(text.replace(" ", "T"), "ns")
        return float((stamp - np.datetime64("1970-01-01T00:00:00", "ns")) / np.timedelta64(1, "ns")) * 1e-9
    match = re.fullmatch(r"(\d{1,2}):(\d\d):(\d\d(?:\.\d+)?)", text)
    if not match:
        raise ValueError(f"'{field}' is not a clock time (YYYY-MM-DD hh:mm:ss.fff or hh:mm:ss.fff)")
    return 3600 * int(match.group(1)) + 60 * int(match.group(2)) + float(match.group(3))


def _load_columns(csv_path, text: str, head: _Header, wanted: list[str], clock: str | None = None
                  ) -> dict[str, np.ndarray]:
    """The `wanted` columns as floats; the column `clock` (a time column of wall-clock stamps) as clock_seconds."""
    idx = [head.names.index(w) for w in wanted]
    converters = {head.names.index(clock): clock_seconds} if clock else None
    try:
        with warnings.catch_warnings():  # an empty body is refused below, with the file named
            warnings.simplefilter("ignore", UserWarning)
            data = np.loadtxt(_lines(_decimal_point(text, head.delimiter)),
                              delimiter=None if head.delimiter == SPACES else head.delimiter,
                              skiprows=head.skip, usecols=idx, ndmin=2, comments="#", quotechar='"',
                              converters=converters)
    except ValueError as exc:
        mark = ("'.' as the decimal mark" if head.delimiter == ","
                else "'.' or ',' as the decimal mark, no digit grouping")
        clocks = (f", and clock times (YYYY-MM-DD hh:mm:ss.fff or hh:mm:ss.fff) in '{clock}'" if clock else
                  " (a time column of clock times: time_unit = \"clock\")")
        raise MeasurementError(f"{csv_path}: not numeric in a used column ({', '.join(wanted)}): {exc}; "
                               f"allowed: numbers with {mark}{clocks}") from exc
    if data.shape[0] == 0:
        raise MeasurementError(f"{csv_path}: no data rows after row {head.skip}; allowed: at least two samples")
    return dict(zip(wanted, data.T))


def read_csv_columns(csv_path, wanted: list[str]) -> dict[str, np.ndarray]:
    """The named columns of a lab-style CSV (comment lines, ',', tab or ';', extra columns), as floats."""
    csv_path = pathlib.Path(csv_path)
    text = read_text(csv_path, MeasurementError)
    head = _header(csv_path, text, wanted)
    for w in wanted:
        if w not in head.names:
            raise MeasurementError(f"{csv_path}: no column {w!r}; columns: {', '.join(head.names)}")
    return _load_columns(csv_path, text, head, wanted)


def rate_of(t: np.ndarray) -> float:
    """The sample rate [Hz] of a time column (a sidecar without sample_rate_hz): the least-squares slope of the
    stamps against their index (rounded stamps average out), put on its 6 significant digits (the rate a DAQ is
    set to) when within 1e-7 of them."""
    k = np.arange(len(t), dtype=float)
    with np.errstate(all="ignore"):  # a time column that is not finite or not increasing is refused by check_time
        slope = np.polyfit(k, t, 1)[0] if len(t) > 1 and np.all(np.isfinite(t)) else np.nan
    fs = 1.0 / slope if slope > 0 else 1.0
    nice = float(f"{fs:.6g}")
    return nice if abs(nice / fs - 1) < 1e-7 else fs


def check_time(t: np.ndarray, fs: float, csv_path, side, column: str, first_row: int, stated: bool = True) -> None:
    """A time column [s] must be the uniform grid of fs (the sidecar's, or where not `stated` the column's own:
    rate_of) within MAX_TIME_SLIP samples (rounding allowed)."""
    if len(t) < 2:
        raise MeasurementError(f"{csv_path}: fewer than two samples")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise MeasurementError(f"{csv_path}: row {first_row + bad[0]}: column '{column}' is not finite; allowed: "
                               "finite times in s (or time_unit)")
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = bad[0] + 1
        what = "repeated" if dt[bad[0]] == 0 else "decreasing"
        raise MeasurementError(f"{csv_path}: row {first_row + k}: {column} = {t[k]:.10g} s after {t[k - 1]:.10g} s "
                               f"({what} time); allowed: increasing times 1/sample_rate_hz apart")
    slip = (t - t[0]) * fs - np.arange(len(t))
    bad = np.flatnonzero(np.abs(slip) > MAX_TIME_SLIP)
    if bad.size:
        k = bad[0]
        step = dt[k - 1] * fs
        if step > 1 + 2 * MAX_TIME_SLIP:
            raise MeasurementError(f"{csv_path}: row {first_row + k}: {column} = {t[k]:.10g} s follows "
                                   f"{t[k - 1]:.10g} s: a gap of {step:.3g} samples; allowed: one sample "
                                   f"(1/{fs:g} s) between rows")
        if not stated:
            raise MeasurementError(f"{csv_path}: row {first_row + k}: {column} = {t[k]:.10g} s is {slip[k]:+.2f} "
                                   f"samples off the uniform grid of the column's rate ({fs:.9g} Hz); allowed: "
                                   f"within {MAX_TIME_SLIP} samples")
        rate = (len(t) - 1) / (t[-1] - t[0])
        raise MeasurementError(f"{side}: [sample_rate_hz] = {fs:g} but column '{column}' is sampled at "
                               f"{rate:.9g} Hz (row {first_row + k}, {column} = {t[k]:.10g} s, is "
                               f"{slip[k]:+.2f} samples off the grid; allowed: within {MAX_TIME_SLIP} samples)")


def _text_columns(csv_path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel],
                  text: str | None = None):
    """The used columns of a text file (the time column's first, if the file has it), the time column's name (or
    None) and the rows above the first sample (error messages count rows from there); `text`: the file's content
    when it is not the file's own text (a worksheet's: _excel_columns)."""
    text = read_text(csv_path, MeasurementError) if text is None else text
    head = _header(csv_path, text, list(channels), meta["columns"])
    names, skip = head.names, head.skip
    for name, ch in channels.items():
        if name not in names:
            raise MeasurementError(f"{csv_path}: column '{name}' named in {side.name} is missing; "
                                   f"columns: {', '.join(names)}")
        written = unit_key(head.units.get(name, ""))
        if written in TO_SI and written != ch.unit:
            raise MeasurementError(f"{csv_path}: row {skip}: the units row gives '{head.units[name]}' for column "
                                   f"'{name}' but {side.name} says '{ch.unit}'; allowed: the same unit in both")
    time_col = meta["time_column"] if meta["time_column"] in names else None
    written = unit_key(head.units.get(time_col, ""))
    if written in TIME_UNITS and written != meta["time_unit"]:
        raise MeasurementError(f"{csv_path}: row {skip}: the units row gives '{head.units[time_col]}' for the time "
                               f"column '{time_col}' but {side.name} says time_unit = '{meta['time_unit']}'; "
                               "allowed: the same unit in both")
    clock = time_col if meta["time_unit"] == CLOCK else None
    return (_load_columns(csv_path, text, head, ([time_col] if time_col else []) + list(channels), clock), time_col,
            skip)


EXCEL_ALLOWED = ("an Excel workbook (.xlsx or .xlsm) whose sheet (the sidecar's `sheet`, else the first) holds the "
                 "used columns under a header row naming them")
EXCEL_SUFFIXES = (".xlsx", ".xlsm")


def _excel_columns(path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel]):
    """The used columns of a worksheet (pyfit.io.excel: read as the text of the sheet's CSV export, rows
    numbered as the spreadsheet numbers them), as _text_columns gives a text file's."""
    text = _opened(path, side, meta, lambda p: sheet_text(p, meta["sheet"]), ExcelFileError, "an Excel workbook",
                   EXCEL_ALLOWED, clock=True)
    return _text_columns(path, side, meta, channels, text)


MAT_ALLOWED = ("a MATLAB file (v4, v6, v7 or v7.3) holding the columns as vectors of one length, as fields of a "
               "struct ('s.x'), or as the columns of one matrix the sidecar's `columns` names")


def _opened(path: pathlib.Path, side: pathlib.Path, meta: dict, read, error: type, kind: str, allowed: str,
            clock: bool = False):
    """A binary measurement file's content as `read` gives it (its `error` refused as not `kind`, e.g. 'a MATLAB
    file'); a sidecar asking for clock stamps refused unless the format holds them (`clock`: a workbook's
    date-time cells)."""
    if meta["time_unit"] == CLOCK and not clock:
        fail(side, "time_unit", f"'{CLOCK}' for {path.name}: clock stamps are text", f"s or ms for {kind}'s time",
             MeasurementError)
    try:
        return read(path)
    except error as exc:
        raise MeasurementError(f"{path}: not readable as {kind} ({exc}); allowed: {allowed}") from exc


def _mat_columns(path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel]):
    """The used columns of a MATLAB file (pyfit.io.matlab), as _text_columns gives a text file's: vectors by
    their names, a struct's fields as 'struct.field', or the columns (or rows) of the one matrix whose size
    matches the sidecar's `columns`, by those names."""
    arrays = _opened(path, side, meta, mat_variables, MatlabFileError, "a MATLAB file", MAT_ALLOWED)
    if meta["columns"] is not None:
        k = len(meta["columns"])
        matrices = [n for n, a in arrays.items() if a.ndim == 2 and k in a.shape]
        if len(matrices) != 1:
            fail(side, "columns", f"{k} names, and {path.name} holds {len(matrices)} matrices with {k} columns or "
                 f"rows ({', '.join(matrices) or 'none'})", MAT_ALLOWED, MeasurementError)
        m = arrays[matrices[0]]
        vectors = dict(zip(meta["columns"], (m if m.shape[1] == k else m.T).T))
    else:
        vectors = {n: a for n, a in arrays.items() if a.ndim == 1}
    return _used_vectors(path, side, meta, channels, vectors, ("variable", "vectors"), MAT_ALLOWED)


def _used_vectors(path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel],
                  vectors: dict[str, np.ndarray], nouns: tuple[str, str], allowed: str):
    """The time vector (when the file holds meta's time_column) and the used channels of a binary file's
    vectors, each at least two samples and all of one length, as _text_columns gives a text file's columns;
    `nouns`: what the file calls one and what the vectors are listed as in a refusal."""
    noun, listed = nouns
    time_col = meta["time_column"] if meta["time_column"] in vectors else None
    used = ([time_col] if time_col else []) + list(channels)
    for name in used:
        if name not in vectors:
            raise MeasurementError(f"{path}: {noun} '{name}' named in {side.name} is missing; {listed}: "
                                   f"{', '.join(vectors) or 'none'}; allowed: {allowed}")
    lengths = {name: len(vectors[name]) for name in used}
    if len(set(lengths.values())) > 1 or min(lengths.values()) < 2:
        raise MeasurementError(f"{path}: the used {noun}s differ in length or hold fewer than two samples "
                               f"({', '.join(f'{n}: {k}' for n, k in lengths.items())}); allowed: {allowed}")
    return {name: np.array(vectors[name], float) for name in used}, time_col, 0


TDMS_ALLOWED = ("a TDMS file whose used channels (named 'group/channel', or by the channel's name where no other "
                "group holds one of that name) are numeric, of one length and, as waveforms, of one wf_increment")
UFF_ALLOWED = ("a universal file whose used channels are time records of dataset 58 (real, evenly spaced), named "
               "'#k' (the k-th record), by id1 or as 'node:direction' ('101:+Z') where no other record holds the name,"
               " of one length and one abscissa increment")
WAVEFORM_TIME = "(waveform timing)"  # the name of the time a file's waveform timing gives, in messages


def _waveform_columns(path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel],
                      read, error: type, kind: str, allowed: str):
    """The used channels of a file whose channels carry their own timing (pyfit.io.waveform: NI TDMS, universal
    file dataset 58), as _text_columns gives a text file's columns: a channel's unit, where the file names a
    known one, must be the sidecar's; without a time channel the time is the waveforms' own (offset + k
    increment), which a stated sample_rate_hz must agree with."""
    named = _opened(path, side, meta, read, error, kind, allowed)
    found = named.channels
    for name in channels:
        if name in named.ambiguous:
            raise MeasurementError(f"{path}: channel '{name}' named in {side.name} names several channels "
                                   f"({', '.join(named.ambiguous[name])}); allowed: one of those names")
    cols, time_col, skip = _used_vectors(path, side, meta, channels, {n: c.data for n, c in found.items()},
                                         ("channel", "channels"), allowed)
    for name, ch in channels.items():
        written = unit_key(found[name].unit)
        if written in TO_SI and written != ch.unit:
            raise MeasurementError(f"{path}: channel '{name}' has the unit '{found[name].unit}' but {side.name} "
                                   f"says '{ch.unit}'; allowed: the same unit in both")
    if time_col is None:
        timing = {n: (found[n].increment_s, found[n].offset_s) for n in channels}
        if len(set(timing.values())) > 1:
            listed = ", ".join(f"{n}: {dt} s, {t0:g} s" for n, (dt, t0) in timing.items())
            raise MeasurementError(f"{path}: the used channels' timings differ (increment, start: {listed}); "
                                   f"allowed: {allowed}")
        increment, offset = next(iter(timing.values()))
        if increment is not None:  # in the sidecar's time unit, as a time channel is
            n = len(next(iter(cols.values())))
            cols = {WAVEFORM_TIME: (offset + np.arange(n) * increment) / TIME_UNITS[meta["time_unit"]], **cols}
            time_col = WAVEFORM_TIME
    return cols, time_col, skip


def _tdms_columns(path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel]):
    """The used channels of an NI TDMS file (pyfit.io.tdms): _waveform_columns."""
    return _waveform_columns(path, side, meta, channels, tdms_channels, TdmsFileError, "a TDMS file", TDMS_ALLOWED)


def _uff_columns(path: pathlib.Path, side: pathlib.Path, meta: dict, channels: dict[str, Channel]):
    """The used time records of a universal file (pyfit.io.uff): _waveform_columns."""
    return _waveform_columns(path, side, meta, channels, uff_channels, UffFileError, "a universal (UFF 58) file",
                             UFF_ALLOWED)


def read_measurement(csv_path: str | pathlib.Path) -> Measurement:
    """Read one measurement file (text, or MATLAB's .mat) and its TOML sidecar (the same stem); validate and
    convert to SI."""
    csv_path = pathlib.Path(csv_path)
    side = csv_path.with_suffix(".toml")
    if not csv_path.is_file():
        raise MeasurementError(f"{csv_path}: file not found")
    meta = check_table(read_toml(side, MeasurementError), side, "", SIDECAR, MeasurementError)
    columns = meta["columns"]
    if columns is not None and (not columns or len(set(columns)) < len(columns)):
        fail(side, "columns", f"{columns} names no column or one twice", "the names of the file's columns, each "
             "once, in order", MeasurementError)
    fs = meta["sample_rate_hz"]
    if fs is not None and not fs > 0:
        fail(side, "sample_rate_hz", f"{fs} is not > 0", error=MeasurementError)
    meta["time_unit"] = unit_key(meta["time_unit"])  # 'sec', 'msec' as DAQ exports write them
    if meta["time_unit"] not in (*TIME_UNITS, CLOCK):
        fail(side, "time_unit", f"'{meta['time_unit']}' unknown", ", ".join((*TIME_UNITS, CLOCK)), MeasurementError)
    if meta["sheet"] is not None and csv_path.suffix.lower() not in EXCEL_SUFFIXES:
        fail(side, "sheet", f"'{meta['sheet']}' for {csv_path.name}", "a sheet of an Excel workbook (.xlsx or "
             ".xlsm) only", MeasurementError)
    inputs = _channels(side, meta["inputs"], "inputs")
    outputs = _channels(side, meta["outputs"], "outputs")
    read = {".mat": _mat_columns, ".tdms": _tdms_columns, ".uff": _uff_columns, ".unv": _uff_columns,
            **dict.fromkeys(EXCEL_SUFFIXES, _excel_columns)}.get(csv_path.suffix.lower(), _text_columns)
    cols, time_col, skip = read(csv_path, side, meta, {**inputs, **outputs})
    n = len(next(iter(cols.values())))
    if fs is None and not time_col:
        fail(side, "sample_rate_hz", f"missing, and {csv_path.name} has no time column '{meta['time_column']}' to "
             "take the rate from", "the rate in Hz, or time_column naming the file's time column", MeasurementError)
    if time_col:
        t_file = cols.pop(time_col)
        t_file = t_file - t_file[0] if meta["time_unit"] == CLOCK else t_file * TIME_UNITS[meta["time_unit"]]
        stated = fs is not None
        fs = fs if stated else rate_of(t_file)
        check_time(t_file, fs, csv_path, side, time_col, skip + 1, stated)
        t0 = float(np.mean(t_file - np.arange(n) / fs))  # the grid that fits the rounded stamps best
    else:
        t0 = 0.0
    values = {}
    for name, ch in {**inputs, **outputs}.items():
        v = cols[name]
        bad = np.flatnonzero(~np.isfinite(v))
        if bad.size:
            raise MeasurementError(f"{csv_path}: row {skip + 1 + bad[0]}: column '{name}' is not finite "
                                   f"({bad.size} such value(s)); allowed: finite numbers")
        with np.errstate(over="ignore"):
            values[name] = v * ch.to_si
        bad = np.flatnonzero(~(np.abs(values[name]) <= MAX_ABS_SI))
        if bad.size:
            raise MeasurementError(f"{csv_path}: row {skip + 1 + bad[0]}: column '{name}' = {v[bad[0]]:.6g} "
                                   f"{ch.unit}, beyond {MAX_ABS_SI:.0e} in SI units; allowed: magnitudes up to "
                                   f"{MAX_ABS_SI:.0e} (so that squares, sums and derivatives stay finite)")
    t = t0 + np.arange(n) / fs
    segments = [check_table(seg, side, f"segments[{i}]", SEGMENT, MeasurementError)
                for i, seg in enumerate(meta["segments"])]
    _check_segments(segments, t, side)
    return Measurement(csv_path, meta["model"], t, inputs, outputs, values, meta["level"], meta["level_value"],
                       dict(meta["excitation"]), meta["notes"], segments=segments)


def _check_segments(segments: list[dict], t: np.ndarray, side) -> None:
    """Each segment [from_s, to_s) within the record and two samples long at least, none overlapping another
    (a sample in two segments could calibrate a model and judge it)."""
    for i, seg in enumerate(segments):
        k = int(np.sum((t >= seg["from_s"]) & (t < seg["to_s"])))
        if not seg["from_s"] < seg["to_s"] or k < 2:
            fail(side, f"segments[{i}]", f"from_s = {seg['from_s']:g} s to to_s = {seg['to_s']:g} s holds {k} "
                 f"samples", f"from_s < to_s, at least two samples within the record's {t[0]:g}-{t[-1]:g} s",
                 MeasurementError)
    spans = sorted((seg["from_s"], seg["to_s"], i) for i, seg in enumerate(segments))
    for (a0, a1, i), (b0, b1, j) in zip(spans, spans[1:]):
        if b0 < a1:
            fail(side, f"segments[{j}]", f"from_s = {b0:g} s lies inside segments[{i}] ({a0:g}-{a1:g} s)",
                 "segments that do not overlap", MeasurementError)


def split_segments(m: Measurement) -> list[Measurement]:
    """A measurement as its sidecar's [[segments]] cut it (one file holding several levels or runs): each
    segment's samples from_s <= t < to_s, its level and level_value, its excitation over the file's; the
    measurement itself when the sidecar names no segments."""
    if not m.segments:
        return [m]
    out = []
    for k, seg in enumerate(m.segments, start=1):
        idx = (m.t >= seg["from_s"]) & (m.t < seg["to_s"])
        out.append(replace(m, t=m.t[idx], values={c: v[idx] for c, v in m.values.items()},
                           level=seg["level"] or m.level, level_value=seg["level_value"],
                           excitation={**m.excitation, **seg["excitation"]}, segment=str(k), segments=[]))
    return out


def _toml_value(v) -> str:
    """A value as TOML: quoted string, true/false, number (Python's or numpy's), or an array of these."""
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(float(v)) if isinstance(v, (float, np.floating)) else f"{int(v)}"


def write_measurement(csv_path: str | pathlib.Path, model: str, t: np.ndarray, inputs: dict[str, tuple],
                      outputs: dict[str, tuple], level: str = "", level_value: float | None = None,
                      excitation: dict | None = None, notes: str = "") -> pathlib.Path:
    """Write a CSV + TOML pair. inputs/outputs: column -> (samples in SI, unit, model_variable)."""
    csv_path = pathlib.Path(csv_path)
    csv_path.parent.mkdir(parents=True, exist_ok=True)
    fs = (len(t) - 1) / (t[-1] - t[0])
    cols = {**inputs, **outputs}
    data = np.column_stack([t] + [np.asarray(v[0]) / TO_SI[unit_key(v[1])] for v in cols.values()])
    np.savetxt(csv_path, data, delimiter=",", header=",".join(["t"] + list(cols)), comments="",
               fmt=["%.12g"] + ["%.10g"] * len(cols))

    def table(name, d):
        lines = [f"[{name}]"]
        for c, (_, unit, var) in d.items():
            lines.append(f'{c} = {{ unit = "{unit}", model_variable = "{var}" }}')
        return lines

    lines = [f'model = "{model}"', f"sample_rate_hz = {fs:.12g}"]
    if level:
        lines.append(f'level = "{level}"')
    if level_value is not None:
        lines.append(f"level_value = {level_value:.12g}")
    if notes:
        lines.append(f'notes = "{notes}"')
    if inputs:
        lines += table("inputs", inputs)
    lines += table("outputs", outputs)
    if excitation:
        lines.append("[excitation]")
        for k, v in excitation.items():
            lines.append(f"{k} = {_toml_value(v)}")
    csv_path.with_suffix(".toml").write_text("\n".join(lines) + "\n")
    return csv_path


LEVEL_KEYS = ("amplitude", "rms", "v0", "level")  # excitation keys that state a level, in this order


def level_order(items: list[Measurement]) -> tuple[list[Measurement], str]:
    """Measurements ordered by excitation level, and what the order rests on: 'level_value' (all sidecars
    give it), else the sidecars' excitation amplitude (the first of LEVEL_KEYS that all give), else the
    RMS of the first input (or, without inputs, of the first output)."""
    if all(m.level_value is not None for m in items):
        return sorted(items, key=lambda m: (m.level_value, m.name)), "level_value"
    for key in LEVEL_KEYS:
        vals = [m.excitation.get(key) for m in items]
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
            for m, v in zip(items, vals):
                m.level_value = float(v)
            return sorted(items, key=lambda m: (m.level_value, m.name)), f"excitation.{key}"
    for m in items:
        ch = next(iter(m.inputs or m.outputs))
        m.level_value = float(np.sqrt(np.mean(m.values[ch] ** 2)))
    return sorted(items, key=lambda m: (m.level_value, m.name)), "input RMS"


def read_dataset(folder: str | pathlib.Path) -> list[Measurement]:
    """All measurements (CSV + TOML pairs) in a folder, ordered by level (see level_order)."""
    return read_dataset_with_order(folder)[0]


def check_quantities(m: Measurement, model_units: dict[str, str], voltages: bool) -> list[str]:
    """Check that each channel's unit measures its model variable's quantity (model_units: variable -> the
    model's unit, e.g. 'N' from the FMU), or, where `voltages`, is a voltage proportional to it (read in the
    model's unit, its gain unknown: every parameter the model fits then carries that gain); returns the voltage
    channels as 'column (model_variable)'. Raises MeasurementError naming the sidecar's field and the units
    allowed."""
    side = m.path.with_suffix(".toml")
    volts = []
    for section, channels in (("inputs", m.inputs), ("outputs", m.outputs)):
        for col, ch in channels.items():
            unit = unit_key(model_units.get(ch.model_variable, ""))
            want, got = QUANTITY.get(unit), QUANTITY[ch.quantity_unit]
            if got == "voltage" and voltages:
                volts.append(f"{col} ({ch.model_variable})")
            if want is None or got == want or (voltages and got == "voltage"):
                continue
            allowed = [u for u, q in QUANTITY.items() if q == want or (voltages and q == "voltage")]
            why = (" (a voltage stands for it only where every model parameter is fitted: give the sensor's "
                   "sensitivity, e.g. sensitivity = \"100 mV/g\")" if got == "voltage" else "")
            fail(side, f"{section}.{col}.unit", f"'{ch.quantity_unit}' measures {got}; model_variable "
                 f"'{ch.model_variable}' is {want} ({unit}){why}", ", ".join(allowed), MeasurementError)
    return volts


# a measurement file's extensions, in any case
DATA_SUFFIXES = (".csv", ".txt", ".dat", ".tsv", ".asc", ".mat", ".tdms", ".uff", ".unv", *EXCEL_SUFFIXES)


def measurement_files(folder: str | pathlib.Path) -> list[pathlib.Path]:
    """The measurement files of a dataset folder: each file ending in one of DATA_SUFFIXES (any case: a DAQ's
    LEVEL1.CSV) beside a TOML sidecar of its stem. A CSV without a sidecar is refused; another text file
    without one (a README.txt) is not a measurement. Two files sharing one sidecar are refused."""
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        raise MeasurementError(f"{folder}: dataset folder not found")
    found = []
    for p in sorted(folder.iterdir()):
        if _is_measurement(p):
            found.append(p)
        elif p.is_file() and p.suffix.lower() == ".csv":
            raise MeasurementError(f"{p}: no sidecar {p.stem}.toml")
    for a, b in zip(found, found[1:]):
        if a.stem == b.stem:
            raise MeasurementError(f"{folder}: {a.name} and {b.name} share the sidecar {a.stem}.toml; allowed: one "
                                   "measurement file per sidecar")
    return found


def _is_measurement(p: pathlib.Path) -> bool:
    """A file ending in one of DATA_SUFFIXES (any case) beside a TOML sidecar of its stem."""
    return p.is_file() and p.suffix.lower() in DATA_SUFFIXES and p.with_suffix(".toml").is_file()


def holds_measurements(folder: pathlib.Path) -> bool:
    """Whether a folder holds a measurement file beside its sidecar (as measurement_files finds them)."""
    return any(_is_measurement(p) for p in folder.iterdir())


def read_dataset_with_order(folder: str | pathlib.Path) -> tuple[list[Measurement], str]:
    """All measurements in a folder (measurement_files; a file with [[segments]] as one per segment), ordered by
    level, and what the order rests on."""
    items = [part for p in measurement_files(folder) for part in split_segments(read_measurement(p))]
    if not items:
        raise MeasurementError(f"{folder}: no measurement found (a file ending in "
                               f"{', '.join(DATA_SUFFIXES)} beside a TOML sidecar of its stem)")
    return level_order(items)


__all__ = ["Channel", "DATA_SUFFIXES", "Measurement", "MeasurementError", "QUANTITY", "TO_SI", "check_quantities",
           "holds_measurements", "level_order", "measurement_files", "read_dataset", "read_dataset_with_order",
           "read_measurement", "split_segments", "unit_key", "write_measurement"]
