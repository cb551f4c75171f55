"""The gap diagnosis on a damper characteristic test (IEC 61897: clamp impedance at three clamp-velocity
levels) made by the independent CasADi reference damper with measurement noise (0.5 % in |Z|, 0.3° in
phase; the sidecar states 1 %), through `python scripts/diagnose.py --impedance`."""
import subprocess
import sys
import pathlib

import numpy as np
import pytest

from pyfit.gap.datasets import DAMPER, IMPEDANCE_UNCERTAINTY, write_impedance_case
from pyfit.gap.result import Diagnosis, Verdict
from pyfit.gap.diagnose import DiagnoseConfig, DiagnoseError
from pyfit.gap import impedance_gap
from pyfit.gap.impedance_gap import diagnose_impedance
from pyfit.io.impedance import read_impedance, write_impedance

ROOT = pathlib.Path(__file__).resolve().parents[1]
SHORT = DiagnoseConfig(nominal_budget=30, refit_budget=40)  # CI budgets; the README's cases use the defaults


def _diagnose_cli(test: pathlib.Path, out: pathlib.Path, fmu_dir, *extra) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "scripts" / "diagnose.py"), "--impedance", str(test),
                           "--out", str(out), "--fmus", str(fmu_dir), *extra], capture_output=True, text=True,
                          timeout=1200)


def _rerun_from_stored_fits(monkeypatch, *args, **kwargs) -> Diagnosis:
    """The diagnosis again into the same folder with every fit forbidden: it must come from OUT/fits/."""
    def no_fit(*_):
        raise AssertionError("a fit was redone although it was stored")

    monkeypatch.setattr(impedance_gap, "_least_squares", no_fit)
    return diagnose_impedance(*args, **kwargs)


@pytest.mark.slow
def test_sidecar_states_the_uncertainty_the_noise_stays_below(tmp_path):
    case = write_impedance_case(tmp_path / "none", "none")
    test = read_impedance(case / "impedance_test.csv")
    clean = read_impedance(write_impedance_case(tmp_path / "clean", "none", seed=1) / "impedance_test.csv")
    assert test.uncertainty == IMPEDANCE_UNCERTAINTY and test.impedance.shape == (7, 3)
    # two noisy copies of the same truth: their relative difference has √2 × the noise's RMS
    noise = float(np.sqrt(np.mean(np.abs(test.impedance / clean.impedance - 1) ** 2)) / np.sqrt(2))
    assert 0.004 < noise < IMPEDANCE_UNCERTAINTY  # 0.5 % in |Z| and 0.3° in phase: about 0.0073


@pytest.mark.slow
def test_null_case_is_no_significant_gap(fmu_dir, tmp_path, measured, monkeypatch):
    case = write_impedance_case(tmp_path / "damper_none", "none", seed=2)
    run = _diagnose_cli(case / "impedance_test.csv", tmp_path / "out", fmu_dir, "--workers", "1")
    assert run.returncode == 0, run.stderr[-3000:]
    rep = Diagnosis.read(tmp_path / "out" / "report.json")
    assert rep.verdict is Verdict.NO_GAP and rep.ranking == ()
    measured("impedance diagnosis, null case: held-out misfit of the calibrated linear damper (RMS |Z/Z_meas − 1|)",
             rep.gap.overall, 1.2 * IMPEDANCE_UNCERTAINTY)
    assert "no significant gap" in (tmp_path / "out" / "report.md").read_text()
    again = _rerun_from_stored_fits(monkeypatch, case / "impedance_test.csv", tmp_path / "out", fmu_dir=fmu_dir)
    assert again.gap.overall == rep.gap.overall


@pytest.mark.slow
def test_withheld_cubic_stiffness_is_named(fmu_dir, tmp_path, measured, monkeypatch):
    case = write_impedance_case(tmp_path / "damper_cubic", "cubic_stiffness")
    cfg = DiagnoseConfig(**{**SHORT.__dict__, "effects": ["cubic_stiffness", "quadratic_damping"]})
    rep = diagnose_impedance(case / "impedance_test.csv", tmp_path / "out", cfg, fmu_dir, workers=2)
    assert rep.chosen == ("cubic_stiffness",), rep.ranking
    top = rep.ranking[0]
    measured("impedance diagnosis, withheld cubic stiffness: held-out shrink [%]", top.shrink_pct, 90.0,
             at_least=True)
    measured("impedance diagnosis, withheld cubic stiffness: held-out misfit after (RMS |Z/Z_meas − 1|)",
             top.heldout_gap_after, IMPEDANCE_UNCERTAINTY)
    truth = DAMPER.withheld["cubic_stiffness"]
    for name in ("k_cs1", "k_cs2"):
        measured(f"impedance diagnosis: fitted {name} relative to the withheld value",
                 abs(top.params[name] / truth[name] - 1), 0.05)
    again = _rerun_from_stored_fits(monkeypatch, case / "impedance_test.csv", tmp_path / "out", cfg, fmu_dir)
    assert again.ranking == rep.ranking


def test_two_levels_cannot_be_diagnosed(tmp_path, fmu_dir):
    freqs = [10.0, 20.0]
    amps = np.array([[0.005, 0.02]]) / (2 * np.pi * np.array(freqs)[:, None])
    csv = write_impedance(tmp_path / "two.csv", freqs, amps, np.full((2, 2), 30.0 + 5j), uncertainty=0.01)
    with pytest.raises(DiagnoseError, match=r"two\.csv: .*at least three clamp-velocity levels.*found 2"):
        diagnose_impedance(csv, tmp_path / "out", fmu_dir=fmu_dir)
    run = _diagnose_cli(csv, tmp_path / "out", fmu_dir)
    assert run.returncode == 2 and "at least three clamp-velocity levels" in run.stderr


def test_uncertainty_must_be_stated(tmp_path, fmu_dir):
    freqs = [10.0]
    amps = np.array([[0.005, 0.01, 0.02]]) / (2 * np.pi * 10.0)
    csv = write_impedance(tmp_path / "t.csv", freqs, amps, np.full((1, 3), 30.0 + 5j))
    with pytest.raises(DiagnoseError, match=r"t\.csv: the test's measurement uncertainty is None.*--uncertainty"):
        diagnose_impedance(csv, tmp_path / "out", fmu_dir=fmu_dir)
