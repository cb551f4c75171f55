"""`stockbridge diagnose --check`: what a diagnosis would read, without fitting (pyfit.gap.dataset_check)."""
import numpy as np
import pytest
import scipy.signal

from pyfit.cli import main
from pyfit.gap.dataset_check import check_dataset, check_text
from pyfit.gap import diagnose as dg
from pyfit.gap.diagnose import DiagnoseError
from pyfit.gap.report import clipped_lines

M, C, K = 2.0, 10.0, 1e5  # kg, N·s/m, N/m: f_n = 35.6 Hz


def _lab_dataset(folder, range_mm=None):
    """A linear SDOF's response to a 5-80 Hz force sweep at three levels (scipy lsim, independent of the FMU), as
    a bench writes it: force in kN, displacement in mm; the middle level's displacement sensor mounted the other
    way round (its sidecar says invert = true); with range_mm, a displacement sensor that reads at most that
    (beyond it, the limit). Returns each level's true displacement [m]."""
    fs, t = 500.0, np.arange(3000) / 500.0
    u = np.sin(2 * np.pi * (5.0 + 6.25 * t) * t)  # 5 Hz + 12.5 Hz/s
    _, y, _ = scipy.signal.lsim(([1.0 / M], [1.0, C / M, K / M]), u, t)
    truth = {}
    for i, level in enumerate((10.0, 25.0, 50.0)):
        sign = -1.0 if i == 1 else 1.0
        name = f"run{i}"
        x_mm = sign * 1e3 * level * y
        if range_mm is not None:
            x_mm = np.clip(x_mm, -range_mm, range_mm)
        rows = "\n".join(f"{tk:.6g},{1e-3 * level * uk:.10g},{xk:.10g}" for tk, uk, xk in zip(t, u, x_mm))
        (folder / f"{name}.csv").write_text("t,F_kN,x_mm\n" + rows + "\n")
        (folder / f"{name}.toml").write_text("\n".join([
            'model = "SDOFBoucWen"', f"sample_rate_hz = {fs}", f'level = "{level:g} N"', f"level_value = {level}",
            "[inputs]", 'F_kN = { unit = "kN", model_variable = "u" }', "[outputs]",
            f'x_mm = {{ unit = "mm", model_variable = "y"{", invert = true" if sign < 0 else ""} }}']) + "\n")
        truth[name] = level * y
    return truth


def test_the_check_states_what_each_file_and_column_was_read_as(tmp_path, fmu_dir):
    truth = _lab_dataset(tmp_path)
    c = check_dataset("sdof", tmp_path, fmu_dir=fmu_dir)
    assert [(f.name, f.role) for f in c.files] == [("run0", "calibration"), ("run1", "held out"),
                                                  ("run2", "calibration")]
    for f in c.files:
        y = next(ch for ch in f.channels if ch.column == "x_mm")
        assert (y.model_variable, y.model_unit, y.inverted) == ("y", "m", f.name == "run1")
        # read in SI whatever the file's unit and sign: the RMS of the true displacement, to the file's 10 digits
        assert y.rms_si == pytest.approx(np.std(truth[f.name]), rel=1e-8)
        assert f.duration_s == pytest.approx(6.0, rel=1e-12) and f.noise_nrmse > 0
        lo, hi = f.excited_hz
        assert lo < 10.0 and 70.0 < hi < 90.0  # the 5-80 Hz sweep
    assert c.resonances_hz and c.excited_hz[0] < c.resonances_hz[0] < c.excited_hz[1]
    text = check_text(c)
    assert "| run1 | x_mm | output | mm | y [m] |" in text and "| inverted |" in text


def test_a_sensor_held_at_its_range_limit_is_named_with_its_samples(tmp_path, fmu_dir, sdof_system):
    """The displacement sensor reads at most 60 % of the highest level's peak: that level's channel is named with
    the samples beyond the limit (counted from the true response), by the check and by the diagnosis's reading;
    the levels within the range are not."""
    truth = _lab_dataset(tmp_path)
    limit = 0.6 * 1e3 * np.max(np.abs(truth["run2"]))
    _lab_dataset(tmp_path, range_mm=limit)
    beyond = int(np.sum(np.abs(1e3 * truth["run2"]) >= limit))
    assert beyond > 50
    c = check_dataset("sdof", tmp_path, fmu_dir=fmu_dir)
    assert {(f.name, ch.column): ch.clipped for f in c.files for ch in f.channels} == {
        ("run0", "F_kN"): 0, ("run0", "x_mm"): 0, ("run1", "F_kN"): 0, ("run1", "x_mm"): 0, ("run2", "F_kN"): 0,
        ("run2", "x_mm"): beyond}
    assert "range limit holds it (an overloaded sensor, amplifier or ADC" in check_text(c)
    assert f"run2 x_mm ({beyond} samples)" in check_text(c)
    runner, system = sdof_system
    clipped = dg._load(tmp_path, system, dg.DiagnoseConfig(), runner).clipped
    assert clipped == {"run2 x_mm": beyond}
    assert f"run2 x_mm ({beyond} samples)." in "".join(clipped_lines(clipped))  # the report's line


def test_the_check_command_prints_it_and_stops_before_any_fit(tmp_path, fmu_dir, capsys):
    (tmp_path / "data").mkdir()
    _lab_dataset(tmp_path / "data")
    out = tmp_path / "out"
    assert main(["diagnose", "--model", "sdof", "--data", str(tmp_path / "data"), "--fmus", str(fmu_dir), "--out",
                 str(out), "--check"]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith("# Dataset check:") and "| run0 | level" not in printed and "10 N" in printed
    assert sorted(q.name for q in out.iterdir()) == ["check.md"]  # nothing fitted: only what it printed
    assert (out / "check.md").read_text() == printed


def test_the_check_raises_what_the_diagnosis_would(tmp_path, fmu_dir):
    _lab_dataset(tmp_path)
    (tmp_path / "run2.toml").write_text((tmp_path / "run2.toml").read_text().replace('"y"', '"x"'))
    with pytest.raises(DiagnoseError, match=r"run2.toml: \[outputs\] model_variable 'x' is not a variable"):
        check_dataset("sdof", tmp_path, fmu_dir=fmu_dir)
