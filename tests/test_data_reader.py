"""The measurement reader on files written the way lab software writes them (not by our writer)."""
import pathlib

import numpy as np
import pytest

from pyfit.io.data import (MeasurementError, check_quantities, holds_measurements, read_dataset_with_order,
                           read_measurement)

FS = 750.0
N = 26251  # 35 s at 750 Hz: t = 35 s written with 6 significant digits is off by up to 5e-5 s = 0.04 sample


def lab_file(tmp_path, name="run", time_fmt="%.6g", time=True, comments=("# bench: shaker 2", "# operator: X"),
             extra=True, sep=",", decimal=".", t=None, sidecar_extra="", level=None, f=13.0, amp=2.0):
    """A CSV as a test bench exports it: comment lines, quoted names, a text column, displacement in mm."""
    t = np.arange(N) / FS if t is None else t
    x = amp * np.sin(2 * np.pi * f * t)  # mm
    force = 3.0 * np.cos(2 * np.pi * f * t)  # kN
    names = (['"t"'] if time else []) + ['"x_mm"', '"F_kN"'] + (['"status"', '"T_room"'] if extra else [])
    rows = []
    for k in range(len(t)):
        fields = ([time_fmt % t[k]] if time else []) + [f"{x[k]:.8f}", f"{force[k]:.8f}"]
        if extra:
            fields += ["OK", "21.5"]
        rows.append(sep.join(v.replace(".", decimal) for v in fields))
    path = tmp_path / f"{name}.csv"
    path.write_text("\n".join(list(comments) + [sep.join(names)] + rows) + "\n")
    side = [
        'model = "SDOFBoucWen"', f"sample_rate_hz = {FS}", *([f"level_value = {level}"] if level is not None else []),
        sidecar_extra,
        "[inputs]", 'F_kN = { unit = "kN", model_variable = "u" }',
        "[outputs]", 'x_mm = { unit = "mm", model_variable = "y" }']
    path.with_suffix(".toml").write_text("\n".join(side) + "\n")
    return path


def test_rounded_time_comments_and_extra_columns_are_read(tmp_path):
    m = read_measurement(lab_file(tmp_path))
    t = np.arange(N) / FS
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-12)
    assert np.max(np.abs(m.t - t)) < 1e-9  # the exact grid, not the 6-digit stamps (off by up to 5e-5 s)
    assert np.max(np.abs(m.values["x_mm"] - 2e-3 * np.sin(2 * np.pi * 13 * t))) < 1e-10  # mm -> m
    assert np.max(np.abs(m.values["F_kN"] - 3e3 * np.cos(2 * np.pi * 13 * t))) < 1e-4  # kN -> N
    assert set(m.values) == {"x_mm", "F_kN"}  # the text column and the temperature are never parsed


def test_tab_separated_export_is_read(tmp_path):
    m = read_measurement(lab_file(tmp_path, sep="\t"))
    t = np.arange(N) / FS
    assert np.max(np.abs(m.values["x_mm"] - 2e-3 * np.sin(2 * np.pi * 13 * t))) < 1e-10


def test_absent_time_column_uses_the_sidecar_rate(tmp_path):
    m = read_measurement(lab_file(tmp_path, time=False))
    assert m.t[0] == 0.0 and m.t[-1] == pytest.approx((N - 1) / FS, rel=1e-14)


@pytest.mark.parametrize("time_unit", ["ms", "msec"])
def test_time_in_ms_with_offset_start(tmp_path, time_unit):
    t = 12.5 + np.arange(N) / FS  # a segment cut from a long record, stamped in ms with 7 digits
    m = read_measurement(lab_file(tmp_path, time_fmt="%.7g", t=t * 1e3, sidecar_extra=f'time_unit = "{time_unit}"'))
    assert m.t[0] == pytest.approx(12.5, abs=1e-6)
    assert np.max(np.abs(np.diff(m.t) - 1 / FS)) < 1e-12


@pytest.mark.parametrize("case, row, words", [
    ("gap", 1000 + 4, "gap of 2 samples"),
    ("repeated", 500 + 4, "repeated time"),
    ("decreasing", 700 + 4, "decreasing time"),
])
def test_time_errors_name_the_row(tmp_path, case, row, words):
    t = np.arange(N) / FS
    if case == "gap":
        t[1000:] += 1 / FS
    elif case == "repeated":
        t[500] = t[499]
    else:
        t[700] = t[699] - 1e-3
    with pytest.raises(MeasurementError) as err:
        read_measurement(lab_file(tmp_path, time_fmt="%.10g", t=t))
    msg = str(err.value)
    assert f"row {row}" in msg and words in msg and "run.csv" in msg


def test_rate_disagreeing_with_sidecar_by_a_fraction_of_a_sample_is_refused(tmp_path):
    t = np.arange(N) / (FS * (1 + 2e-5))  # 0.5 sample off after 35 s
    with pytest.raises(MeasurementError, match=r"run.toml: \[sample_rate_hz\] = 750 but column 't' is sampled at 750.01"):
        read_measurement(lab_file(tmp_path, time_fmt="%.10g", t=t))


def test_rate_within_rounding_is_accepted(tmp_path):
    t = np.arange(N) / (FS * (1 + 5e-6))  # 0.13 sample after 35 s: a clock within tolerance
    m = read_measurement(lab_file(tmp_path, time_fmt="%.10g", t=t))
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-12)


def _without_rate(path: pathlib.Path) -> pathlib.Path:
    side = path.with_suffix(".toml")
    side.write_text("\n".join(line for line in side.read_text().split("\n") if "sample_rate_hz" not in line))
    return path


@pytest.mark.parametrize("rate, time_fmt", [(FS, "%.6g"), (2560.0, "%.6g"), (1000.0 / 3.0, "%.9g")])
def test_a_sidecar_without_a_rate_takes_the_time_column_s(tmp_path, rate, time_fmt):
    """Stamps rounded to 6 significant digits (up to 5e-5 s off over 35 s) give the DAQ's rate to 1e-7, put on its
    6 digits; a rate with no short decimal form (1000/3 Hz) is kept as the stamps give it."""
    t = np.arange(N) / rate
    m = read_measurement(_without_rate(lab_file(tmp_path, time_fmt=time_fmt, t=t)))
    assert m.sample_rate_hz == pytest.approx(rate, rel=1e-7)
    if rate != 1000.0 / 3.0:
        assert 1.0 / (m.t[1] - m.t[0]) == pytest.approx(rate, rel=1e-12)  # snapped: the rate the DAQ was set to
    assert np.max(np.abs(m.t - t)) < 0.25 / rate


def test_a_sidecar_without_a_rate_needs_a_time_column_and_a_uniform_one(tmp_path):
    with pytest.raises(MeasurementError, match=r"run.toml: \[sample_rate_hz\] missing, and run.csv has no time "
                                               r"column 't' to take the rate from; allowed: the rate in Hz"):
        read_measurement(_without_rate(lab_file(tmp_path, time=False)))
    t = np.arange(N) / FS
    t[N // 2:] += 0.4 / FS  # a clock that slips by 0.4 samples half way
    with pytest.raises(MeasurementError, match=r"run.csv: row \d+: t = .* samples off the uniform grid of the "
                                               r"column's rate \(7\d\d\.\d+ Hz\)"):
        read_measurement(_without_rate(lab_file(tmp_path, time_fmt="%.10g", t=t)))


@pytest.mark.parametrize("sep", [";", "\t"])
def test_decimal_commas_between_semicolons_or_tabs_read_to_the_same_numbers(tmp_path, sep):
    """A spreadsheet's export in a locale that writes decimal commas: ';' or a tab between the columns, so a
    comma in a field can only be the decimal mark. The file is read to the numbers its '.' twin holds."""
    twin = read_measurement(lab_file(tmp_path, "point", time_fmt="%.10g"))
    m = read_measurement(lab_file(tmp_path, "comma", sep=sep, decimal=",", time_fmt="%.10g"))
    for name, v in twin.values.items():
        np.testing.assert_array_equal(m.values[name], v)
    np.testing.assert_array_equal(m.t, twin.t)


def test_a_units_row_above_decimal_commas_is_skipped(tmp_path):
    path = lab_file(tmp_path, sep=";", decimal=",", extra=False, time_fmt="%.10g")
    lines = path.read_text().splitlines()
    lines.insert(3, "s;mm;kN")  # under the header (two comment lines before it)
    path.write_text("\n".join(lines) + "\n")
    m = read_measurement(path)
    assert np.max(np.abs(m.values["x_mm"] - 2e-3 * np.sin(2 * np.pi * 13 * np.arange(N) / FS))) < 1e-10


def test_what_a_decimal_comma_makes_ambiguous_is_refused_naming_the_fix(tmp_path):
    # decimal commas between ',' separators: a field per digit group, more fields than names
    with pytest.raises(MeasurementError, match=r"row 4: 9 fields but 5 column names \(decimal commas\? allowed "
                                               r"with ';', a tab or spaces between columns"):
        read_measurement(lab_file(tmp_path, decimal=",", extra=True, time_fmt="%.6f"))
    # digit grouping beside a decimal comma (1.234,5): refused, not read as 1.2345 or 1234.5
    path = lab_file(tmp_path, sep=";", decimal=",", extra=False, time_fmt="%.10g", amp=2000.0)
    lines = path.read_text().splitlines()
    t, x, force = lines[5].split(";")
    lines[5] = ";".join([t, "1.234,5", force])
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasurementError, match=r"not numeric in a used column .*'\.' or ',' as the decimal mark, "
                                               r"no digit grouping"):
        read_measurement(path)


def test_a_delimiter_inside_a_quoted_name_does_not_choose_the_columns(tmp_path):
    path = lab_file(tmp_path, sep=";", decimal=",", extra=False, time_fmt="%.10g")
    text = path.read_text().replace('"x_mm"', '"x, clamp [mm]"')
    path.write_text(text)
    side = path.with_suffix(".toml")
    side.write_text(side.read_text().replace("x_mm = {", '"x, clamp [mm]" = {'))
    m = read_measurement(path)
    assert np.max(np.abs(m.values["x, clamp [mm]"] - 2e-3 * np.sin(2 * np.pi * 13 * np.arange(N) / FS))) < 1e-10


def test_missing_column_and_unknown_unit(tmp_path):
    p = lab_file(tmp_path)
    side = p.with_suffix(".toml")
    side.write_text(side.read_text().replace('x_mm = { unit = "mm"', 'x_um = { unit = "mm"'))
    with pytest.raises(MeasurementError, match=r"run.csv: column 'x_um' named in run.toml is missing; columns: t, x_mm"):
        read_measurement(p)
    side.write_text(side.read_text().replace('x_um = { unit = "mm"', 'x_mm = { unit = "inch"'))
    with pytest.raises(MeasurementError, match=r"run.toml: \[outputs.x_mm.unit\] 'inch' unknown; allowed: m, cm, mm"):
        read_measurement(p)


def test_levels_ordered_by_value_then_excitation_then_input_rms(tmp_path):
    for i, (lv, amp) in enumerate([(3.0, 1.0), (1.0, 3.0), (2.0, 2.0)]):
        d = tmp_path / "a"
        d.mkdir(exist_ok=True)
        lab_file(d, f"f{i}", level=lv, amp=amp)
    items, basis = read_dataset_with_order(tmp_path / "a")
    assert basis == "level_value" and [m.level_value for m in items] == [1.0, 2.0, 3.0]
    d = tmp_path / "b"
    d.mkdir()
    for i, a in enumerate([5.0, 1.0, 3.0]):
        lab_file(d, f"f{i}", sidecar_extra=f"[excitation]\namplitude = {a}")
    items, basis = read_dataset_with_order(d)
    assert basis == "excitation.amplitude" and [m.path.stem for m in items] == ["f1", "f2", "f0"]
    d = tmp_path / "c"
    d.mkdir()
    for i, amp in enumerate([2.0, 1.0, 3.0]):  # input force amplitude scales with amp below
        p = lab_file(d, f"f{i}", amp=amp)
        text = p.read_text().split("\n")
        p.write_text("\n".join(text[:3] + [",".join(r.split(",")[:2] + [f"{float(r.split(',')[2]) * amp:.8f}"]
                                                    + r.split(",")[3:]) for r in text[3:] if r] ) + "\n")
    items, basis = read_dataset_with_order(d)
    assert basis == "input RMS" and [m.path.stem for m in items] == ["f1", "f0", "f2"]


def test_a_dataset_s_files_are_found_by_their_sidecars_whatever_their_extension(tmp_path):
    """A DAQ's LEVEL1.CSV, a text export's .txt and .dat, each beside its sidecar, read to the numbers of a .csv
    twin; a README.txt without a sidecar is no measurement; a CSV without one, or two files sharing one, is
    refused naming the fix."""
    d = tmp_path / "lab"
    d.mkdir()
    for i, (name, suffix) in enumerate([("LEVEL1", ".CSV"), ("level2", ".txt"), ("level3", ".dat")]):
        p = lab_file(d, name, level=i + 1.0, amp=1.0 + i)
        p.rename(p.with_suffix(suffix))
    (d / "README.txt").write_text("bench 2, December, three levels\n")
    twin = read_measurement(lab_file(tmp_path, "twin", level=2.0, amp=2.0))
    items, basis = read_dataset_with_order(d)
    assert [m.path.name for m in items] == ["LEVEL1.CSV", "level2.txt", "level3.dat"] and basis == "level_value"
    assert np.array_equal(items[1].values["x_mm"], twin.values["x_mm"])
    (d / "level4.csv").write_text("t,x_mm,F_kN\n0,0,0\n")
    with pytest.raises(MeasurementError, match=r"level4.csv: no sidecar level4.toml"):
        read_dataset_with_order(d)
    (d / "level4.csv").unlink()
    (d / "level3.txt").write_bytes((d / "level3.dat").read_bytes())
    with pytest.raises(MeasurementError, match=r"level3.dat and level3.txt share the sidecar level3.toml; "
                                               r"allowed: one"):
        read_dataset_with_order(d)
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "README.txt").write_text("nothing yet\n")
    with pytest.raises(MeasurementError, match=r"no measurement found \(a file ending in .csv, .txt"):
        read_dataset_with_order(empty)
    assert holds_measurements(d) and not holds_measurements(empty)  # which folders `diagnose --cases` takes


def _export(tmp_path, header: str, rows: list[str], unit_x: str = "mm") -> pathlib.Path:
    """A CSV written by hand (header, then rows) with a sidecar for its columns "x" (unit_x) and "F" (kN)."""
    path = tmp_path / "export.csv"
    path.write_text("\n".join([header] + rows) + "\n")
    path.with_suffix(".toml").write_text("\n".join([
        'model = "SDOFBoucWen"', f"sample_rate_hz = {FS}", 'time_column = "Time, s"', "[inputs]",
        'F = { unit = "kN", model_variable = "u" }', "[outputs]",
        f'x = {{ unit = "{unit_x}", model_variable = "y" }}']))
    return path


ROWS = [f"{k / FS:.6g},{0.5 * k:.6f},{-2.0 * k:.6f}" for k in range(400)]


@pytest.mark.parametrize("header, rows, unit_x", [
    ('"Time, s",x,F', ROWS, "mm"),  # a comma inside a quoted name
    ('"Time, s",x,F\n"s","mm","kN"', ROWS, "mm"),  # a units row that agrees with the sidecar
    ('"Time, s",x,F\n\n# units:\ns,mm,kN\n# data:', ROWS, "mm"),  # blank and comment lines around the units row
    ('"Time, s",x,F\n[s],[mm],[kN]', ROWS, "[mm]"),  # bracketed units, in the row and in the sidecar
    ('"Time, s",x,F,', [r + "," for r in ROWS], "mm"),  # every line ends in the delimiter
    ('"Time, s",x,F', ['"{}","{}","{}"'.format(*r.split(",")) for r in ROWS], "mm"),  # quoted numbers
])
def test_lab_export_variants_are_read(tmp_path, header, rows, unit_x):
    m = read_measurement(_export(tmp_path, header, rows, unit_x))
    k = np.arange(400)
    assert np.array_equal(m.values["x"], 0.5e-3 * k) and np.array_equal(m.values["F"], -2.0e3 * k)  # mm, kN -> SI
    assert np.max(np.abs(m.t - k / FS)) < 1e-8  # the grid fitted to stamps rounded by up to 5e-7 s


@pytest.mark.parametrize("unit, si", [("m/s^2", 1.0), ("m/s²", 1.0), ("mm/s^2", 1e-3), ("µm", 1e-6), ("μm", 1e-6),
                                      ("[m/s]", 1.0), ("m/s/s", 1.0), ("m s^-2", 1.0), ("m·s⁻²", 1.0),
                                      ("mm/sec", 1e-3), ("m/sec^2", 1.0), ("G", 9.80665), ("gn", 9.80665),
                                      ("ips", 0.0254), ("in/s²", 0.0254)])
def test_unit_spellings(tmp_path, unit, si):
    m = read_measurement(_export(tmp_path, '"Time, s",x,F', ROWS, unit))
    assert m.values["x"][2] == pytest.approx(1.0 * si, rel=1e-15)


# the definitions, written out: 1 in = 2.54 cm, 1 ft = 12 in, 1 lbf = 1 lb (0.45359237 kg) x standard gravity
@pytest.mark.parametrize("unit, si", [("cm", 0.01), ("in", 0.0254), ("ft", 12 * 0.0254), ("in/s", 0.0254),
                                      ("ft/s^2", 12 * 0.0254), ("cm/s²", 0.01), ("mg", 9.80665e-3), ("mN", 1e-3),
                                      ("daN", 10.0), ("lbf", 0.45359237 * 9.80665)])
def test_lab_and_imperial_units_convert_to_si(tmp_path, unit, si):
    m = read_measurement(_export(tmp_path, '"Time, s",x,F', ROWS, unit))
    assert m.values["x"][2] == pytest.approx(1.0 * si, rel=1e-15)


def test_units_row_that_contradicts_the_sidecar_is_refused(tmp_path):
    p = _export(tmp_path, '"Time, s",x,F\ns,m,kN', ROWS)
    with pytest.raises(MeasurementError, match=r"export.csv: row 2: the units row gives 'm' for column 'x' but "
                                               r"export.toml says 'mm'; allowed: the same unit in both"):
        read_measurement(p)
    p = _export(tmp_path, '"Time, s",x,F\nms,mm,kN', ROWS)  # the sidecar's time_unit is the default "s"
    with pytest.raises(MeasurementError, match=r"row 2: the units row gives 'ms' for the time column 'Time, s' "
                                               r"but export.toml says time_unit = 's'"):
        read_measurement(p)


@pytest.mark.parametrize("header, rows", [
    ("Time x F", [r.replace(",", " ") for r in ROWS]),  # one space
    ("  Time      x          F", ["  " + "  ".join(f"{v:>10}" for v in r.split(",")) for r in ROWS]),  # aligned
    ('"Time"  "x"  "F"\n s  mm  kN', [r.replace(",", "   ").replace(".", ",") for r in ROWS]),  # decimal commas
])
def test_columns_aligned_by_spaces_are_read(tmp_path, header, rows):
    p = _export(tmp_path, header, rows)
    side = p.with_suffix(".toml")
    side.write_text(side.read_text().replace('time_column = "Time, s"', 'time_column = "Time"'))
    m = read_measurement(p)
    k = np.arange(400)
    assert np.array_equal(m.values["x"], 0.5e-3 * k) and np.array_equal(m.values["F"], -2.0e3 * k)


def test_names_and_fields_split_at_spaces_into_other_numbers_are_refused(tmp_path):
    # a name that holds a space, unquoted: four names over three fields
    p = _export(tmp_path, "Time s x F", [r.replace(",", " ") for r in ROWS])
    with pytest.raises(MeasurementError, match=r"export.csv: row 2: 3 fields separated by spaces under 4 name\(s\) "
                                               r"in row 1; allowed: as many names as fields"):
        read_measurement(p)


def _headerless(tmp_path, rows: list[str], columns='["Time", "x", "F"]', comments=()) -> pathlib.Path:
    """A numeric export without a header line, its sidecar naming the columns."""
    path = _export(tmp_path, "", rows)
    path.write_text("\n".join(list(comments) + rows) + "\n")
    side = path.with_suffix(".toml")
    side.write_text(side.read_text().replace('time_column = "Time, s"', f'time_column = "Time"\ncolumns = {columns}'))
    return path


@pytest.mark.parametrize("rows", [
    ROWS,  # ','
    [" ".join(f"{float(v):15.7e}" for v in r.split(",")) for r in ROWS],  # MATLAB's save -ascii
    [r.replace(",", ";").replace(".", ",") for r in ROWS],  # ';' and decimal commas
    [r.replace(",", "\t") for r in ROWS],  # tab
])
def test_a_file_without_a_header_line_is_read_with_the_sidecar_s_column_names(tmp_path, rows):
    m = read_measurement(_headerless(tmp_path, rows, comments=("# logger dump",)))
    k = np.arange(400)
    np.testing.assert_allclose(m.values["x"], 0.5e-3 * k, rtol=1e-7, atol=0)  # 8 significant digits written
    np.testing.assert_allclose(m.values["F"], -2.0e3 * k, rtol=1e-7, atol=0)
    assert np.max(np.abs(m.t - k / FS)) < 1e-8


def test_a_header_line_and_its_absence_are_told_apart_by_name(tmp_path):
    # numbers where the names should be: the sidecar's `columns` named as the fix
    path = _export(tmp_path, ROWS[0], ROWS[1:])
    with pytest.raises(MeasurementError, match=r"export.csv: row 1 holds numbers, not column names; allowed: a "
                                               r"header line of column names above the data, or the sidecar's "
                                               r"`columns = \[...\]`"):
        read_measurement(path)
    # a header line under a sidecar that names the columns: the row and the fix named
    path = _headerless(tmp_path, ['"Time, s",x,F'] + ROWS)
    with pytest.raises(MeasurementError, match=r"row 1 names the columns \(Time, s, x, F\) but the sidecar's "
                                               r"`columns` names them too \(Time, x, F\); allowed: one of the two"):
        read_measurement(path)
    # a line that splits into as many numbers nowhere: the first line named
    path = _headerless(tmp_path, [r + ",1" for r in ROWS])
    with pytest.raises(MeasurementError, match=r"row 1 does not split into 3 numbers \(the sidecar's columns: Time, "
                                               r"x, F\)"):
        read_measurement(path)
    # a name twice, or none
    for columns in ('["Time", "x", "x"]', "[]"):
        with pytest.raises(MeasurementError, match=r"export.toml: \[columns\] .* names no column or one twice"):
            read_measurement(_headerless(tmp_path, ROWS, columns=columns))


def _with_sensitivity(tmp_path, unit: str, sensitivity: str, variable="y") -> pathlib.Path:
    """The export's x column recorded as a sensor's voltage in `unit`, with `sensitivity` in the sidecar."""
    path = _export(tmp_path, '"Time, s",x,F', ROWS)
    side = path.with_suffix(".toml")
    side.write_text(side.read_text().replace(
        'x = { unit = "mm", model_variable = "y" }',
        f'x = {{ unit = "{unit}", model_variable = "{variable}", sensitivity = "{sensitivity}" }}'))
    return path


# what the column reads, by hand: volts over the sensitivity in its unit, that unit in SI
@pytest.mark.parametrize("unit, sensitivity, si_per_number, quantity_unit, model_unit", [
    ("mV", "100 mV/g", 1e-3 / 0.1 * 9.80665, "g", "m/s2"),  # an accelerometer
    ("V", "2.25 mV/N", 1.0 / 2.25e-3, "N", "N"),  # a force cell
    ("V", "10 V/mm", 0.1 * 1e-3, "mm", "m"),  # a displacement sensor
    ("mV", " 1e2  mV / m/s^2 ", 1e-3 / 0.1, "m/s2", "m/s2"),  # spaces, an exponent, a spelling of the unit
])
def test_a_voltage_with_its_sensor_s_sensitivity_reads_what_the_sensor_measures(tmp_path, unit, sensitivity,
                                                                                si_per_number, quantity_unit,
                                                                                model_unit):
    m = read_measurement(_with_sensitivity(tmp_path, unit, sensitivity))
    k = np.arange(400)
    np.testing.assert_allclose(m.values["x"], 0.5 * k * si_per_number, rtol=1e-14, atol=0)
    assert m.outputs["x"].quantity_unit == quantity_unit
    # what it measures is checked against the model variable, not the volts: no voltage channel
    assert check_quantities(m, {"y": model_unit, "u": "N"}, voltages=False) == []


@pytest.mark.parametrize("unit, sensitivity, says", [
    ("mm", "100 mV/g", r"\[outputs.x.sensitivity\] on a column in 'mm', not a voltage"),
    ("mV", "100 mV per g", r"\[outputs.x.sensitivity\] '100 mV per g' is not a sensitivity"),
    ("mV", "100 mV/furlong", r"'100 mV/furlong' is not a sensitivity"),
    ("mV", "1 V/mV", r"'1 V/mV' is not a sensitivity"),
    ("mV", "0 mV/g", r"'0 mV/g' is not a sensitivity"),
    ("mV", "1.2.3 mV/g", r"'1.2.3 mV/g' is not a sensitivity"),  # no number: refused, not a crash
])
def test_a_sensitivity_that_cannot_be_read_is_refused_naming_the_field(tmp_path, unit, sensitivity, says):
    with pytest.raises(MeasurementError, match=says + r".*allowed: '<number> V/<unit>' or '<number> mV/<unit>'"):
        read_measurement(_with_sensitivity(tmp_path, unit, sensitivity))


PREAMBLE = ["Sample rate: 750 Hz", "Date,2026-05-04", "Operator;X", "Channels: Time, x, F", "", "Test 12 12.5 3"]


def test_a_preamble_without_comment_marks_is_skipped_up_to_the_header(tmp_path):
    """An export's settings above the header, as DAQ software writes them (no '#'): the header is the first line
    that names every column the sidecar uses; a units row under it and the rows below read as without the
    preamble."""
    path = _export(tmp_path, "\n".join(PREAMBLE + ['"Time, s",x,F', "s,mm,kN"]), ROWS)
    m = read_measurement(path)
    k = np.arange(400)
    assert np.array_equal(m.values["x"], 0.5e-3 * k) and np.array_equal(m.values["F"], -2.0e3 * k)
    # a row named in an error counts the preamble's lines: the units row is row 8
    path.write_text(path.read_text().replace("s,mm,kN", "s,m,kN"))
    with pytest.raises(MeasurementError, match=r"export.csv: row 8: the units row gives 'm' for column 'x'"):
        read_measurement(path)


def test_a_preamble_above_a_file_without_a_header_line_is_skipped(tmp_path):
    path = _headerless(tmp_path, PREAMBLE + [r.replace(",", ";").replace(".", ",") for r in ROWS])
    m = read_measurement(path)
    assert np.array_equal(m.values["F"], -2.0e3 * np.arange(400))


def test_an_inverted_sensor_is_read_in_the_model_s_sign_convention(tmp_path):
    path = _with_sensitivity(tmp_path, "mV", "100 mV/g")
    plain = read_measurement(path).values["x"]
    side = path.with_suffix(".toml")
    side.write_text(side.read_text().replace('sensitivity = "100 mV/g"', 'sensitivity = "100 mV/g", invert = true'))
    assert np.array_equal(read_measurement(path).values["x"], -plain)
    side.write_text(side.read_text().replace("invert = true", 'invert = "yes"'))
    with pytest.raises(MeasurementError, match=r"\[outputs.x.invert\] must be bool, not 'yes'"):
        read_measurement(path)


def _mat_twin(tmp_path, name: str, layout: str, **savemat) -> tuple[pathlib.Path, object]:
    """A MATLAB file holding the columns of lab_file's CSV in one of the layouts a lab saves them in, beside the
    CSV's sidecar (plus `columns` for a matrix), and the CSV's own reading. Written by scipy (v4 to v7), or by
    hdf5storage in MATLAB's v7.3 layout (HDF5) where savemat asks for format '7.3'."""
    import hdf5storage
    import scipy.io

    csv = lab_file(tmp_path, name)
    twin = read_measurement(csv)
    data = np.loadtxt(csv, delimiter=",", skiprows=3, usecols=(0, 1, 2))
    t, x, force = data.T
    side = csv.with_suffix(".toml").read_text()
    if layout == "vectors":  # save('run.mat', 't', 'x_mm', 'F_kN') of column vectors, and a text note beside them
        content = {"t": t[:, None], "x_mm": x[:, None], "F_kN": force[:, None], "operator": "X"}
    elif layout == "struct":  # one struct per channel set: the sidecar names 'daq.x_mm'
        content = {"daq": {"t": t, "x_mm": x, "F_kN": force}}
        side = side.replace("F_kN =", '"daq.F_kN" =').replace("x_mm =", '"daq.x_mm" =')
        side = 'time_column = "daq.t"\n' + side
    else:  # one matrix, a channel per row (3 x N), and a calibration vector of another length beside it
        content = {"data": data.T, "cal": np.array([1.0, 2.0])}
        side = 'columns = ["t", "x_mm", "F_kN"]\n' + side
    csv.unlink()
    mat = csv.with_suffix(".mat")
    if savemat.get("format") == "7.3":
        hdf5storage.savemat(str(mat), content, matlab_compatible=True, **savemat)
    else:
        scipy.io.savemat(mat, content, **savemat)
    mat.with_suffix(".toml").write_text(side)
    return mat, twin


@pytest.mark.parametrize("layout, savemat", [("vectors", {}), ("vectors", {"format": "4"}), ("struct", {}),
                                             ("matrix", {"do_compression": True}), ("vectors", {"format": "7.3"}),
                                             ("struct", {"format": "7.3"}), ("matrix", {"format": "7.3"})])
def test_a_matlab_file_reads_to_the_numbers_of_its_csv_twin(tmp_path, layout, savemat):
    mat, twin = _mat_twin(tmp_path, "run", layout, **savemat)
    m = read_measurement(mat)
    key = "daq.x_mm" if layout == "struct" else "x_mm"
    assert np.array_equal(m.values[key], twin.values["x_mm"]) and np.array_equal(m.t, twin.t)
    assert np.array_equal(m.values[key.replace("x_mm", "F_kN")], twin.values["F_kN"])
    items, _ = read_dataset_with_order(tmp_path)
    assert [i.path.name for i in items] == ["run.mat"]


@pytest.mark.parametrize("savemat", [{}, {"format": "7.3"}], ids=["v5", "v7.3"])
def test_a_matlab_file_that_cannot_be_used_is_refused_naming_the_fix(tmp_path, savemat):
    """The vectors listed are the numeric ones (the text variable beside them is not), in either format."""
    import struct

    mat, _ = _mat_twin(tmp_path, "run", "vectors", **savemat)
    side = mat.with_suffix(".toml")
    side.write_text(side.read_text().replace("x_mm =", "x =", 1))
    listed = "t, x_mm, F_kN" if not savemat else "F_kN, t, x_mm"  # file order; HDF5 lists its names sorted
    with pytest.raises(MeasurementError, match=rf"run.mat: variable 'x' named in run.toml is missing; vectors: "
                                               rf"{listed}; allowed: a MATLAB file \(v4, v6, v7 or v7.3\)"):
        read_measurement(mat)
    side.write_text('columns = ["t", "x_mm"]\n' + side.read_text())
    with pytest.raises(MeasurementError, match=r"\[columns\] 2 names, and run.mat holds 0 matrices"):
        read_measurement(mat)
    # a v7.3 header (version 0x0200) over no HDF5 content: a damaged or truncated file
    header = b"MATLAB 7.3 MAT-file, HDF5 schema 1.00 .".ljust(116) + bytes(8) + struct.pack("<H", 0x0200) + b"IM"
    mat.write_bytes(header + bytes(512))
    with pytest.raises(MeasurementError, match=r"run.mat: not readable as a MATLAB file \(.*v7.3"):
        read_measurement(mat)
    mat.write_bytes(b"t,x_mm\n0,1\n" * 30)
    with pytest.raises(MeasurementError, match=r"run.mat: not readable as a MATLAB file"):
        read_measurement(mat)


def _tdms_twin(tmp_path, layout: str) -> tuple[pathlib.Path, object]:
    """An NI TDMS file (written by npTDMS's writer) holding the columns of lab_file's CSV as NI DAQ software logs
    them, beside the CSV's sidecar, and the CSV's own reading: 'waveforms' (channels with wf_increment and
    unit_string, no time channel, the sidecar without sample_rate_hz), 'time channel' (a channel 't' beside
    them, no waveform timing), 'timestamps' (a channel of time stamps, the sidecar's time_column, no
    sample_rate_hz) or 'groups' (a second group holding a channel named as the used displacement:
    the sidecar names it 'Laser/x_mm')."""
    from nptdms import ChannelObject, GroupObject, TdmsWriter

    csv = lab_file(tmp_path, "run")
    twin = read_measurement(csv)
    t, x, force = np.loadtxt(csv, delimiter=",", skiprows=3, usecols=(0, 1, 2)).T
    side = csv.with_suffix(".toml").read_text()
    wave = {"wf_increment": 1.0 / FS, "wf_start_offset": 0.0}
    if layout == "waveforms":
        objects = [GroupObject("Data"), ChannelObject("Data", "x_mm", x, {**wave, "unit_string": "mm"}),
                   ChannelObject("Data", "F_kN", force, {**wave, "unit_string": "kN"})]
        side = side.replace(f"sample_rate_hz = {FS}\n", "")
    elif layout == "time channel":
        objects = [GroupObject("Data"), ChannelObject("Data", "t", t, {"unit_string": "s"}),
                   ChannelObject("Data", "x_mm", x), ChannelObject("Data", "F_kN", force)]
    elif layout == "timestamps":  # LabVIEW's time stamps (ns resolution) beside channels without waveform timing
        start = np.datetime64("2026-05-04T10:15:00", "ns")
        stamps = start + np.round(np.arange(len(t)) * 1e9 / FS).astype("timedelta64[ns]")
        objects = [GroupObject("Data"), ChannelObject("Data", "Time", stamps), ChannelObject("Data", "x_mm", x),
                   ChannelObject("Data", "F_kN", force)]
        side = 'time_column = "Time"\n' + side.replace(f"sample_rate_hz = {FS}\n", "")
    else:
        objects = [ChannelObject("Shaker", "F_kN", force, {**wave, "unit_string": "kN"}),
                   ChannelObject("Laser", "x_mm", x, {**wave, "unit_string": "mm"}),
                   ChannelObject("Spare", "x_mm", -x, {**wave, "unit_string": "mm"})]
        side = side.replace("x_mm =", '"Laser/x_mm" =')
    csv.unlink()
    path = csv.with_suffix(".tdms")
    with TdmsWriter(str(path)) as w:
        w.write_segment(objects)
    path.with_suffix(".toml").write_text(side)
    return path, twin


@pytest.mark.parametrize("layout", ["waveforms", "time channel", "timestamps", "groups"])
def test_an_ni_tdms_file_reads_to_the_numbers_of_its_csv_twin(tmp_path, layout):
    path, twin = _tdms_twin(tmp_path, layout)
    m = read_measurement(path)
    key = "Laser/x_mm" if layout == "groups" else "x_mm"
    resolution = 1e-6 if layout == "timestamps" else 1e-9  # npTDMS writes time stamps to the microsecond
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-12) and np.max(np.abs(m.t - twin.t)) < resolution
    assert np.array_equal(m.values[key], twin.values["x_mm"]) and np.array_equal(m.values["F_kN"], twin.values["F_kN"])
    items, _ = read_dataset_with_order(tmp_path)
    assert [i.path.name for i in items] == ["run.tdms"]


def _tdms_by_the_spec(path: pathlib.Path, group: str, channels: dict[str, tuple[np.ndarray, dict]]) -> None:
    """One TDMS segment written byte by byte from NI's description of the format ('TDMS File Format Internal
    Structure'), not by the library the reader uses: a lead-in (tag 'TDSm', table of contents: metadata, new
    object list, raw data; version 4713; the segment's and the metadata's lengths), the objects ('/', the group,
    its channels) with their raw data index (float64 = type 10, or time stamps = type 0x44 for a structured
    array of 'fractions' and 'seconds'; one dimension, the number of values) and properties (float64 values, or
    strings = type 0x20), then each channel's samples, little-endian."""
    import struct

    def text(s: str) -> bytes:
        b = s.encode()
        return struct.pack("<I", len(b)) + b

    def props(d: dict) -> bytes:
        out = struct.pack("<I", len(d))
        for k, v in d.items():
            out += text(k) + (struct.pack("<I", 0x20) + text(v) if isinstance(v, str) else struct.pack("<Id", 10, v))
        return out

    meta = struct.pack("<I", 2 + len(channels)) + text("/") + struct.pack("<I", 0xFFFFFFFF) + props({})
    meta += text(f"/'{group}'") + struct.pack("<I", 0xFFFFFFFF) + props({})
    raw = b""
    for name, (data, p) in channels.items():
        stamps = data.dtype.names == ("fractions", "seconds")  # time stamps (type 0x44): u64 2^-64 s, i64 s
        meta += text(f"/'{group}'/'{name}'") + struct.pack("<IIIQ", 20, 0x44 if stamps else 10, 1, len(data))
        meta += props(p)
        raw += data.astype([("fractions", "<u8"), ("seconds", "<i8")] if stamps else "<f8").tobytes()
    lead = b"TDSm" + struct.pack("<iiQQ", 2 | 4 | 8, 4713, len(meta) + len(raw), len(meta))
    path.write_bytes(lead + meta + raw)


def test_a_tdms_file_written_from_ni_s_description_of_the_format_is_read(tmp_path):
    """A file whose bytes follow NI's format description (not npTDMS's writer): its waveform timing gives the
    record's time (offset 0.25 s, 1 kHz), or a channel of time stamps does; its unit_string is checked, its
    samples read to SI."""
    x, force = np.sin(np.arange(2000) / 50.0), np.cos(np.arange(2000) / 50.0)
    wave = {"wf_increment": 1e-3, "wf_start_offset": 0.25}
    path = tmp_path / "shaker.tdms"
    _tdms_by_the_spec(path, "Untitled", {"Laser": (x, {**wave, "unit_string": "mm"}),
                                         "Force": (force, {**wave, "unit_string": "kN"})})
    path.with_suffix(".toml").write_text('model = "SDOFBoucWen"\n[inputs]\nForce = { unit = "kN", model_variable = '
                                         '"u" }\n[outputs]\nLaser = { unit = "mm", model_variable = "y" }\n')
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(1000.0, rel=1e-12)
    assert np.max(np.abs(m.t - (0.25 + np.arange(2000) / 1000.0))) < 1e-12
    assert np.array_equal(m.values["Laser"], x * 1e-3) and np.array_equal(m.values["Force"], force * 1e3)
    # a logger's time stamps instead (whole seconds since 1904 and 2^-64 s fractions, 750 Hz from 0.3 s past a
    # second): the time channel reads to better than a nanosecond (stamps cut to the microsecond, as datetime64[us]
    # holds them, would put the grid about 0.4 us off)
    k = np.arange(2000)
    whole, frac = np.divmod(0.3 + k / 750.0, 1.0)
    stamps = np.zeros(2000, [("fractions", "u8"), ("seconds", "i8")])
    stamps["seconds"], stamps["fractions"] = 3_860_000_000 + whole.astype(int), np.round(frac * 2.0**64)
    _tdms_by_the_spec(path, "Untitled", {"Time": (stamps, {}), "Laser": (x, {"unit_string": "mm"}),
                                         "Force": (force, {"unit_string": "kN"})})
    side = path.with_suffix(".toml")
    side.write_text('time_column = "Time"\n' + side.read_text())
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(750.0, rel=1e-12) and np.max(np.abs(m.t - k / 750.0)) < 1e-9
    side.write_text(side.read_text().replace('"mm"', '"m"'))
    with pytest.raises(MeasurementError, match=r"channel 'Laser' has the unit 'mm' but shaker.toml says 'm'"):
        read_measurement(path)
    path.with_suffix(".toml").write_text('time_unit = "clock"\n' + path.with_suffix(".toml").read_text())
    with pytest.raises(MeasurementError, match=r"\[time_unit\] 'clock' for shaker.tdms: clock stamps are text"):
        read_measurement(path)


def test_an_ni_tdms_file_that_cannot_be_used_is_refused_naming_the_fix(tmp_path):
    """Each refusal names the file, the channel and what is allowed: a channel named ambiguously (two groups hold
    it) or not at all, a unit_string the sidecar contradicts, waveforms of different timing, a stated rate the
    waveforms contradict, and a file that is not TDMS."""
    from nptdms import ChannelObject, TdmsWriter

    path, _ = _tdms_twin(tmp_path, "groups")
    side = path.with_suffix(".toml")
    groups = side.read_text()
    side.write_text(groups.replace('"Laser/x_mm" =', "x_mm ="))
    with pytest.raises(MeasurementError, match=r"run.tdms: channel 'x_mm' named in run.toml names several channels "
                                               r"\(Laser/x_mm, Spare/x_mm\); allowed: one of those names"):
        read_measurement(path)
    side.write_text(groups.replace('"Laser/x_mm" =', '"Laser/x" ='))
    with pytest.raises(MeasurementError, match=r"run.tdms: channel 'Laser/x' named in run.toml is missing; channels: "
                                               r"(?=.*Shaker/F_kN)(?=.*Laser/x_mm).*; allowed: a TDMS file"):
        read_measurement(path)
    side.write_text(groups.replace('unit = "mm"', 'unit = "um"'))
    with pytest.raises(MeasurementError, match=r"channel 'Laser/x_mm' has the unit 'mm' but run.toml says 'um'"):
        read_measurement(path)
    side.write_text(groups.replace("sample_rate_hz = 750.0", "sample_rate_hz = 1000.0"))
    with pytest.raises(MeasurementError, match=r"\[sample_rate_hz\] = 1000 but column '\(waveform timing\)' is sampled "
                                               r"at 750 Hz"):
        read_measurement(path)
    side.write_text(groups)
    x = np.zeros(N)
    with TdmsWriter(str(path)) as w:
        w.write_segment([ChannelObject("Shaker", "F_kN", x, {"wf_increment": 1 / FS}),
                         ChannelObject("Laser", "x_mm", x, {"wf_increment": 1 / (2 * FS)})])
    with pytest.raises(MeasurementError, match=r"run.tdms: the used channels' timings differ"):
        read_measurement(path)
    path.write_bytes(b"t,x_mm\n0,1\n" * 30)
    with pytest.raises(MeasurementError, match=r"run.tdms: not readable as a TDMS file"):
        read_measurement(path)


def _uff58(id1: str, node: int, direction: int, unit: str, data: np.ndarray, dt: float, t0: float = 0.0,
           spec: int = 8, function: int = 1, abscissa: int = 17, binary: str | None = None) -> str | bytes:
    """One time record (universal dataset 58, ASCII, real double) written line by line from the format's
    description, not by the library the reader uses: the delimiters, five ID lines, the DOF identification
    (`function` type, 1: time response; the response node and direction), the data form (type 4, even spacing,
    abscissa start and increment), the abscissa (specific data type `abscissa`, 17: time) and ordinate (`spec`,
    its unit label) characteristics, then the values four to a line (E20.12). With `binary` (a numpy dtype:
    '<f8', '>f4', ...) the record is dataset 58b: an ID line naming the byte order (1: little, 2: big endian),
    the IEEE format, the 11 ASCII lines and the data's bytes, the same 11 lines (data type 4 or 2: double or
    single), then the values' bytes with the closing delimiter right after them (returned as bytes)."""
    raw = None if binary is None else np.asarray(data, dtype=binary).tobytes()
    dtype = np.dtype(binary or "<f8")
    head = "    58" if raw is None else \
        f"{58:6d}b{1 if dtype.byteorder in '<=' else 2:6d}{2:6d}{11:12d}{len(raw):12d}{0:6d}{0:6d}{0:12d}{0:12d}"
    lines = ["    -1", head, id1, "NONE", "NONE", "NONE", "NONE",
             f"{function:5d}{0:10d}{0:5d}{0:10d} {'NONE':10s}{node:10d}{direction:4d} {'NONE':10s}{0:10d}{0:4d}",
             f"{4 if dtype.itemsize == 8 else 2:10d}{len(data):10d}{1:10d}{t0:13.5e}{dt:13.5e}{0.0:13.5e}",
             f"{abscissa:10d}{0:5d}{0:5d}{0:5d} {'NONE':20s} {'NONE':20s}",
             f"{spec:10d}{0:5d}{0:5d}{0:5d} {'NONE':20s} {unit:20s}",
             f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':20s} {'NONE':20s}",
             f"{0:10d}{0:5d}{0:5d}{0:5d} {'NONE':20s} {'NONE':20s}"]
    if raw is not None:
        return ("\n".join(lines) + "\n").encode("ascii") + raw + b"    -1\n"
    lines += ["".join(f"{v:20.12e}" for v in data[i:i + 4]) for i in range(0, len(data), 4)]
    return "\n".join(lines + ["    -1"]) + "\n"


def test_a_universal_file_s_time_records_read_to_the_numbers_of_their_csv_twin(tmp_path):
    """A universal file (dataset 58) holding the CSV twin's force and displacement as time records, written
    from the format's description (a records' writer of our own in the test, not pyuff's), with an FRF record
    beside them that is not a channel: read by id1 and by 'node:direction', timed by the abscissa increment (no
    sample_rate_hz), the units checked; a record whose name another shares is refused naming both."""
    csv = lab_file(tmp_path, "run")
    twin = read_measurement(csv)
    t, x, force = np.loadtxt(csv, delimiter=",", skiprows=3, usecols=(0, 1, 2)).T
    side = csv.with_suffix(".toml").read_text().replace(f"sample_rate_hz = {FS}\n", "")
    csv.unlink()
    frf = _uff58("H 101:+Z/1:+Z", 101, 3, "mm/kN", np.ones(8), 1.0, function=4, abscissa=18)  # an FRF over Hz
    path = tmp_path / "run.uff"
    path.write_text(_uff58("F_kN", 1, 3, "kN", force, 1 / FS, spec=13) + _uff58("Laser", 101, 3, "mm", x, 1 / FS)
                    + frf)
    side_file = path.with_suffix(".toml")
    side_file.write_text(side.replace("x_mm =", '"101:+Z" ='))
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-12) and np.max(np.abs(m.t - twin.t)) < 1e-9
    assert np.allclose(m.values["101:+Z"], twin.values["x_mm"], rtol=1e-11, atol=0)  # 12 digits written
    assert np.allclose(m.values["F_kN"], twin.values["F_kN"], rtol=1e-11, atol=0)
    side_file.write_text(side.replace("x_mm =", "Laser =").replace('unit = "mm"', 'unit = "m"'))
    with pytest.raises(MeasurementError, match=r"run.uff: channel 'Laser' has the unit 'mm' but run.toml says 'm'"):
        read_measurement(path)
    path.write_text(path.read_text() + _uff58("Laser", 102, 3, "mm", x, 1 / FS))
    side_file.write_text(side.replace("x_mm =", "Laser ="))
    with pytest.raises(MeasurementError, match=r"run.uff: channel 'Laser' named in run.toml names several channels "
                                               r"\(#2, #4\)"):
        read_measurement(path)
    side_file.write_text(side.replace("x_mm =", '"#4" ='))
    assert np.allclose(read_measurement(path).values["#4"], twin.values["x_mm"], rtol=1e-11, atol=0)


@pytest.mark.parametrize("dtype", ["<f8", ">f4"])
def test_a_binary_universal_file_s_time_records_read_to_the_numbers_of_their_csv_twin(tmp_path, dtype):
    """Dataset 58b, the binary form test software such as Simcenter Testlab can export, written from the
    format's description (doubles in little-endian order as a PC writes them; singles in big-endian order as a
    workstation did): read to the CSV twin's numbers, exactly for doubles, to single precision (2^-24 of each
    value) for singles; timed by the abscissa increment as the ASCII form."""
    csv = lab_file(tmp_path, "run")
    twin = read_measurement(csv)
    t, x, force = np.loadtxt(csv, delimiter=",", skiprows=3, usecols=(0, 1, 2)).T
    side = csv.with_suffix(".toml").read_text().replace(f"sample_rate_hz = {FS}\n", "")
    csv.unlink()
    path = tmp_path / "run.uff"
    path.write_bytes(_uff58("F_kN", 1, 3, "kN", force, 1 / FS, spec=13, binary=dtype)
                     + _uff58("Laser", 101, 3, "mm", x, 1 / FS, binary=dtype))
    path.with_suffix(".toml").write_text(side.replace("x_mm =", '"101:+Z" ='))
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-12) and np.max(np.abs(m.t - twin.t)) < 1e-9
    rtol = 0.0 if dtype.endswith("8") else 2.0**-24
    assert np.allclose(m.values["101:+Z"], twin.values["x_mm"], rtol=rtol, atol=0)
    assert np.allclose(m.values["F_kN"], twin.values["F_kN"], rtol=rtol, atol=0)


@pytest.mark.parametrize("rate", [750.0, 1000.0, 1651.2, 2048.0, 2560.0, 8192.0, 12800.0, 25600.0, 48000.0, 51200.0])
def test_a_universal_file_s_six_digit_increment_gives_the_rate_the_daq_was_set_to(rate):
    from pyfit.io.uff import increment_of

    written = float(f"{1 / rate:.5e}")  # the header's E13.5
    assert increment_of(written) == pytest.approx(1 / rate, rel=1e-15)


def test_a_universal_file_written_by_pyuff_is_read(tmp_path):
    """Records as pyuff writes them (another writer's layout of dataset 58): by id1 and by node and direction,
    the start of the abscissa kept, accelerations in g read to m/s²."""
    import pyuff

    t = np.arange(3000) / 2048.0
    a, f = np.sin(2 * np.pi * 30 * t), np.cos(2 * np.pi * 30 * t)
    common = dict(func_type=1, ref_node=0, ref_dir=0, abscissa_spacing=1, abscissa_min=0.5, abscissa_inc=1 / 2048.0,
                  x=0.5 + t,
                  abscissa_spec_data_type=17, abscissa_axis_units_lab="s", orddenom_spec_data_type=0,
                  z_axis_spec_data_type=0, binary=0)
    sets = [pyuff.prepare_58(id1="acc_mass", rsp_node=2, rsp_dir=-3, data=a, ordinate_axis_units_lab="g",
                             ordinate_spec_data_type=12, **common),
            pyuff.prepare_58(id1="clamp_force", rsp_node=1, rsp_dir=3, data=f, ordinate_axis_units_lab="N",
                             ordinate_spec_data_type=13, **common)]
    path = tmp_path / "sweep.unv"
    pyuff.UFF(str(path)).write_sets(sets, mode="overwrite")
    path.with_suffix(".toml").write_text('model = "SDOFBoucWen"\n[inputs]\nclamp_force = { unit = "N", model_variable '
                                         '= "u" }\n[outputs]\n"2:-Z" = { unit = "g", model_variable = "y" }\n')
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(2048.0, rel=1e-12) and m.t[0] == pytest.approx(0.5, abs=1e-12)
    assert np.allclose(m.values["2:-Z"], a * 9.80665, rtol=1e-10, atol=1e-12)  # g is standard gravity here
    assert np.allclose(m.values["clamp_force"], f, rtol=1e-10, atol=1e-12)


def test_a_file_holding_several_levels_reads_as_one_measurement_per_segment(tmp_path):
    """Three levels recorded one after the other in one file, cut by the sidecar's [[segments]]: each segment
    reads to the numbers of the level written in a file of its own, under the name 'file#k', its level and
    level_value its segment's, and the dataset orders them by level like separate files."""
    n = 1500
    apart, one = tmp_path / "apart", tmp_path / "one"
    apart.mkdir()
    one.mkdir()
    parts = {level: lab_file(apart, f"L{level:g}", level=level, amp=level, t=np.arange(n) / FS)
             for level in (2.0, 1.0, 3.0)}
    rows = []
    for k, level in enumerate((2.0, 1.0, 3.0)):  # not in level order: the segments are ordered by their levels
        body = parts[level].read_text().split("\n")[3:]
        rows += [f"{(k * n + i) / FS:.10g}," + r.split(",", 1)[1] for i, r in enumerate(b for b in body if b)]
    (one / "run.csv").write_text('"t","x_mm","F_kN","status","T_room"\n' + "\n".join(rows) + "\n")
    side = parts[1.0].with_suffix(".toml").read_text().replace("level_value = 1.0\n", "")
    segments = "".join(f"[[segments]]\nfrom_s = {k * n / FS!r}\nto_s = {(k + 1) * n / FS!r}\nlevel = \"{lv:g} mm\"\n"
                       f"level_value = {lv}\n" for k, lv in enumerate((2.0, 1.0, 3.0)))
    (one / "run.toml").write_text(side + segments)
    items, basis = read_dataset_with_order(one)
    assert basis == "level_value" and [m.name for m in items] == ["run#2", "run#1", "run#3"]
    for m in items:
        alone = read_measurement(parts[m.level_value])
        assert m.level == f"{m.level_value:g} mm" and len(m.t) == n
        assert np.array_equal(m.values["x_mm"], alone.values["x_mm"])
        assert np.array_equal(m.values["F_kN"], alone.values["F_kN"])


@pytest.mark.parametrize("segments, says", [
    ("[[segments]]\nfrom_s = 1.0\nto_s = 0.5\n", r"\[segments\[0\]\] from_s = 1 s to to_s = 0.5 s holds 0 samples"),
    ("[[segments]]\nfrom_s = 40.0\nto_s = 50.0\n", r"holds 0 samples; allowed: from_s < to_s, at least two"),
    ("[[segments]]\nfrom_s = 0.0\nto_s = 10.0\n[[segments]]\nfrom_s = 9.0\nto_s = 20.0\n",
     r"\[segments\[1\]\] from_s = 9 s lies inside segments\[0\] \(0-10 s\); allowed: segments that do not overlap"),
    ("[[segments]]\nfrom = 0.0\nto_s = 10.0\n", r"\[segments\[0\].from\] unknown key; allowed: excitation, from_s"),
])
def test_segments_that_cannot_be_cut_are_refused_naming_the_table(tmp_path, segments, says):
    path = lab_file(tmp_path)
    side = path.with_suffix(".toml")
    side.write_text(side.read_text() + segments)
    with pytest.raises(MeasurementError, match=says):
        read_measurement(path)


@pytest.mark.parametrize("stamp", ["%Y-%m-%d %H:%M:%S.%f", "%Y-%m-%dT%H:%M:%S.%f", "%H:%M:%S.%f"])
def test_a_time_column_of_clock_stamps_reads_as_seconds_from_the_first(tmp_path, stamp):
    """A DAQ that stamps each sample with the wall clock (a date and time, or the time of day, to the µs): the
    record's time runs from its first stamp, the rate comes from the stamps when the sidecar gives none, and
    the stamps must meet it as numeric ones do."""
    import datetime

    start = datetime.datetime(2026, 5, 4, 10, 15, 32, 125000)
    n = 3000
    rows = [f"{(start + datetime.timedelta(seconds=k / FS)).strftime(stamp)},{np.sin(k / 7):.8f},{np.cos(k / 5):.8f}"
            for k in range(n)]
    path = tmp_path / "run.csv"
    path.write_text("Time,x_mm,F_kN\n" + "\n".join(rows) + "\n")
    path.with_suffix(".toml").write_text('model = "SDOFBoucWen"\ntime_column = "Time"\ntime_unit = "clock"\n'
                                         '[inputs]\nF_kN = { unit = "kN", model_variable = "u" }\n'
                                         '[outputs]\nx_mm = { unit = "mm", model_variable = "y" }\n')
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-9) and np.max(np.abs(m.t - np.arange(n) / FS)) < 1e-6
    assert m.values["x_mm"][7] == pytest.approx(1e-3 * np.sin(1.0), abs=1e-11)
    path.write_text(path.read_text().replace(rows[10].split(",")[0], "12.5", 1))
    with pytest.raises(MeasurementError, match=r"run.csv: not numeric in a used column .*'12.5'.* at row 10.*and "
                                               r"clock times \(YYYY-MM-DD hh:mm:ss.fff or hh:mm:ss.fff\) in 'Time'"):
        read_measurement(path)
    side = path.with_suffix(".toml")
    side.write_text(side.read_text().replace('time_unit = "clock"\n', ""))
    with pytest.raises(MeasurementError, match=r'a time column of clock times: time_unit = "clock"'):
        read_measurement(path)


def _xlsx_by_the_spec(path, rows: list[list]) -> None:
    """A one-sheet workbook written from the Office Open XML description (ECMA-376: the package's content types
    and relationships, a workbook naming the sheet, the sheet's rows of cells), not by the library the reader
    uses: text as inline strings, numbers as their shortest repr (read back bit for bit)."""
    import zipfile
    from xml.sax.saxutils import escape

    def cell(ref, v):
        if isinstance(v, str):
            return f'<c r="{ref}" t="inlineStr"><is><t>{escape(v)}</t></is></c>'
        return f'<c r="{ref}"><v>{v!r}</v></c>'

    def ref(col, row):
        return f"{chr(ord('A') + col)}{row}"

    sheet = "".join(f'<row r="{i}">' + "".join(cell(ref(j, i), v) for j, v in enumerate(r) if v is not None)
                    + "</row>" for i, r in enumerate(rows, 1) if r)
    ns = "http://schemas.openxmlformats.org"
    parts = {
        "[Content_Types].xml": f'<Types xmlns="{ns}/package/2006/content-types">'
        '<Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
        '<Default Extension="xml" ContentType="application/xml"/>'
        '<Override PartName="/xl/workbook.xml" ContentType="application/vnd.openxmlformats-officedocument.'
        'spreadsheetml.sheet.main+xml"/><Override PartName="/xl/worksheets/sheet1.xml" ContentType="application/'
        'vnd.openxmlformats-officedocument.spreadsheetml.worksheet+xml"/></Types>',
        "_rels/.rels": f'<Relationships xmlns="{ns}/package/2006/relationships"><Relationship Id="rId1" '
        f'Type="{ns}/officeDocument/2006/relationships/officeDocument" Target="xl/workbook.xml"/></Relationships>',
        "xl/workbook.xml": f'<workbook xmlns="{ns}/spreadsheetml/2006/main" xmlns:r="{ns}/officeDocument/2006/'
        'relationships"><sheets><sheet name="Messung" sheetId="1" r:id="rId1"/></sheets></workbook>',
        "xl/_rels/workbook.xml.rels": f'<Relationships xmlns="{ns}/package/2006/relationships"><Relationship '
        f'Id="rId1" Type="{ns}/officeDocument/2006/relationships/worksheet" Target="worksheets/sheet1.xml"/>'
        '</Relationships>',
        "xl/worksheets/sheet1.xml": f'<worksheet xmlns="{ns}/spreadsheetml/2006/main"><sheetData>{sheet}'
        '</sheetData></worksheet>'}
    with zipfile.ZipFile(path, "w") as z:
        for name, xml in parts.items():
            z.writestr(name, '<?xml version="1.0" encoding="UTF-8" standalone="yes"?>' + xml)


def _twin_rows(csv) -> tuple[list[str], list[list]]:
    """The CSV twin's header names and its rows as numbers (the text column as text)."""
    names = ["t", "x_mm", "F_kN", "status", "T_room"]
    body = [line.split(",") for line in csv.read_text().splitlines()[3:] if line]
    return names, [[float(a), float(b), float(c), s, float(d)] for a, b, c, s, d in body]


def test_an_excel_sheet_written_from_the_format_s_description_reads_to_the_numbers_of_its_csv_twin(tmp_path):
    """A workbook written from the Office Open XML description (not by openpyxl, which reads it), its one sheet
    holding a title row, an empty row, the twin's header and its rows: read to the twin's numbers exactly (a
    cell holds the double the CSV's text parses to) with its time; `sheet` naming a sheet the workbook lacks
    refused listing the ones it holds; a row named in an error is the spreadsheet's (a title cell of two lines
    counted as one row)."""
    csv = lab_file(tmp_path, "run", t=np.arange(3000) / FS)
    twin = read_measurement(csv)
    names, rows = _twin_rows(csv)
    side = csv.with_suffix(".toml").read_text()
    csv.unlink()
    path = tmp_path / "run.xlsx"
    _xlsx_by_the_spec(path, [["Schwingtisch 2, Versuch 3\nBetreiber: X"], [], names, *rows])
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(FS, rel=1e-12) and np.max(np.abs(m.t - twin.t)) < 1e-9
    assert np.array_equal(m.values["x_mm"], twin.values["x_mm"])
    assert np.array_equal(m.values["F_kN"], twin.values["F_kN"])
    rows[99][1] = "NaN"  # in the spreadsheet's row 103: under a title of two lines, an empty row and the header
    _xlsx_by_the_spec(path, [["Schwingtisch 2, Versuch 3\nBetreiber: X"], [], names, *rows])
    with pytest.raises(MeasurementError, match=r"run.xlsx: row 103: column 'x_mm' is not finite"):
        read_measurement(path)
    path.with_suffix(".toml").write_text('sheet = "Run 3"\n' + side)
    with pytest.raises(MeasurementError, match=r"run.xlsx: not readable as an Excel workbook \(no sheet 'Run 3'; "
                                               r"sheets: Messung\)"):
        read_measurement(path)


def test_an_excel_workbook_s_named_sheet_with_units_and_clock_times_is_read(tmp_path):
    """A workbook as a bench's spreadsheet holds one (written by openpyxl): a settings sheet first, the run on a
    sheet the sidecar names, title rows, a units row under the header, the time as the spreadsheet's date-time
    cells (time_unit = "clock"; 500 Hz, whole milliseconds apart: such a cell is read to the millisecond) and the
    rate taken from them: the numbers of the CSV twin, the same time; a units row that contradicts the sidecar,
    a file that is no workbook and `sheet` beside a CSV are refused."""
    import datetime
    import openpyxl

    csv = lab_file(tmp_path, "run", t=np.arange(3000) / 500.0)
    side = csv.with_suffix(".toml").read_text().replace(f"sample_rate_hz = {FS}\n", "")
    csv.with_suffix(".toml").write_text(side)
    twin = read_measurement(csv)
    names, rows = _twin_rows(csv)
    csv.unlink()
    start = datetime.datetime(2026, 5, 4, 10, 15, 32)
    book = openpyxl.Workbook()
    book.active.title = "Settings"
    book.active.append(["shaker", "2"])
    run = book.create_sheet("Run 3")
    run.append(["Sine 13 Hz"])
    run.append(names)
    run.append(["hh:mm:ss", "mm", "kN", "", "degC"])
    for r in rows:
        run.append([start + datetime.timedelta(seconds=r[0])] + r[1:])
    path = tmp_path / "run.xlsx"
    book.save(path)
    path.with_suffix(".toml").write_text(f'sheet = "Run 3"\ntime_unit = "clock"\n' + side)
    m = read_measurement(path)
    assert m.sample_rate_hz == pytest.approx(500.0, rel=1e-12)
    assert np.max(np.abs((m.t - m.t[0]) - (twin.t - twin.t[0]))) < 1e-9
    assert np.array_equal(m.values["x_mm"], twin.values["x_mm"])
    assert np.array_equal(m.values["F_kN"], twin.values["F_kN"])
    run.cell(row=3, column=2).value = "m"
    book.save(path)
    with pytest.raises(MeasurementError, match=r"run.xlsx: row 3: the units row gives 'm' for column 'x_mm' but "
                                               r"run.toml says 'mm'"):
        read_measurement(path)
    path.write_text("t,x_mm\n0,1\n")
    with pytest.raises(MeasurementError, match=r"run.xlsx: not readable as an Excel workbook \("):
        read_measurement(path)
    path.unlink()
    lab_file(tmp_path, "run")
    path.with_suffix(".toml").write_text('sheet = "Run 3"\n' + side)
    with pytest.raises(MeasurementError, match=r"run.toml: \[sheet\] .*; allowed: a sheet of an Excel workbook"):
        read_measurement(tmp_path / "run.csv")
