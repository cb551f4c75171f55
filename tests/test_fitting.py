"""Fitting machinery: identifiability, surrogate, NNO, baselines, measurement files, fit configs, resume."""
import dataclasses
import json
import pathlib
import re
import shutil
import textwrap

import numpy as np
import pytest
import torch

from pyfit.io.sweep_config import ConfigError
from pyfit.io.data import MeasurementError, read_measurement, write_measurement
from pyfit.fit.batch import evaluations_to_reach, fit_batch
from pyfit.io.fit_config import load_fit
from pyfit.io.fit_config import FreeParameter, NNOSettings
from pyfit.fit.optim import baselines
from pyfit.fit.optim.nno import nno
from pyfit.fit.optim.surrogate import Surrogate
from pyfit.runtime.sweep import fmu_interface


def test_only_beta_gamma_and_beta_delta_are_identifiable(runner):
    """(beta, gamma, delta) and (2 beta, gamma/2, delta/2) give the same response, bit for bit."""
    base = {"exc_rate": 6.0}
    a = runner("SDOFBoucWen").simulate(4.0, 1e-3, ["y", "z"], dict(base, beta=1000.0, gamma=0.8, delta=-1.1))
    b = runner("SDOFBoucWen").simulate(4.0, 1e-3, ["y", "z"], dict(base, beta=2000.0, gamma=0.4, delta=-0.55))
    c = runner("SDOFBoucWen").simulate(4.0, 1e-3, ["y", "z"], dict(base, beta=1000.0, gamma=0.4, delta=-0.55))
    np.testing.assert_array_equal(a["y"], b["y"])
    assert np.max(np.abs(a["y"] - c["y"])) > 1e-2 * np.max(np.abs(a["y"]))  # the products do matter


def _linear_residuals(x):
    """A residual vector whose least-squares optimum is known: x* = (0.3, 0.7, 0.55)."""
    A = np.array([[1.0, 0.2, 0.0], [0.0, 1.0, -0.3], [0.4, 0.0, 1.0], [1.0, 1.0, 1.0]])
    return A @ (np.asarray(x) - np.array([0.3, 0.7, 0.55]))


def _curved_residuals(x):
    x = np.asarray(x)
    return np.array([10 * (x[1] - x[0] ** 2), 1 - x[0], 3 * (x[2] - 0.4)])  # optimum (1, 1, 0.4)


def test_identifiability_finds_the_degenerate_pair():
    vars_ = [FreeParameter("a", 0, 1), FreeParameter("b", 0, 1), FreeParameter("c", 0, 1)]
    rng = np.random.default_rng(0)
    noise = rng.normal(0, 0.01, 50)

    def degenerate(x):  # depends on a and b only through a + b
        t = np.linspace(0, 1, 50)
        return (x[0] + x[1] - 0.8) * t + (x[2] - 0.5) * t**2 + noise

    ident = baselines.identifiability(degenerate, np.array([0.3, 0.5, 0.5]), vars_)
    assert ident.singular_values[-1] < 1e-6 * ident.singular_values[0]
    ok = baselines.identifiability(_linear_residuals, np.array([0.3, 0.7, 0.55]), vars_, noise_var=1e-4)
    assert ok.singular_values[-1] > 0.1
    # the residual is linear (J = A exactly, central differences exact to rounding): sigma = sqrt(diag(1e-4 (A^T A)^-1))
    A = np.array([[1.0, 0.2, 0.0], [0.0, 1.0, -0.3], [0.4, 0.0, 1.0], [1.0, 1.0, 1.0]])
    np.testing.assert_allclose(ok.std, np.sqrt(np.diag(1e-4 * np.linalg.inv(A.T @ A))), rtol=1e-8)


def test_surrogate_learns_a_smooth_vector_function():
    rng = np.random.default_rng(1)
    X = rng.random((80, 2))
    R = np.column_stack([np.sin(3 * X[:, 0]) + X[:, 1], X[:, 0] * X[:, 1]])
    s = Surrogate([20], seed=0).fit(X, R)
    Xt = rng.random((50, 2))
    Rt = np.column_stack([np.sin(3 * Xt[:, 0]) + Xt[:, 1], Xt[:, 0] * Xt[:, 1]])
    assert np.sqrt(np.mean((s.predict(Xt) - Rt) ** 2)) < 0.05
    # predictions run on one thread whatever the caller's setting, which they restore
    was = torch.get_num_threads()
    try:
        torch.set_num_threads(2)
        on_two = s.predict(Xt)
        assert torch.get_num_threads() == 2
        torch.set_num_threads(1)
        np.testing.assert_array_equal(s.predict(Xt), on_two)
    finally:
        torch.set_num_threads(was)


def test_nno_finds_the_optimum_returns_the_best_point_and_is_reproducible():
    settings = NNOSettings(init_sim=10, max_sim=30, fun_tol=1e-6, p_size=20, ga_generations=40, seed=3,
                           max_epochs=600, patience=60)
    a = nno(_linear_residuals, 3, settings)
    # the same seed repeats the same evaluations (a shorter budget only ends the run sooner)
    b = nno(_linear_residuals, 3, dataclasses.replace(settings, max_sim=18))
    assert [(h["x"], h["true_error"]) for h in a.history[:18]] == [(h["x"], h["true_error"]) for h in b.history]
    np.testing.assert_allclose(a.x, [0.3, 0.7, 0.55], atol=0.03)
    # fun_tol 1e-6 is below what 30 evaluations reach here (2e-6): the budget ends the run
    assert a.stop_reason == "max_sim" and a.n_evaluations == 30
    # a looser fun_tol ends it as soon as a true evaluation is below it, before the budget
    c = nno(_linear_residuals, 3, dataclasses.replace(settings, fun_tol=1e-3))
    assert c.stop_reason == "fun_tol" and c.n_evaluations < 30
    assert c.history[-1]["true_error"] < 1e-3 <= min(h["true_error"] for h in c.history[:-1])


def test_baselines_respect_the_budget_and_polish_converges():
    de = baselines.differential_evolution(_curved_residuals, 3, budget=100, seed=0)
    assert de.n_evaluations == 100 and de.stop_reason == "budget"
    ga, reached = baselines.ga_direct(_curved_residuals, 3, budget=200, pop_size=20, seed=0, target=0.05)
    assert reached is not None and ga.n_evaluations == reached  # stopped at the target, within the budget
    assert ga.history[reached - 1]["true_error"] <= 0.05 < min(h["true_error"] for h in ga.history[:reached - 1])
    pol = baselines.polish(_curved_residuals, np.array([0.8, 0.6, 0.6]), budget=200)
    np.testing.assert_allclose(pol.x, [1.0, 1.0, 0.4], atol=1e-3)


def test_measurement_round_trip_with_units(tmp_path):
    t = np.arange(0, 1, 1e-3)
    path = write_measurement(tmp_path / "m.csv", "StockbridgeDamper", t,
                             {"acc": (np.sin(t) * 9.80665, "g", "a_base")},
                             {"x1": (1e-3 * np.cos(t), "mm", "x1")}, level="v0=0.05 m/s", level_value=0.05)
    m = read_measurement(path)
    np.testing.assert_allclose(m.values["x1"], 1e-3 * np.cos(t), rtol=1e-9)
    np.testing.assert_allclose(m.values["acc"], np.sin(t) * 9.80665, rtol=1e-9, atol=1e-12)
    assert m.level_value == 0.05 and m.outputs["x1"].model_variable == "x1"


@pytest.mark.parametrize("edit,needle", [
    (lambda csv, side: csv.write_text(csv.read_text().replace("\n0.5,", "\nnan,", 1)), "column 't'"),
    (lambda csv, side: side.write_text(side.read_text().replace("sample_rate_hz = 1000", "sample_rate_hz = 999")),
     "[sample_rate_hz]"),
    (lambda csv, side: side.write_text(side.read_text().replace('x1 = {', 'x9 = {')), "column 'x9'"),
    (lambda csv, side: side.write_text(side.read_text().replace('unit = "mm"', 'unit = "furlong"')),
     "[outputs.x1.unit] 'furlong' unknown"),
])
def test_bad_measurement_files_name_file_and_field(tmp_path, edit, needle):
    t = np.arange(0, 1, 1e-3)
    path = write_measurement(tmp_path / "m.csv", "X", t, {}, {"x1": (np.cos(t), "mm", "x1")})
    lines = path.read_text().splitlines()
    lines[501] = "0.5," + lines[501].split(",", 1)[1]
    path.write_text("\n".join(lines) + "\n")
    edit(path, path.with_suffix(".toml"))
    with pytest.raises(MeasurementError) as err:
        read_measurement(path)
    assert needle in str(err.value) and "m." in str(err.value)


TINY = """
[fit]
model = "SDOFBoucWen"
method = "nno"
budget = 12
[target]
file = "data/tiny.csv"
[target.synthetic]
excitation = { kind = 2, amplitude = 120.0, f_start = 20.0, f_end = 50.0, rate = 10.0 }
stop_time = 3.0
sample_rate_hz = 1000.0
outputs = ["y"]
noise_std = { y = 1e-6 }
[experiment]
exc_type = 2
exc_amplitude = 120.0
exc_f_start = 20.0
exc_f_end = 50.0
exc_rate = 10.0
[objective]
kind = "psd_log"
segment_s = 1.0
channels = [{ output = "y", column = "y_meas", bands = [[30.0, 42.0]] }]
[variables]
alpha = [40000.0, 60000.0]
[nno]
init_sim = 10
ga_generations = 10
max_epochs = 400
patience = 40
[report]
truth = { alpha = 50000.0 }
"""


def test_a_fit_target_channel_in_another_quantity_is_refused(tmp_path, fmu_dir):
    """The fit's bounds and fixed values are SI: a displacement column declared in N (or in V) is refused before
    any simulation, naming the sidecar's field and the units of a length."""
    from pyfit.fit.fitting import ensure_target, open_objectives

    cfg_path = tmp_path / "tiny.toml"
    cfg_path.write_text(TINY)
    cfg = load_fit(cfg_path)
    ensure_target(cfg)
    side = cfg.target_file.with_suffix(".toml")
    written = side.read_text()
    for unit, quantity in (("N", "force"), ("V", "voltage")):
        side.write_text(re.sub(r'(y_meas = \{ unit = )"m"', rf'\1"{unit}"', written))
        with pytest.raises(MeasurementError) as err:
            open_objectives(cfg, fmu_dir)
        assert f"[outputs.y_meas.unit] '{unit}' measures {quantity}; model_variable 'y' is length (m)" in str(
            err.value) and "allowed: m, cm, mm, um, in, ft" in str(err.value), str(err.value)


def test_fit_batch_writes_results_and_resumes_without_redoing(tmp_path, fmu_dir):
    cfg = tmp_path / "tiny.toml"
    cfg.write_text(TINY)
    out = tmp_path / "out"
    first = fit_batch([cfg], repeats=2, out=out, fmu_dir=fmu_dir, workers=2, progress=False)
    assert [r.get("error") for r in first] == [None, None]
    files = sorted(out.glob("tiny/seed_*/result.json"))
    assert len(files) == 2
    r0 = json.loads(files[0].read_text())
    assert r0["true_evaluations"] == 12 and len(r0["history"]) == 12
    assert {"pyfit", "fmpy", "torch", "casadi"} <= set(r0["versions"]) and len(r0["fmu_sha256"]) == 64
    assert (files[0].parent / "convergence.png").is_file() and (out / "summary.md").is_file()
    stages = r0["stage_s"]  # the stages partition the run: their sum is its wall time (timer calls apart)
    assert list(stages) == ["setup (FMU, measurement, objective)", "global search (nno)",
                            "final errors, identifiability"]
    assert sum(stages.values()) == pytest.approx(r0["wall_s"], abs=1e-3)
    stamp = files[0].stat().st_mtime_ns
    shutil.rmtree(files[1].parent)  # as if the batch had been killed before the second run finished
    second = fit_batch([cfg], repeats=2, out=out, fmu_dir=fmu_dir, workers=1, progress=False)
    assert files[0].stat().st_mtime_ns == stamp  # the finished run was not redone
    assert files[1].is_file() and len(second) == 2


@pytest.mark.parametrize("change,key", [
    (("budget = 12", "budget = 12\nspeed = 1"), "fit.speed"),
    (("alpha = [40000.0, 60000.0]", "alpha = [60000.0, 40000.0]"), "variables.alpha"),
    (("alpha = [40000.0, 60000.0]", "alfa = [40000.0, 60000.0]"), "variables"),
    (('method = "nno"', 'method = "annealing"'), "fit.method"),
    (('[target.synthetic]', '[target.unused]'), "target.unused"),
    (("ga_generations = 10", "ga_generations = 10\nlog_ratio = true"), "nno.log_ratio"),  # needs psd_band
    (("patience = 40", "patience = 0"), "nno.patience"),
    (("stop_time = 3.0", "stop_time = 3.0\nanti_alias = false\npassband_ripple_db = 0.005"),
     "target.synthetic.passband_ripple_db"),
])
def test_bad_fit_config_names_file_and_key(tmp_path, fmu_dir, change, key):
    cfg = tmp_path / "tiny.toml"
    cfg.write_text(TINY.replace(*change))
    with pytest.raises(ConfigError) as err:
        load_fit(cfg, lambda m: fmu_interface(fmu_dir / f"{m}.fmu").parameters)
    assert str(cfg) in str(err.value) and f"[{key}]" in str(err.value)


def test_missing_target_file_is_named(tmp_path):
    cfg = tmp_path / "tiny.toml"
    text = TINY.split("[target.synthetic]")[0] + "[experiment]" + TINY.split("[experiment]")[1]
    cfg.write_text(textwrap.dedent(text))
    with pytest.raises(ConfigError, match=r"\[target.file\] measurement .*tiny.csv not found"):
        load_fit(cfg)


def test_ga_baseline_runs_after_nno_and_stops_at_its_median(tmp_path, fmu_dir):
    """The NNO-vs-GA comparison: the GA config (same problem) runs in a second phase, stops once it reaches the
    NNO median final objective, and summary.md counts its evaluations; another problem is not compared."""
    (tmp_path / "tiny.toml").write_text(TINY)
    (tmp_path / "tiny_ga.toml").write_text(TINY.replace('method = "nno"', 'method = "ga"')
                                           .replace("budget = 12", "budget = 40"))
    (tmp_path / "other_ga.toml").write_text(TINY.replace('method = "nno"', 'method = "ga"')
                                            .replace("alpha = [40000.0, 60000.0]", "alpha = [40000.0, 61000.0]"))
    out = tmp_path / "out"
    results = fit_batch([tmp_path / "tiny_ga.toml", tmp_path / "other_ga.toml", tmp_path / "tiny.toml"], repeats=1,
                        out=out, fmu_dir=fmu_dir, workers=1, progress=False)
    nno_runs = [r for r in results if r["method"] == "nno"]
    ga_runs = [r for r in results if pathlib.Path(r["config"]).stem == "tiny_ga"]
    other = [r for r in results if pathlib.Path(r["config"]).stem == "other_ga"]
    goal = float(np.median([r["objective"] for r in nno_runs]))
    assert all(r["stop_at"] == pytest.approx(goal) for r in ga_runs)
    assert all(r["stop_at"] is None and r["true_evaluations"] == 12 for r in other)  # no NNO on that problem
    for r in ga_runs:
        reached = r["global_best_so_far"][-1] <= goal
        assert reached == (r["stop_reason"] == "target")
        assert r["true_evaluations"] == (evaluations_to_reach(r["global_best_so_far"], goal, 60) if reached else 40)
    summary = (out / "summary.md").read_text()
    assert "NNO vs GA (tiny vs tiny_ga, same problem)" in summary and "other_ga vs" not in summary


def _resonance_log_psd_residuals(x):
    """log-PSD misfit of a single resonance, f0 = 20 + 30 x0 Hz and zeta = 0.005 + 0.05 x1, on 121 bins in
    20-50 Hz; the truth x* = (0.52, 0.3) is f0 = 35.6 Hz, zeta = 2 %."""
    f = np.linspace(20.0, 50.0, 121)

    def log_psd(u):
        f0, zeta = 20.0 + 30.0 * u[0], 0.005 + 0.05 * u[1]
        return -np.log((1 - (f / f0) ** 2) ** 2 + (2 * zeta * f / f0) ** 2)

    return log_psd(np.asarray(x)) - log_psd(np.array([0.52, 0.3]))


@pytest.mark.slow  # 90 s of FMU runs; the NNO loop on a known residual: test_nno_finds_the_optimum_returns_the_best_point
def test_trust_region_nno_pins_frequency_and_damping_of_a_resonance(measured):
    """Where a global surrogate cannot resolve a sharp resonance from 10-40 samples (it left zeta off by
    0.07-0.16 in unit terms on seeds 0-2 when this test was written), the trust-region box keeps the GA where
    the surrogate has been checked: f0 within 0.06 Hz and zeta within 1e-4 after 40 true evaluations."""
    settings = NNOSettings(init_sim=10, max_sim=40, fun_tol=0.0, p_size=20, ga_generations=40, seed=2,
                           trust_region=True)
    tr = nno(_resonance_log_psd_residuals, 2, settings)
    measured("trust-region NNO, log-PSD of one resonance (f0 over 20–50 Hz, ζ over 0.5–5.5 %), 40 evaluations: "
             "|f0 − 35.6 Hz| [Hz]", 30.0 * abs(tr.x[0] - 0.52), 0.06)
    measured("the same: |ζ − 2 %|", 0.05 * abs(tr.x[1] - 0.3), 1e-4)
    radii = [h["radius"] for h in tr.history if h.get("radius") is not None]
    assert min(radii) < 0.5 and all(settings.x_tol <= r <= 0.5 for r in radii)


def test_log_ratio_search_transform_is_log_of_the_psd_ratio(tmp_path, fmu_dir):
    """The psd_band residual sqrt(w) (P - P_meas)/P_meas becomes sqrt(w) log(P/P_meas), the psd_log residual; the penalty
    vector stays finite; other objective kinds refuse it."""
    from pyfit.fit.fitting import _objective, ensure_target
    from pyfit.runtime.examples import ensure_fmu

    cfg_path = tmp_path / "tiny.toml"
    cfg_path.write_text(TINY.replace('kind = "psd_log"', 'kind = "psd_band"')
                        .replace('bands = [[30.0, 42.0]] }', 'bands = [[30.0, 42.0]], weight = 4.0 }'))
    cfg = load_fit(cfg_path)
    ensure_target(cfg)
    fmu = ensure_fmu(cfg.model, fmu_dir)
    band = _objective(cfg, fmu, read_measurement(cfg.target_file), "psd_band")
    log = _objective(cfg, fmu, read_measurement(cfg.target_file), "psd_log")
    x = np.array([0.8])
    np.testing.assert_allclose(band.log_ratio(band.residuals(x)), log.residuals(x), rtol=1e-10, atol=1e-12)
    assert np.all(np.isfinite(band.log_ratio(np.full(band.size, -1.0))))
    with pytest.raises(ValueError, match="psd_band"):
        log.log_ratio(log.residuals(x))
    band.close()
    log.close()
