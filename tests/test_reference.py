"""The FMUs against the independent CasADi reference; the reference's two integrators against each other."""
import numpy as np
import pytest

from pyfit.reference import crosscheck
from pyfit.analysis.excitation import Excitation
from pyfit.reference import integrate
from pyfit.reference import models


@pytest.mark.parametrize("name", models.NAMES)
def test_rhs_and_jacobian_agree_with_reference(fmu_dir, name, measured):
    for r in crosscheck.check_rhs_and_jacobian(name, fmu_dir / f"{name}.fmu", n_samples=5):
        what = ("right-hand side at 5 sampled states, parameters, inputs" if r.level == "rhs"
                else "Jacobian: directional derivatives vs CasADi AD")
        measured(f"{name} vs the CasADi reference, {what}: max relative error", r.figures["max_rel_error"],
                 1e-10 if r.level == "rhs" else 1e-8)


@pytest.mark.parametrize("name", models.NAMES)
def test_trajectories_agree_with_reference(fmu_dir, name, measured):
    results = crosscheck.check_trajectories(name, fmu_dir / f"{name}.fmu")
    assert {r.level for r in results} == {"trajectory_sweep_ModelExchange", "trajectory_sweep_CoSimulation",
                                          "trajectory_multisine_CoSimulation"}
    limit = 1e-6 if name == "SDOFBoucWen" else 1e-5
    for r in results:
        measured(f"{name} {r.level.replace('trajectory_', '').replace('_', ', ')} vs CVODES (rtol 1e-12) on the "
                 "reference: max|Δy|/max|y|", max(v["max_rel_error"] for v in r.figures.values()), limit)
        assert all(v["psd_peak_hz_diff"] < 0.01 for v in r.figures.values())


@pytest.mark.parametrize("name,exc,stop", [
    ("SDOFBoucWen", Excitation(2, 120.0, 0.0, 60.0, 6.0), 4.0),
    ("TwoDOFd", Excitation(2, 10.0, 0.0, 60.0, 6.0), 4.0),
    ("StockbridgeDamper", Excitation(4, 0.05, 5.0, 40.0, 10.0, t_ramp=1.0), 2.0),
])
def test_newmark_converges_to_cvodes_at_second_order(name, exc, stop, measured):
    model = models.by_name(name)
    grid = np.arange(round(stop / 1e-3) + 1) * 1e-3
    ref = integrate.simulate_cvodes(model, grid, excitation=exc, rtol=1e-12, atol=1e-15)
    out = list(model.outputs)[0]
    errors = []
    for h in (1e-4, 5e-5):
        fine = np.arange(round(stop / h) + 1) * h
        nm = integrate.simulate_newmark(model, fine, excitation=exc)
        errors.append(np.max(np.abs(nm[out][::round(1e-3 / h)] - ref[out])) / np.max(np.abs(ref[out])))
    assert errors[0] < 1e-3
    measured(f"{name}: the thesis's Newmark scheme vs CVODES, error ratio for h = 1e-4 → 5e-5 s (second order: 4)",
             abs(errors[0] / errors[1] - 4), 0.5)
