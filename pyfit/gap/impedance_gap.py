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
from pyfit.gap import judge, selection
from pyfit.gap.diagnose import DiagnoseConfig, DiagnoseError, fmu_defaults
from pyfit.gap.result import BandMisfit, Diagnosis, Gap, LevelMisfit, ModelFit, NominalFit, Verdict
from pyfit.gap.effect import Scale
from pyfit.gap.systems import damper_stiffness, damper_stuck_force, make_system
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


def _read_test(csv_path, uncertainty: float | None) -> tuple[ImpedanceTest, float]:
    """The impedance test and its relative measurement uncertainty (`uncertainty`, else its sidecar's)."""
    test = read_impedance(csv_path)
    uncertainty = test.uncertainty if uncertainty is None else uncertainty
    if uncertainty is None or not 0 < uncertainty < 1:
        raise DiagnoseError(f"{test.path}: the test's measurement uncertainty is {uncertainty}; an impedance table "
                            "carries no noise to estimate it from: state it (`uncertainty` in the sidecar or "
                            "--uncertainty), the relative error, 0 < uncertainty < 1")
    return test, uncertainty


def _damper(fmu: str, nominal, cfg: DiagnoseConfig):
    """The damper system (with the user's description), the FMU's defaults and the description."""
    runner = FmuRunner(fmu)
    described = load_nominal(nominal) if isinstance(nominal, (str, pathlib.Path)) else nominal
    if described is not None:
        if described.family != "damper":
            raise DiagnoseError(f"{described.path}: [nominal.family] = '{described.family}'; an impedance test is "
                                "of a damper")
        described.check_against(runner.parameters())
    defaults = fmu_defaults(runner)
    runner.close()
    system = make_system("damper", defaults, described)
    unknown = [e for e in (cfg.effects or []) if e not in system.effects]
    if unknown:
        raise DiagnoseError(f"effects: '{unknown[0]}' unknown for the damper; allowed: {', '.join(system.effects)}")
    return system, defaults, described


@dataclass(frozen=True)
class ImpedanceRun:
    """One impedance diagnosis's inputs: the FMU, the test, its calibration and held-out levels, the system, the
    settings, where fits are stored (OUT/fits) and their key, the workers."""

    fmu: str
    test: ImpedanceTest
    cal: ImpedanceTest
    held: ImpedanceTest
    system: object
    cfg: DiagnoseConfig
    fits_dir: pathlib.Path
    key: str
    workers: int | None

    def judged(self, name, params, free, n_added, evaluations) -> ImpedanceFit:
        """A fit's errors on the calibration and held-out levels."""
        return ImpedanceFit(name, {k: float(v) for k, v in params.items()}, free, n_added,
                            relative_error(model_impedance(self.fmu, self.cal, params), self.cal),
                            relative_error(model_impedance(self.fmu, self.held, params), self.held), evaluations)


def _nominal(r: ImpedanceRun) -> ImpedanceFit:
    """The nominal damper calibrated on the calibration levels (from its start and the stiffness scan)."""
    system = r.system
    start = system.start([])
    starts = [start] + [{**start, system.stiffness: start[system.stiffness] * f} for f in STIFFNESS_SCAN if f != 1]
    bounds = {n: (min(system.bounds(s)[n][0] for s in starts), max(system.bounds(s)[n][1] for s in starts))
              for n in start}
    path = r.fits_dir / "nominal.json"
    params, n_eval = _stored(path, r.key) or _fit_and_store(
        ((r.fmu, r.cal, dict(system.nominal_fixed), starts, bounds, (), r.cfg.nominal_budget), path, r.key))
    return r.judged("nominal", params, list(start), 0, n_eval)


def _effect_fits(r: ImpedanceRun, nominal: ImpedanceFit, defaults: dict) -> dict[str, ImpedanceFit]:
    """Each candidate effect refitted on the calibration levels (an impedance table carries no time signals:
    effects on the recorded channels do not apply)."""
    system, fits, free, jobs = r.system, {}, {}, []
    scale = deflection_scale(r.fmu, r.cal, {**defaults, **nominal.params})
    for name in r.cfg.effects or [n for n, e in system.effects.items() if not e.signal_only]:
        effect, path = system.effects[name], r.fits_dir / f"{name}.json"
        e_start, e_bounds, e_fixed = effect_start(system, effect, scale, nominal.params)
        free[name], kept = list(e_start), _stored(path, r.key)
        if kept:
            fits[name] = r.judged(name, kept[0], free[name], effect.strengths, kept[1])
            continue
        tries = [{**e_start, **s} for s in _strength_starts(effect, scale) + effect.starts(scale)]
        jobs.append(((r.fmu, r.cal, {**system.nominal_fixed, **e_fixed}, tries, e_bounds,
                      tuple(p.name for p in effect.params if p.log), r.cfg.refit_budget), path, r.key))
    for job, (params, n_eval) in zip(jobs, map_tasks(_fit_and_store, jobs, r.workers, progress=False)):
        name = job[1].stem
        fits[name] = r.judged(name, params, free[name], system.effects[name].strengths, n_eval)
    return fits


def _ranking(fits: dict, before: float, reference: float, explained_below: float, cfg) -> list[ModelFit]:
    """The refitted effects by score: the shrink of the held-out misfit less 5 points per added strength."""
    ranking = []
    for name, fit in fits.items():
        shrink = selection.shrink_pct(before, fit.heldout_error, reference)
        ranking.append(ModelFit(
            name, (name,), selection.score(before, fit.heldout_error, reference, fit.n_added), before,
            fit.heldout_error, shrink, {n: fit.params[n] for n in fit.free}, fit.n_added, fit.calibration_error,
            fit.evaluations, selection.explains(shrink, fit.heldout_error, explained_below, cfg.min_shrink_pct),
            values=dict(fit.params)))
    return sorted(ranking, key=lambda d: -d.score)


def _impedance_gap(r: ImpedanceRun, z_nom: np.ndarray, cal_cols, held_cols, floor: float, before: float,
                   reference: float) -> Gap:
    """Where the nominal misfits: by frequency on the held-out levels and by level (relative errors)."""
    test, cfg = r.test, r.cfg
    error = np.abs(z_nom / test.impedance - 1) ** 2
    by_frequency = np.sqrt(np.mean(error[:, held_cols], axis=1))
    velocity = (2 * np.pi * test.frequencies[:, None] * test.amplitudes).mean(axis=0)
    worst = float(test.frequencies[int(np.argmax(by_frequency))])
    return Gap(
        overall=before, noise_floor=floor, noise_floor_scaled=floor, noise_floor_method=("stated uncertainty",),
        significant=bool(selection.significant(before, floor, cfg.noise_factor, cfg.min_gap)),
        worst_band_hz=(worst, worst),
        by_band=tuple(BandMisfit((float(f), float(f)), float(e)) for f, e in zip(test.frequencies, by_frequency)),
        by_level=tuple(LevelMisfit(test.path.stem, f"{velocity[j] * 1e3:.3g} mm/s", float(velocity[j]),
                                   j in held_cols, float(np.sqrt(np.mean(error[:, j]))), floor)
                       for j in sorted(cal_cols + held_cols, key=lambda j: velocity[j])),
        shrink_reference=reference, metric="relative impedance error")


def diagnose_impedance(csv_path, out_dir, cfg: DiagnoseConfig | None = None, fmu_dir="fmus",
                       nominal: NominalModel | str | None = None, uncertainty: float | None = None,
                       workers: int | None = None) -> Diagnosis:
    """Diagnose a damper's impedance test against the nominal damper (a NominalModel or TOML file; None: the
    FMU's damper); `uncertainty`: the test's relative measurement error (RMS of |Z_meas / Z_true − 1|; None: the
    value its sidecar states). The effects are refitted on `workers` processes (None: one per core); finished
    fits are kept in OUT/fits/. Writes OUT/report.json, OUT/report.md and the impedance figures."""
    cfg = cfg or DiagnoseConfig()
    test, floor = _read_test(csv_path, uncertainty)
    cal_cols, held_cols = split_levels(test)
    fmu = str(ensure_fmu("DamperElement", pathlib.Path(fmu_dir)))
    system, defaults, described = _damper(fmu, nominal, cfg)
    out = pathlib.Path(out_dir)
    (out / "fits").mkdir(parents=True, exist_ok=True)
    description = ({"fixed": described.fixed, "free": {k: asdict(v) for k, v in described.free.items()}}
                   if described else {})
    key = hashlib.sha256(test.path.read_bytes() + test.path.with_suffix(".toml").read_bytes() + json.dumps(
        [cfg.nominal_budget, cfg.refit_budget, description], sort_keys=True).encode()).hexdigest()[:16]
    r = ImpedanceRun(fmu, test, levels_of(test, cal_cols), levels_of(test, held_cols), system, cfg, out / "fits",
                     key, workers)
    nominal_fit = _nominal(r)
    before = nominal_fit.heldout_error
    significant = selection.significant(before, floor, cfg.noise_factor, cfg.min_gap)
    nominal_fits = nominal_fit.calibration_error <= cfg.nominal_max_nrmse
    fits = _effect_fits(r, nominal_fit, defaults) if significant and nominal_fits else {}
    reference = min([floor] + [fit.heldout_error for fit in fits.values()])
    explained_below = selection.explained_below(floor, cfg.explain_factor, cfg.explain_margin)
    z_nom = model_impedance(fmu, test, nominal_fit.params)
    gap = _impedance_gap(r, z_nom, cal_cols, held_cols, floor, before, reference)
    ranking = _ranking(fits, before, reference, explained_below, cfg)
    verdict = judge.verdict(gap, ranking[0] if ranking else None, nominal_fits)
    d = Diagnosis("damper", fmu, str(test.path), verdict, (ranking[0].effect,) if verdict is Verdict.EXPLAINED else (),
                  explained_below, gap, tuple(ranking), (),
                  NominalFit({n: nominal_fit.params[n] for n in nominal_fit.free}, nominal_fit.calibration_error,
                             nominal_fit.evaluations, dict(nominal_fit.params)),
                  tuple(v.level for v in gap.by_level if not v.held_out),
                  tuple(v.level for v in gap.by_level if v.held_out))
    models = {"nominal": z_nom}
    if ranking:
        models[f"with {ranking[0].effect}"] = model_impedance(fmu, test, fits[ranking[0].effect].params)
    plots.impedance_curves(out, test, models, test.path.stem)
    (out / "report.json").write_text(json.dumps(d.to_json(), indent=1))
    (out / "report.md").write_text(report_markdown(d, cfg))
    return d


def report_markdown(d: Diagnosis, cfg: DiagnoseConfig) -> str:
    """The report of diagnose_impedance as Markdown."""
    g, floor = d.gap, d.gap.noise_floor
    lines = [f"# Gap diagnosis on an impedance test: {pathlib.Path(d.source).name}", "",
             f"**Verdict: {d.sentence}.**", "",
             f"Calibrated on the clamp-velocity levels {', '.join(d.calibration_files)}; held out: "
             f"{', '.join(d.held_out_files)}.", "",
             "Held-out misfit of the nominal damper (RMS of |Z_model/Z_meas − 1|): "
             f"**{g.overall:.4f}**; calibration misfit {d.nominal.calibration_nrmse:.4f}; "
             f"the test's stated uncertainty {floor:.4f}. A gap counts above "
             f"{selection.noise_level(floor, cfg.noise_factor, cfg.min_gap):.4f}; an effect explains it when its "
             f"held-out misfit is at most {d.explained_below:.4f} and it removes at least {cfg.min_shrink_pct:.0f} % "
             "of the gap.", "",
             "Nominal: " + ", ".join(f"{n} = {v:.4g}" for n, v in d.nominal.params.items()), "",
             "## Where", "", "| frequency [Hz] | nominal held-out misfit |", "|---|---|"]
    lines += [f"| {b.band_hz[0]:g} | {b.nrmse:.4f} |" for b in g.by_band]
    if d.ranking:
        lines += ["", "## Which effect", "", "| effect | score | held-out misfit after | shrink [%] | added params | "
                  "fitted |", "|---|---|---|---|---|---|"]
        for r in d.ranking:
            params = ", ".join(f"{k} = {v:.4g}" for k, v in r.params.items())
            lines.append(f"| {r.effect} | {r.score:.1f} | {r.heldout_gap_after:.4f} | {r.shrink_pct:.1f} | "
                         f"{r.n_added_params} | {params} |")
        lines += ["", "Score = shrink − 5 points per added parameter beyond the first; shrink = (misfit before − "
                  f"after) / (misfit before − reference), reference {g.shrink_reference:.4f} = the smaller of "
                  "the uncertainty and the best misfit after."]
    lines += ["", "![|Z|](impedance_abs.png)", "", "![phase](impedance_phase.png)"]
    return "\n".join(lines) + "\n"
