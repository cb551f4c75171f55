"""The gap diagnosis on a damper characteristic test (IEC 61897 / IEEE 664: the clamp impedance versus
frequency at three or more clamp-velocity levels) instead of time records.

The nominal (linear) damper is calibrated on the lowest and highest level; its misfit on the levels between
them is the gap (where: by frequency); each candidate effect of theory §6 is added and refitted on the
same two levels (which), and judged by how far it shrinks the misfit on the held-out levels (how far). The
misfit is the RMS over test points of |Z_model / Z_meas − 1| (a relative error ε in |Z| or ε rad of phase
counts ε), judged against the test's stated measurement uncertainty (an impedance table carries no noise
to estimate it from). Simulations: the damper table runs of the energy balance (a clamp sine, settled, first
harmonics over whole periods) of the DamperElement FMU. SI units.
"""
from __future__ import annotations

import hashlib
import json
import pathlib
from dataclasses import asdict, dataclass

import numpy as np

from pyfit.fit.impedance_objective import model_impedance, relative_residuals
from pyfit.fit.optim.baselines import polish
from pyfit.gap.attribute import STIFFNESS_SCAN, UnitScaling, effect_start
from pyfit.gap import selection
from pyfit.gap.diagnose import DiagnoseConfig, DiagnoseError, fmu_defaults
from pyfit.gap.systems import Scale, damper_stiffness, damper_stuck_force, make_system
from pyfit.io.impedance import ImpedanceTest, read_impedance
from pyfit.io.nominal import NominalModel, load_nominal
from pyfit.report import plots
from pyfit.runtime.batch import RunSpec, map_tasks, run_batch
from pyfit.runtime.examples import ensure_fmu
from pyfit.runtime.fmu import FmuRunner

STRENGTH_STEPS = (0.02, 0.1, 0.3)  # an effect's start tried at these fractions of the way to each bound


@dataclass
class ImpedanceFit:
    """A model calibrated on the calibration levels: its FMU parameters and errors (relative, RMS)."""

    effect: str
    params: dict
    free: list
    n_added: int
    calibration_error: float
    heldout_error: float
    evaluations: int


def split_levels(test: ImpedanceTest) -> tuple[list[int], list[int]]:
    """(calibration, held-out) level columns: the lowest and highest clamp velocity calibrate, the rest are
    held out; levels ordered by their mean clamp velocity amplitude [m/s]."""
    n = test.amplitudes.shape[1]
    if n < 3:
        raise DiagnoseError(f"{test.path}: a diagnosis on an impedance test needs at least three clamp-velocity "
                            f"levels (two to calibrate on, one held out between them); found {n}")
    velocity = (2 * np.pi * test.frequencies[:, None] * test.amplitudes).mean(axis=0)
    order = [int(j) for j in np.argsort(velocity)]
    return [order[0], order[-1]], order[1:-1]


def levels_of(test: ImpedanceTest, cols: list[int]) -> ImpedanceTest:
    """The test restricted to the level columns `cols`."""
    return ImpedanceTest(test.path, test.frequencies, test.amplitudes[:, cols], test.impedance[:, cols],
                         test.uncertainty)


def relative_error(z: np.ndarray, test: ImpedanceTest) -> float:
    """RMS over the test points of |z / Z_meas − 1|; inf if a run failed."""
    e = np.abs(z / test.impedance - 1)
    return float(np.sqrt(np.mean(e ** 2))) if np.all(np.isfinite(e)) else float("inf")


def _least_squares(fmu: str, test: ImpedanceTest, fixed: dict, starts: list[dict], bounds: dict, log: tuple,
                   budget: int) -> tuple[dict, int]:
    """The best of `starts` (one evaluation each), then least squares on the relative residuals within
    `bounds` (never worse than that start). Returns (parameters, evaluations)."""
    unit = UnitScaling(list(starts[0]), bounds, log)

    def residuals(x):
        return relative_residuals(model_impedance(fmu, test, {**fixed, **unit.values(x)}), test)

    xs = [unit.scaled(s) for s in starts]
    costs = [float(np.sum(residuals(x) ** 2)) for x in xs]
    result = polish(residuals, xs[int(np.argmin(costs))], budget=budget)
    return {**fixed, **unit.values(result.x)}, len(xs) + result.n_evaluations


def _fit_and_store(job: tuple) -> tuple[dict, int]:
    """_least_squares(*args) (in a worker), stored at once in `path` under `key`: an interrupted diagnosis
    keeps it."""
    args, path, key = job
    params, evaluations = _least_squares(*args)
    pathlib.Path(path).write_text(json.dumps({"key": key, "params": params, "evaluations": evaluations}, indent=1))
    return params, evaluations


def _stored(path: pathlib.Path, key: str) -> tuple[dict, int] | None:
    """A fit stored by _fit_and_store under the same key (same test, nominal and fit settings), or None."""
    if path.is_file():
        d = json.loads(path.read_text())
        if d.get("key") == key:
            return d["params"], d["evaluations"]
    return None


def deflection_scale(fmu: str, test: ImpedanceTest, params: dict, settle: float = 4.0) -> Scale:
    """Scale of the effects: RMS over the test points of cable end 1 relative to the clamp [m] and of its rate
    [m/s] (the calibrated nominal under each clamp sine, after `settle` s), the arm's tip stiffness, and the force
    a stuck joint transmits (systems.damper_stuck_force: the heavier mass at the clamp's peak acceleration)."""
    specs = [RunSpec(fmu, settle + 2.0 / f, 1.0 / (40 * f), ("x1", "x_clamp"),
                     {**params, "exc_type": 1, "exc_amplitude": float(a), "exc_f_start": float(f), "exc_t_ramp": 1.5})
             for f, row in zip(test.frequencies, test.amplitudes) for a in row]
    rms = []
    for r in run_batch(specs, workers=1, progress=False):
        if not r.ok:
            raise DiagnoseError(f"{test.path}: the calibrated nominal damper fails under the test's clamp sines "
                                f"({r.message})")
        rel = (r["x1"] - r["x_clamp"])[-80:]  # the last two periods
        rms.append(float(np.sqrt(np.mean(rel ** 2))))
    omega = 2 * np.pi * np.repeat(test.frequencies, test.amplitudes.shape[1])
    rms = np.array(rms)
    peak_acc = max(float(np.max((2 * np.pi * f) ** 2 * np.abs(row))) for f, row in zip(test.frequencies,
                                                                                       test.amplitudes))
    return Scale(float(np.sqrt(np.mean(rms ** 2))), float(np.sqrt(np.mean((omega * rms) ** 2))),
                 damper_stiffness(params), dict(params), damper_stuck_force(params, peak_acc))


def _strength_starts(effect, scale: Scale) -> list[dict]:
    """The effect's start and its strengths moved STRENGTH_STEPS of the way towards each bound (shape
    parameters kept at their start)."""
    ranges = {p.name: p.range(scale) for p in effect.params}
    shape = {p.name for p in effect.params if p.shape}
    first = {n: st for n, (lo, st, hi) in ranges.items()}
    starts = [first]
    for step in STRENGTH_STEPS:
        for bound in (2, 0):  # index of the upper, then the lower bound in (lower, start, upper)
            s = {n: r[1] if n in shape else r[1] + step * (r[bound] - r[1]) for n, r in ranges.items()}
            if s not in starts:
                starts.append(s)
    return starts


def diagnose_impedance(csv_path, out_dir, cfg: DiagnoseConfig | None = None, fmu_dir="fmus",
                       nominal: NominalModel | str | None = None, uncertainty: float | None = None,
                       workers: int | None = None) -> dict:
    """Diagnose a damper's impedance test against the nominal damper (a NominalModel or TOML file; None: the
    theory §1.3 damper); `uncertainty`: the test's relative measurement error (RMS of |Z_meas / Z_true − 1|;
    None: the value its sidecar states). The effects are refitted in parallel on `workers` processes (None:
    one per core); finished fits are kept in OUT/fits/ (a rerun with the same OUT redoes only the unfinished
    ones). Writes OUT/report.json, OUT/report.md and the impedance figures; returns the report."""
    cfg = cfg or DiagnoseConfig()
    test = read_impedance(csv_path)
    uncertainty = test.uncertainty if uncertainty is None else uncertainty
    if uncertainty is None or not 0 < uncertainty < 1:
        raise DiagnoseError(f"{test.path}: the test's measurement uncertainty is {uncertainty}; an impedance table "
                            "carries no noise to estimate it from: state it (`uncertainty` in the sidecar or "
                            "--uncertainty), the relative error, 0 < uncertainty < 1")
    cal_cols, held_cols = split_levels(test)
    cal, held = levels_of(test, cal_cols), levels_of(test, held_cols)
    fmu = str(ensure_fmu("DamperElement", pathlib.Path(fmu_dir)))
    runner = FmuRunner(fmu)
    described = load_nominal(nominal) if isinstance(nominal, (str, pathlib.Path)) else nominal
    if described is not None:
        if described.family != "damper":
            raise DiagnoseError(f"{described.path}: [nominal.family] = '{described.family}'; an impedance test is "
                                "of a damper")
        described.check_against(runner.parameters())
    defaults = fmu_defaults(runner)
    system = make_system("damper", defaults, described)
    runner.close()
    unknown = [e for e in (cfg.effects or []) if e not in system.effects]
    if unknown:
        raise DiagnoseError(f"effects: '{unknown[0]}' unknown for the damper; allowed: {', '.join(system.effects)}")

    def judged(name, params, free, n_added, evaluations) -> ImpedanceFit:
        return ImpedanceFit(name, {k: float(v) for k, v in params.items()}, free, n_added,
                            relative_error(model_impedance(fmu, cal, params), cal),
                            relative_error(model_impedance(fmu, held, params), held), evaluations)

    start = system.start([])
    starts = [start] + [{**start, system.stiffness: start[system.stiffness] * f} for f in STIFFNESS_SCAN if f != 1]
    bounds = {n: (min(system.bounds(s)[n][0] for s in starts), max(system.bounds(s)[n][1] for s in starts))
              for n in start}
    out = pathlib.Path(out_dir)
    (out / "fits").mkdir(parents=True, exist_ok=True)
    description = ({"fixed": described.fixed, "free": {k: asdict(v) for k, v in described.free.items()}}
                   if described else {})
    key = hashlib.sha256(test.path.read_bytes() + test.path.with_suffix(".toml").read_bytes() + json.dumps(
        [cfg.nominal_budget, cfg.refit_budget, description], sort_keys=True).encode()).hexdigest()[:16]
    nominal_path = out / "fits" / "nominal.json"
    params, n_eval = _stored(nominal_path, key) or _fit_and_store(
        ((fmu, cal, dict(system.nominal_fixed), starts, bounds, (), cfg.nominal_budget), nominal_path, key))
    nominal_fit = judged("nominal", params, list(start), 0, n_eval)
    floor, gap = uncertainty, nominal_fit.heldout_error
    significant = gap > max(cfg.noise_factor * floor, floor + cfg.min_gap)
    nominal_fits = nominal_fit.calibration_error <= cfg.nominal_max_nrmse
    fits = {}
    if significant and nominal_fits:
        scale = deflection_scale(fmu, cal, {**defaults, **nominal_fit.params})
        free, jobs = {}, []
        # an impedance table carries no time signals: effects on the recorded channels do not apply
        for name in cfg.effects or [n for n, e in system.effects.items() if not e.signal_only]:
            effect, path = system.effects[name], out / "fits" / f"{name}.json"
            e_start, e_bounds, e_fixed = effect_start(system, effect, scale, nominal_fit.params)
            free[name], stored = list(e_start), _stored(path, key)
            if stored:
                fits[name] = judged(name, stored[0], free[name], effect.strengths, stored[1])
                continue
            tries = [{**e_start, **s} for s in _strength_starts(effect, scale) + effect.starts(scale)]
            jobs.append(((fmu, cal, {**system.nominal_fixed, **e_fixed}, tries, e_bounds,
                          tuple(p.name for p in effect.params if p.log), cfg.refit_budget), path, key))
        for job, (params, n_eval) in zip(jobs, map_tasks(_fit_and_store, jobs, workers, progress=False)):
            name = job[1].stem
            fits[name] = judged(name, params, free[name], system.effects[name].strengths, n_eval)
    ranking = []
    # the reference of the shrink: the stated uncertainty, or the best held-out misfit if smaller
    reference = min([floor] + [fit.heldout_error for fit in fits.values()])
    for name, fit in fits.items():
        shrink = 100.0 * (gap - fit.heldout_error) / (gap - reference) if gap > reference else 0.0
        explains = (shrink >= cfg.min_shrink_pct
                    and fit.heldout_error <= selection.explained_below(floor, cfg.explain_factor,
                                                                      cfg.explain_margin))
        ranking.append({"effect": name, "score": shrink - 5.0 * (fit.n_added - 1), "shrink_pct": shrink,
                        "heldout_error_after": fit.heldout_error, "calibration_error": fit.calibration_error,
                        "explains": bool(explains), "n_added_params": fit.n_added,
                        "params": {n: fit.params[n] for n in fit.free}, "evaluations": fit.evaluations})
    ranking.sort(key=lambda d: -d["score"])
    if not nominal_fits:
        verdict = "nominal model does not fit"
    elif not significant:
        verdict = "no significant gap"
    elif ranking and ranking[0]["explains"]:
        verdict = f"gap explained by {ranking[0]['effect']}"
    else:
        verdict = "gap not explained by the candidate effects"
    z_nom = model_impedance(fmu, test, nominal_fit.params)
    by_frequency = np.sqrt(np.mean(np.abs(z_nom[:, held_cols] / test.impedance[:, held_cols] - 1) ** 2, axis=1))
    velocity = 2 * np.pi * test.frequencies[:, None] * test.amplitudes
    result = {"test": str(test.path), "verdict": verdict,
              "chosen_effect": ranking[0]["effect"] if verdict.startswith("gap explained") else None,
              "uncertainty": floor, "shrink_reference": reference, "heldout_error_nominal": gap,
              "significant": bool(significant),
              "calibration_levels_m_s": [float(velocity[:, j].mean()) for j in cal_cols],
              "heldout_levels_m_s": [float(velocity[:, j].mean()) for j in held_cols],
              "nominal": asdict(nominal_fit),
              "by_frequency": [{"frequency_hz": float(f), "heldout_error": float(e)}
                               for f, e in zip(test.frequencies, by_frequency)],
              "ranking": ranking}
    models = {"nominal": z_nom}
    if ranking:
        best = ranking[0]["effect"]
        models[f"with {best}"] = model_impedance(fmu, test, fits[best].params)
    plots.impedance_curves(out, test, models, test.path.stem)
    (out / "report.json").write_text(json.dumps(result, indent=1))
    (out / "report.md").write_text(report_markdown(result, cfg))
    return result


def report_markdown(rep: dict, cfg: DiagnoseConfig) -> str:
    """The report of diagnose_impedance as Markdown."""
    floor = rep["uncertainty"]

    def mm_s(levels):
        return ", ".join(f"{v * 1e3:.3g}" for v in levels)

    lines = [f"# Gap diagnosis on an impedance test: {pathlib.Path(rep['test']).name}", "",
             f"**Verdict: {rep['verdict']}.**", "",
             f"Calibrated on the clamp-velocity levels {mm_s(rep['calibration_levels_m_s'])} mm/s; held out: "
             f"{mm_s(rep['heldout_levels_m_s'])} mm/s.", "",
             "Held-out misfit of the nominal damper (RMS of |Z_model/Z_meas − 1|): "
             f"**{rep['heldout_error_nominal']:.4f}**; calibration misfit {rep['nominal']['calibration_error']:.4f}; "
             f"the test's stated uncertainty {floor:.4f}. A gap counts above "
             f"{max(cfg.noise_factor * floor, floor + cfg.min_gap):.4f}; an effect explains it when its held-out "
             f"misfit is at most {selection.explained_below(floor, cfg.explain_factor, cfg.explain_margin):.4f} "
             "and it removes "
             f"at least {cfg.min_shrink_pct:.0f} % of the gap.", "",
             "Nominal: " + ", ".join(f"{n} = {rep['nominal']['params'][n]:.4g}" for n in rep["nominal"]["free"]), "",
             "## Where", "", "| frequency [Hz] | nominal held-out misfit |", "|---|---|"]
    lines += [f"| {d['frequency_hz']:g} | {d['heldout_error']:.4f} |" for d in rep["by_frequency"]]
    if rep["ranking"]:
        lines += ["", "## Which effect", "", "| effect | score | held-out misfit after | shrink [%] | added params | "
                  "fitted |", "|---|---|---|---|---|---|"]
        for r in rep["ranking"]:
            params = ", ".join(f"{k} = {v:.4g}" for k, v in r["params"].items())
            lines.append(f"| {r['effect']} | {r['score']:.1f} | {r['heldout_error_after']:.4f} | "
                         f"{r['shrink_pct']:.1f} | {r['n_added_params']} | {params} |")
        lines += ["", "Score = shrink − 5 points per added parameter beyond the first; shrink = (misfit before − "
                  f"after) / (misfit before − reference), reference {rep['shrink_reference']:.4f} = the smaller of "
                  "the uncertainty and the best misfit after."]
    lines += ["", "![|Z|](impedance_abs.png)", "", "![phase](impedance_phase.png)"]
    return "\n".join(lines) + "\n"
