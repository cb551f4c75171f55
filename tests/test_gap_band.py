"""The prediction band of a refitted model (pyfit.gap.band): the parameter sets its calibration files cannot tell
apart from its fit.

On stepped sines of an SDOF with a cubic spring of random strength, written by the CasADi reference (another solver,
its own sensor chain): with the spring's strength the one free parameter, fitted by a bounded scalar minimisation,
the band reaches as far as an exact root-finding of the calibration bound says (the Gauss-Newton region is the
quadratic model of the calibration misfit; within 20 % of the exact reach, never beyond it), and its tolerance is
two standard errors of a white-noise NRMSE. A linear model of the same data (the wrong model) predicts the held-out
file no better anywhere in its band: a band moves a prediction where the response has two steady states, not a
model's structure."""
import dataclasses
import pathlib

import numpy as np
import pytest
import scipy.optimize

from pyfit.gap import band, datasets, selection
from pyfit.gap import diagnose as dg
from pyfit.gap import simulate as sim
from pyfit.gap.attribute import Fit, stacked_residuals
from pyfit.gap.systems import make_system
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.fmu import FmuRunner


@pytest.fixture(scope="module")
def duffing(tmp_path_factory):
    """Three stepped-sine levels of an SDOF with a random hardening spring; the records as a diagnosis splits them."""
    k3 = float(10 ** np.random.default_rng(27).uniform(np.log10(2e8), np.log10(2e9)))
    data = datasets.write_dataset(tmp_path_factory.mktemp("duffing"), datasets.SDOF, "cubic_stiffness",
                                  truth={"k3": k3}, style=datasets.LabStyle("stepped_sine", record_s=16.0))
    runner = FmuRunner(str(ensure_fmu("SDOFBoucWen", pathlib.Path("fmus"))))
    system = make_system("sdof", dg.fmu_defaults(runner), None)
    loaded = dg._load(data, system, dg.DiagnoseConfig(), runner)
    cfg = dg.with_drive(dg.DiagnoseConfig(), system, loaded.rate)
    yield runner, loaded.cal, loaded.held, {**system.nominal_fixed, **datasets.SDOF.linear}, k3, cfg.upsample
    runner.close()


def test_the_band_reaches_as_far_as_the_calibration_allows(duffing, measured):
    runner, cal, held, linear, k3, upsample = duffing

    def cost(scale):
        r = stacked_residuals(runner, cal, {**linear, "k3": k3 * scale}, upsample, 1)
        return float(r @ r)

    best = scipy.optimize.minimize_scalar(cost, bounds=(0.9, 1.1), method="bounded",
                                          options={"xatol": 1e-6}).x
    fitted = {**linear, "k3": k3 * best}
    samples = sum(r.n * len(r.outputs) for r in cal)
    ssr0 = cost(best)
    bound = ssr0 * (1 + np.sqrt(2 / samples)) ** 2
    up = scipy.optimize.brentq(lambda d: cost(best * (1 + d)) - bound, 0.0, 0.05, xtol=1e-7)
    down = scipy.optimize.brentq(lambda d: cost(best * (1 - d)) - bound, 0.0, 0.05, xtol=1e-7)
    fit = Fit("cubic_stiffness", fitted, ["k3"], 1, float(np.sqrt(ssr0 / len(cal))), 0, 0.0)
    b = band.prediction_band(runner, fit, (), cal, held, upsample, 1)
    assert b.tolerance == pytest.approx(np.sqrt(2 / samples))
    assert b.fit_calibration == pytest.approx(fit.calibration_nrmse, rel=1e-9)
    assert b.ends == 2 and b.kept == 2 and b.probed >= 2  # both ends of the one axis within the bound
    measured("SDOF cubic spring, stepped sines: the band's reach in k3 over the exact root of the calibration bound",
             b.reach["k3"] / min(up, down), 0.8, at_least=True)
    assert b.reach["k3"] <= max(up, down)
    assert b.calibration_nrmse <= b.fit_calibration * (1 + b.tolerance)
    at_fit = selection.heldout_nrmse({r.name: sim.simulate(runner, r, fitted, upsample) for r in held}, held)
    assert b.heldout_nrmse <= at_fit


def test_a_wrong_model_is_not_moved_onto_the_data_within_its_band(duffing, measured):
    runner, cal, held, linear, k3, upsample = duffing
    free = ["k", "c"]

    def residuals(x):
        p = {**linear, **dict(zip(free, x))}
        return stacked_residuals(runner, cal, p, upsample, 1)

    x = scipy.optimize.least_squares(residuals, [linear["k"], linear["c"]], x_scale=[linear["k"], linear["c"]],
                                     max_nfev=60).x
    fitted = {**linear, **dict(zip(free, x))}
    fit = Fit("linear", fitted, free, 0, float(np.sqrt(np.sum(residuals(x) ** 2) / len(cal))), 0, 0.0)
    b = band.prediction_band(runner, fit, (), cal, held, upsample, 1)
    at_fit = selection.heldout_nrmse({r.name: sim.simulate(runner, r, fitted, upsample) for r in held}, held)
    assert at_fit > 0.05  # far from the data: the spring is strong at the held-out level
    measured("a linear model of the cubic spring's stepped sines: best held-out NRMSE in its band over its fit's",
             b.heldout_nrmse / at_fit, 0.95, at_least=True)
    assert set(b.reach) == set(free) and max(b.reach.values()) <= band.MAX_CHANGE + 1e-12
    assert dataclasses.asdict(b)["effect"] == "linear"
