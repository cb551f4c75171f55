"""One fitting run: target measurement -> objective -> optimiser -> result.json and figures."""
from __future__ import annotations

import dataclasses
import hashlib
import json
import pathlib
from dataclasses import asdict

import numpy as np
from fmpy import read_model_description

from pyfit import __version__
from pyfit.analysis import signals
from pyfit.report import plots
from pyfit.io import benchmark_data
from pyfit.runtime.benchmark_runs import simulate_validation
from pyfit.io.data import check_quantities, read_measurement
from pyfit.io.fit_config import FitConfig
from pyfit.io.impedance import read_impedance
from pyfit.fit.impedance_objective import ImpedanceObjective
from pyfit.fit.objective import Objective
from pyfit.fit.optim import baselines
from pyfit.fit.optim.nno import nno
from pyfit.runtime.clock import StageClock
from pyfit.runtime.examples import ensure_fmu
from pyfit.reference.synthetic import SyntheticSpec, write_synthetic


def ensure_target(cfg: FitConfig) -> pathlib.Path:
    """The target measurement, made from [target.synthetic] (CasADi reference + sensor chain) if missing."""
    if cfg.target_file.is_file():
        return cfg.target_file
    if cfg.synthetic is None:
        raise FileNotFoundError(f"{cfg.path}: [target.file] {cfg.target_file} not found")
    s = cfg.synthetic
    spec = SyntheticSpec(cfg.model, s["excitation"], s["stop_time"], s["sample_rate_hz"], s["outputs"],
                         s["parameters"], s["noise_std"], s["oversample"], s["seed"], solver=s["solver"],
                         anti_alias=s["anti_alias"], passband_ripple_db=s["passband_ripple_db"])
    tmp = cfg.target_file.with_name(cfg.target_file.stem + ".partial.csv")
    write_synthetic(tmp, spec)
    tmp.with_suffix(".toml").replace(cfg.target_file.with_suffix(".toml"))
    tmp.replace(cfg.target_file)
    return cfg.target_file


def _versions() -> dict:
    import casadi
    import fmpy
    import pymoo
    import scipy
    import torch

    return {"pyfit": __version__, "fmpy": fmpy.__version__, "torch": torch.__version__, "casadi": casadi.__version__,
            "numpy": np.__version__, "scipy": scipy.__version__, "pymoo": pymoo.__version__}


def _objective(cfg: FitConfig, fmu, measurement, kind: str) -> Objective | ImpedanceObjective:
    if kind == "impedance":
        return ImpedanceObjective(str(fmu), measurement, cfg.variables, cfg.fixed, cfg.penalty)
    return Objective(str(fmu), measurement, cfg.variables, cfg.channels, cfg.fixed, kind, cfg.segment_s,
                     cfg.warmup_s, cfg.tolerance, cfg.penalty, cfg.use_inputs, cfg.input_upsample, cfg.input_periodic)


@dataclasses.dataclass
class Search:
    """The optimiser's outcome: the best point (unit-scaled), the global stage's result, the history of every
    true evaluation (stage-tagged, evaluations counted over all stages), and the objective of the last stage."""

    x: np.ndarray
    global_result: object  # OptimResult of the global stage
    history: list
    ann: list
    true_evaluations: int
    stop_reason: str
    final_objective: object


def search(cfg: FitConfig, objective_of, seed: int, stop_at: float | None = None, clock: StageClock | None = None
           ) -> Search:
    """cfg's method with the given seed: the global stage on objective_of(cfg.objective_kind), then (nno+polish)
    each polish stage on objective_of(kind), from the best point so far. objective_of: kind -> an objective with
    residuals(x) on unit-scaled x (and log_ratio for NNO's transform)."""
    obj = objective_of(cfg.objective_kind)
    n = len(cfg.variables)
    ann = []
    if cfg.method in ("nno", "nno+polish"):
        res = nno(obj.residuals, n, dataclasses.replace(cfg.nno, seed=seed),
                  transform=obj.log_ratio if cfg.nno_log_ratio else None)
        ann = [h for h in res.history if h.get("ann_error") is not None]
    elif cfg.method == "ga":
        res, _ = baselines.ga_direct(obj.residuals, n, cfg.budget, cfg.ga_pop_size, seed, stop_at)
    elif cfg.method == "de":
        res = baselines.differential_evolution(obj.residuals, n, cfg.budget, seed)
    else:
        res = baselines.polish(obj.residuals, np.full(n, 0.5), cfg.budget)
    history = [dict(h, stage="global") for h in res.history]
    if clock:
        clock.end(f"global search ({cfg.method.split('+')[0]})")
    best_x, n_eval, stop, final_obj = res.x, res.n_evaluations, res.stop_reason, obj
    if cfg.method == "nno+polish":
        for kind, budget in zip(cfg.polish_kinds, cfg.polish_budgets):
            final_obj = objective_of(kind)
            pol = baselines.polish(final_obj.residuals, best_x, budget)
            history += [dict(h, stage=f"polish:{kind}", evaluations=h["evaluations"] + n_eval) for h in pol.history]
            best_x, n_eval, stop = pol.x, n_eval + pol.n_evaluations, f"{stop}+{kind}:{pol.stop_reason}"
            if clock:
                clock.end(f"polish ({kind})")
    return Search(best_x, res, history, ann, int(n_eval), stop, final_obj)


def open_objectives(cfg: FitConfig, fmu_dir: pathlib.Path):
    """A cache of cfg's objectives on its target (kind -> Objective, opened on first use), and the measurement."""
    fmu = ensure_fmu(cfg.model, fmu_dir)
    impedance = cfg.objective_kind == "impedance"
    measurement = read_impedance(cfg.target_file) if impedance else read_measurement(cfg.target_file)
    if not impedance:  # the bounds and fixed values are SI: every channel in its model variable's quantity
        units = {v.name: v.unit or "" for v in read_model_description(str(fmu)).modelVariables}
        check_quantities(measurement, units, voltages=False)
    objectives = {}

    def objective_of(kind: str):
        if kind not in objectives:
            objectives[kind] = _objective(cfg, fmu, measurement, kind)
        return objectives[kind]

    return objective_of, objectives, fmu


def run_fit(cfg: FitConfig, fmu_dir: pathlib.Path, out_dir: pathlib.Path, seed: int,
            stop_at: float | None = None) -> dict:
    """Fit with cfg's method and the given seed; write result.json and figures into out_dir; return the result.
    stop_at: the GA baseline stops when its error first reaches this value (the NNO-vs-GA comparison)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    clock = StageClock()
    impedance = cfg.objective_kind == "impedance"
    objective_of, objectives, fmu = open_objectives(cfg, fmu_dir)
    obj = objective_of(cfg.objective_kind)
    clock.end("setup (FMU, measurement, objective)")
    found = search(cfg, objective_of, seed, stop_at, clock)
    res, history, ann, best_x, n_eval, stop = (found.global_result, found.history, found.ann, found.x,
                                               found.true_evaluations, found.stop_reason)
    final_obj = found.final_objective
    error = float(np.sum(obj.residuals(best_x) ** 2))
    ident = baselines.identifiability(final_obj.residuals, best_x, cfg.variables)
    band_error = obj.band_error_percent(best_x) if cfg.objective_kind in ("psd_band", "psd_log") else {}
    impedance_error = obj.errors(best_x) if impedance else {}
    clock.end("final errors, identifiability")
    wall_s = clock.elapsed()
    params = obj.params(best_x)
    fitted = {v.name: params[v.name] for v in cfg.variables}
    result = {
        "config": str(cfg.path), "config_text": cfg.path.read_text(), "model": cfg.model, "method": cfg.method,
        "seed": seed, "parameters": fitted, "x_unit": [float(v) for v in best_x], "objective": error,
        "band_error_percent": band_error, "impedance_error": impedance_error,
        "objective_kind": cfg.objective_kind, "problem": cfg.problem_key(), "stop_at": stop_at,
        "global_best_so_far": np.minimum.accumulate([h["true_error"] for h in res.history]).tolist(),
        "true_evaluations": int(n_eval), "stop_reason": stop, "wall_s": wall_s, "stage_s": clock.stages,
        "identifiability": asdict(ident), "recovery": recovery(fitted, cfg), "history": history,
        "versions": _versions(), "fmu_sha256": hashlib.sha256(pathlib.Path(fmu).read_bytes()).hexdigest(),
        "target": str(cfg.target_file),
    }
    if cfg.benchmark:
        try:
            result["benchmark_rms_db"] = benchmark_validation(obj, best_x, out_dir)
        except benchmark_data.BenchmarkDataMissing as exc:  # third-party data: the fit stands without it
            result["benchmark_rms_db"] = None
            result["benchmark_note"] = str(exc)
        clock.end("validation on the official signals (after wall_s)")
    (out_dir / "result.json").write_text(json.dumps(result, indent=1, default=float))
    (_impedance_figures if impedance else _figures)(cfg, obj, best_x, history, ann, out_dir)
    for o in objectives.values():
        o.close()
    return result


def benchmark_validation(obj: Objective, x, out_dir: pathlib.Path) -> dict[str, float]:
    """RMS error [dB re 1 m] of the fitted model on the official Bouc-Wen validation signals (never used to
    estimate), with a figure of the error signals."""
    params = obj.params(x)
    out, panels = {}, []
    for name, upsample in (("multisine", 20), ("sinesweep", 4)):
        sig = benchmark_data.load(name)
        y = simulate_validation(obj.runner, sig, upsample=upsample, params=params)
        out[name] = signals.rms_db(y - sig.y)
        panels.append((f"{name}: RMS error {out[name]:.1f} dB re 1 m (official output RMS "
                       f"{1e6 * np.sqrt(np.mean(sig.y ** 2)):.0f} µm)", np.arange(len(y)) / benchmark_data.FS_HZ,
                       1e6 * (y - sig.y)))
    plots.error_signals(out_dir / "benchmark_validation.png", panels, "y_model − y_official [µm]")
    return out


def recovery(fitted: dict, cfg: FitConfig) -> dict:
    """Relative errors against a known truth (synthetic targets), also for identifiable products."""
    if not cfg.truth:
        return {}
    vals = dict(cfg.truth, **fitted)
    out = {k: (fitted[k] - cfg.truth[k]) / cfg.truth[k] for k in fitted if k in cfg.truth and cfg.truth[k]}
    for a, b in cfg.products:
        if a in vals and b in vals and a in cfg.truth and b in cfg.truth:
            true = cfg.truth[a] * cfg.truth[b]
            out[f"{a}*{b}"] = (vals[a] * vals[b] - true) / true
    return out


def _figures(cfg, obj: Objective, x, history, ann, out_dir):
    plots.convergence(out_dir / "convergence.png", history, ann, f"{cfg.path.stem}: convergence ({cfg.method})")
    res = obj.simulate(x)
    fs = obj.fs
    units = {c.output: obj.runner.variables[c.output].unit for c in cfg.channels}
    for ch in cfg.channels:
        meas = obj.m.values[ch.column]
        curves = [("measured", meas, fs), ("fitted model", res[ch.output], fs)]
        plots.psd_overlay(out_dir / f"psd_{ch.output}.png", curves, ch.output, units, f"{cfg.path.stem}: PSD",
                          cfg.segment_s)
        if ch.bands:
            lo = min(b[0] for b in ch.bands)
            hi = max(b[1] for b in ch.bands)
            plots.psd_in_bands(out_dir / f"psd_band_{ch.output}.png", [("measured", meas), ("fitted model", res[ch.output])],
                               fs, cfg.segment_s, (lo, hi), ch.output, units, f"{cfg.path.stem}: PSD in the bands")
        plots.time_histories(out_dir / f"time_{ch.output}.png",
                             [("measured", obj.t, {ch.output: meas}), ("fitted model", res.time, {ch.output: res[ch.output]})],
                             [ch.output], units, f"{cfg.path.stem}: measured and fitted {ch.output}")


def _impedance_figures(cfg, obj: ImpedanceObjective, x, history, ann, out_dir):
    plots.convergence(out_dir / "convergence.png", history, ann, f"{cfg.path.stem}: convergence ({cfg.method})")
    plots.impedance_curves(out_dir, obj.test, {"fitted": obj.impedance(x)}, f"{cfg.path.stem}: measured and fitted")
