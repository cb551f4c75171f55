"""The diagnosis on lab-style withheld-effect datasets: sweeps from rest instead of multisines, accelerometer
outputs, a clamp motion recorded as displacement only, a damper described by its user (not the design one).
Slow (minutes per case): `python -m pytest -m slow tests/test_gap_lab.py`."""
import pytest

from pyfit.gap import datasets
from pyfit.gap import diagnose as dg
from pyfit.io.nominal import NominalModel

CI = dg.DiagnoseConfig(nominal_budget=30, refit_budget=60)
SYMMETRIC = NominalModel("damper", {"m1": 1.0, "m2": 1.0, "L1": 0.15, "L2": 0.15, "J_G1": 2.0e-3, "J_G2": 2.0e-3,
                                    "a1": 0.02, "a2": 0.02})


def _check(rep, effect, measured, what):
    if effect == "none":
        assert rep["verdict"] == "no significant gap", rep["verdict"]
        return
    assert rep["chosen_effect"] == effect, (rep["verdict"], [(r["effect"], r["shrink_pct"]) for r in rep["ranking"]])
    measured(f"{what}, {effect} withheld: held-out shrink of the chosen effect [%]", rep["ranking"][0]["shrink_pct"],
             80.0, at_least=True)


@pytest.mark.slow
@pytest.mark.parametrize("effect", ["hysteresis", "cubic_stiffness", "coulomb_friction", "quadratic_damping", "none"])
def test_sdof_force_sweeps_with_an_accelerometer(tmp_path, fmu_dir, effect, measured):
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, effect,
                                  style=datasets.LabStyle("sweep", outputs=("a",)))
    rep = dg.diagnose("sdof", data, tmp_path / "out", CI, fmu_dir, workers=2, progress=False)
    _check(rep, effect, measured, "SDOF, 35 s force sweeps, accelerometer on the mass")


@pytest.mark.slow
@pytest.mark.parametrize("effect", ["hysteresis", "cubic_stiffness", "coulomb_friction", "quadratic_damping",
                                    "mass_eccentricity", "none"])
def test_described_damper_clamp_sweeps_recorded_as_displacement(tmp_path, fmu_dir, effect, measured):
    data = datasets.write_dataset(tmp_path / "data", datasets.DAMPER, effect,
                                  style=datasets.LabStyle("sweep", motion="x"), base=SYMMETRIC.parameters())
    rep = dg.diagnose("damper", data, tmp_path / "out", CI, fmu_dir, workers=2, progress=False, nominal=SYMMETRIC)
    _check(rep, effect, measured, "symmetric damper (1 kg, 0.15 m, described), constant-velocity clamp sweeps, "
                                  "clamp displacement only")
