"""Property-based tests of the measurement reader: a lab file, re-encoded (encoding, line ends, column delimiter,
decimal mark) or damaged at random, is either read to the same numbers or refused with a MeasurementError that
names the file, never another exception."""
import codecs
import datetime
import pathlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pyfit.io.data import MeasurementError, clock_seconds, read_measurement

FS = 500.0
N = 40
SIDECAR = "\n".join([
    'model = "SDOFBoucWen"', f"sample_rate_hz = {FS}", "[inputs]", 'F_kN = { unit = "kN", model_variable = "u" }',
    "[outputs]", 'x_mm = { unit = "mm", model_variable = "y" }']) + "\n"


def lab_text() -> str:
    """A small export as a bench writes it: comments, quoted names, a units row, a text column."""
    t = np.arange(N) / FS
    rows = [f"{t[k]:.6g},{2.0 * np.sin(2 * np.pi * 13 * t[k]):.8f},{3.0 * np.cos(2 * np.pi * 13 * t[k]):.8f},OK"
            for k in range(N)]
    return "\n".join(["# exported by the bench software", '"t","x_mm","F_kN","status"', "s,mm,kN,-", *rows]) + "\n"


def expected() -> dict[str, np.ndarray]:
    t = np.arange(N) / FS
    return {"x_mm": 2e-3 * np.sin(2 * np.pi * 13 * t), "F_kN": 3e3 * np.cos(2 * np.pi * 13 * t)}


def write_pair(folder: pathlib.Path, data: bytes) -> pathlib.Path:
    path = folder / "run.csv"
    path.write_bytes(data)
    path.with_suffix(".toml").write_text(SIDECAR, encoding="utf-8")
    return path


# byte-order marks and encodings as Windows DAQ programs and spreadsheets write them
ENCODINGS = [("utf-8", b""), ("utf-8", codecs.BOM_UTF8), ("utf-16-le", codecs.BOM_UTF16_LE),
             ("utf-16-be", codecs.BOM_UTF16_BE), ("utf-32-le", codecs.BOM_UTF32_LE)]


# column delimiter and decimal mark as exports write them (a decimal comma only where a comma separates no columns;
# columns aligned by one space or several)
STYLES = [(",", "."), ("\t", "."), (";", ","), ("\t", ","), (";", "."), (" ", "."), ("   ", ",")]


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(encoding=st.sampled_from(ENCODINGS), newline=st.sampled_from(["\n", "\r\n", "\r"]),
       trailing=st.sampled_from(["", "delimiter", " "]), style=st.sampled_from(STYLES))
def test_re_encoded_files_read_to_the_same_numbers(tmp_path, encoding, newline, trailing, style):
    name, bom = encoding
    sep, decimal = style
    lines = [line if line.startswith("#") else sep.join(f.replace(".", decimal) for f in line.split(","))
             for line in lab_text().splitlines()]
    end = sep if trailing == "delimiter" else trailing
    text = newline.join(line + (end if k > 0 else "") for k, line in enumerate(lines)) + newline
    m = read_measurement(write_pair(tmp_path, bom + text.encode(name)))
    for column, values in expected().items():
        # 8 decimals written: the rounding is at most 5e-9 of the written unit
        np.testing.assert_allclose(m.values[column], values, rtol=0, atol=5e-9 * (1e-3 if column == "x_mm" else 1e3))


MUTATIONS = st.one_of(
    st.tuples(st.just("flip"), st.integers(0, 10_000), st.integers(0, 255)),
    st.tuples(st.just("insert"), st.integers(0, 10_000), st.binary(min_size=1, max_size=8)),
    st.tuples(st.just("delete"), st.integers(0, 10_000), st.integers(1, 40)),
    st.tuples(st.just("truncate"), st.integers(0, 10_000), st.just(0)),
    st.tuples(st.just("field"), st.integers(0, 10_000), st.sampled_from(
        ["1e308", "-1e308", "nan", "inf", "", "1,5", "0x1A", "--", "1e-400", "9" * 400, '"', "\x00"])),
)


def mutate(data: bytes, mutation) -> bytes:
    kind, at, arg = mutation
    at = at % (len(data) + 1)
    if kind == "flip":
        return data[:at] + bytes([arg]) + data[at + 1:]
    if kind == "insert":
        return data[:at] + arg + data[at:]
    if kind == "delete":
        return data[:at] + data[at + arg:]
    if kind == "truncate":
        return data[:at]
    text = data.decode("utf-8", errors="replace")  # replace the numeric field that contains byte `at`
    start = text.rfind(",", 0, at) + 1
    end = min([i for i in (text.find(",", at), text.find("\n", at)) if i >= 0] or [len(text)])
    return (text[:start] + arg + text[end:]).encode("utf-8")


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(encoding=st.sampled_from(ENCODINGS), mutations=st.lists(MUTATIONS, min_size=1, max_size=3))
def test_damaged_files_are_read_or_refused_naming_the_file(tmp_path, encoding, mutations):
    name, bom = encoding
    data = lab_text().encode("utf-8")
    for mutation in mutations:
        data = mutate(data, mutation)
    try:
        payload = bom + data.decode("utf-8").encode(name)
    except UnicodeDecodeError:
        payload = bom + data  # bytes that are no UTF-8 stay as they are, behind the mark
    path = write_pair(tmp_path, payload)
    try:
        m = read_measurement(path)
    except MeasurementError as exc:
        assert str(path) in str(exc) or str(path.with_suffix(".toml")) in str(exc)
        return
    for v in m.values.values():  # what is read is finite, SI and on the sidecar's grid
        assert np.all(np.isfinite(v)) and len(v) == len(m.t)
    assert np.allclose(np.diff(m.t), 1 / FS)


@pytest.mark.parametrize("payload, says", [
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR", "binary file"),
    (b"t,x_mm,F_kN\n0,1,\xff\xfe2\n", "not UTF-8 text"),
    (codecs.BOM_UTF16_LE + b"\x00\xd8t\x00", "not utf-16 text"),
])
def test_binary_and_undecodable_files_name_the_file(tmp_path, payload, says):
    path = write_pair(tmp_path, payload)
    with pytest.raises(MeasurementError, match=says) as info:
        read_measurement(path)
    assert str(path) in str(info.value)


def test_a_value_that_would_overflow_is_refused_with_its_row(tmp_path):
    lines = lab_text().splitlines()  # a comment, the header and the units row: the sample at t = 0.004 s is row 6
    lines[5] = "0.004,1e308," + lines[5].split(",", 2)[2]
    path = write_pair(tmp_path, ("\n".join(lines) + "\n").encode())
    with pytest.raises(MeasurementError, match=r"row 6: column 'x_mm' = 1e\+308 mm, beyond 1e\+100") as info:
        read_measurement(path)
    assert str(path) in str(info.value)


def test_a_utf16_sidecar_is_read(tmp_path):
    path = write_pair(tmp_path, lab_text().encode())
    path.with_suffix(".toml").write_bytes(codecs.BOM_UTF16_LE + SIDECAR.encode("utf-16-le"))
    assert read_measurement(path).sample_rate_hz == FS


@settings(max_examples=300, deadline=None)
@given(st.datetimes(min_value=datetime.datetime(1990, 1, 1), max_value=datetime.datetime(2100, 1, 1)), st.booleans())
def test_a_clock_stamp_reads_to_the_seconds_python_s_datetime_counts(stamp, with_t):
    """clock_seconds against the standard library's own arithmetic: an ISO date-time's seconds since 1970 (to
    the 1e-6 s its float keeps over 2e9 s), a time of day's seconds since midnight (exact to the microsecond)."""
    text = stamp.strftime(f"%Y-%m-%d{'T' if with_t else ' '}%H:%M:%S.%f")
    since_1970 = (stamp - datetime.datetime(1970, 1, 1)).total_seconds()
    assert clock_seconds(text) == pytest.approx(since_1970, abs=1e-6)
    of_day = stamp.hour * 3600 + stamp.minute * 60 + stamp.second + stamp.microsecond * 1e-6
    assert clock_seconds(stamp.strftime("%H:%M:%S.%f")) == pytest.approx(of_day, abs=1e-9)
