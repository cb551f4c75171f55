"""The diagnosis run: dataset -> nominal calibration -> where (gap on held-out files) -> which (screening,
refits, the model search) -> how far (shrink) -> the Diagnosis and its report. Finished fits are stored under
OUT/fits/ with a key of the dataset and settings, so an interrupted diagnosis resumes from them."""
from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import pathlib
from dataclasses import asdict, dataclass

from pyfit.runtime.clock import StageClock
from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.linearize import linear_modes
from pyfit.runtime.examples import ensure_fmu
from pyfit.gap import band, confidence, judge, localise, polarity, proposal, report, selection, user_candidates
from pyfit.gap import simulate as sim
from pyfit.gap.attribute import Fit, effect_task, nominal_task, run_fit, screen
from pyfit.gap.config import JUDGING, DiagnoseConfig, DiagnoseError, load_config, settings_with_role
from pyfit.gap.dataset import Dataset, default_calibration, load as _load
from pyfit.gap.rate import AnalysisRate, drive_upsample
from pyfit.gap.result import Detection, Diagnosis, Gap
from pyfit.gap.search import ModelSearch, SearchContext, simulated_on
from pyfit.gap.store import fit_and_store, on_one_blas_thread, run_fits, stored
from pyfit.gap.systems import System, family_fmu, make_system
from pyfit.io.nominal import NominalModel, load_nominal

__all__ = ["DiagnoseConfig", "DiagnoseError", "Dataset", "default_calibration", "load_config", "prepare", "diagnose",
           "misfit_at", "fmu_defaults", "tried_effects", "with_drive", "run_fit", "fit_and_store"]


def tried_effects(system, cfg: DiagnoseConfig) -> list[str]:
    """The effects a diagnosis screens and refits: those `cfg.effects` names, else every effect of the system but
    the ones offered only on request (effect.Effect.opt_in)."""
    return cfg.effects or [n for n, e in system.effects.items() if not e.opt_in]


def with_drive(cfg: DiagnoseConfig, system, rate: AnalysisRate) -> DiagnoseConfig:
    """cfg with the FMU's drive grid set: its own upsample when it sets one, else the family's for the rate the
    records are analysed at (rate.drive_upsample)."""
    return cfg if cfg.upsample is not None else dataclasses.replace(cfg, upsample=drive_upsample(system.upsample,
                                                                                               rate))


def _detection(system, fits: dict, sims: dict, held, gap: Gap, scale, runner, cfg: DiagnoseConfig) -> Detection:
    """Whether the single effects' refits find a gap the nominal's held-out misfit left within the noise
    threshold: the refit that leaves the least held-out misfit, against the nominal's and against that refit's
    own linear values with its effect at zero or reduced to its linear part (Effect.linear_parts: what refitting
    the linear parameters alone buys, and a linear element where the effect acts), by selection.detected_by_refit
    with `cfg.min_detect_cut`. A change of the linear system itself (Effect.linear) does not count (its refit
    takes up the sensor chain's linear part as well): the refit of the others that leaves the least is taken."""
    after = {n: selection.heldout_nrmse(sims[n], held) for n in fits}
    best = min(after, key=lambda n: (system.effects[n].linear, after[n]))
    effect, refit = system.effects[best], fits[best].params
    parts = effect.linear_parts(refit)
    linear_only = min(selection.heldout_nrmse(simulated_on(runner, held, {**refit, **values}, system, cfg), held)
                      for values in [effect.absent(scale), *parts])
    before = min(gap.overall, linear_only)
    return Detection(best, after[best], linear_only, bool(parts), 1.0 - after[best] / before if before > 0 else 0.0,
                     cfg.min_detect_cut,
                     not effect.linear and selection.detected_by_refit(before, after[best], cfg.min_detect_cut))


def _check_signs(system, fmu: str, cal: list, cfg: DiagnoseConfig, nominal: Fit, best: float, data_dir,
                 workers) -> None:
    """Where the calibrated nominal fits no calibration file (`best`: its NRMSE on the one it fits best), whether
    it does once an output's sign is changed (pyfit.gap.polarity): DiagnoseError naming that output and the
    sidecar's fix, before any effect is tried."""
    if best <= cfg.nominal_max_nrmse:
        return
    change = polarity.sign_change(system, fmu, cal, cfg.nominal_budget, cfg.upsample, workers or os.cpu_count() or 1,
                                  cfg.nominal_max_nrmse)
    if change is None:
        return
    which = ", ".join(change.outputs)
    raise DiagnoseError(
        f"{data_dir}: the nominal model fits no calibration file as recorded (NRMSE {nominal.calibration_nrmse:.2f}) "
        f"but fits them with the sign of {which} changed (NRMSE {change.nrmse_changed:.2f}): "
        + ("every output's sign convention, or the input's, is" if change.every_output else
           "that sensor's sign convention is") + " the model's opposite; allowed: the model's convention, e.g. "
        f"`invert = true` on the column{'s' if len(change.outputs) > 1 else ''} recorded as {which} in every sidecar "
        "(or on the input's), once the sensor's mounting is checked")


def fmu_defaults(runner: FmuRunner) -> dict[str, float]:
    """The FMU's parameter start values (the .mo defaults), SI."""
    return {v.name: float(v.start) for v in runner.model_description.modelVariables
            if v.causality == "parameter" and v.start is not None and v.type == "Real"}


def _with_user_candidates(system, users, fmu_parameters: set):
    """The system with the user's declared candidates among its effects (checked against the FMU)."""
    for name, effect in users.effects.items():
        if name in system.effects:
            raise DiagnoseError(f"{users.path}: candidate '{name}' is a built-in candidate; give it another name")
        missing = [p for p in [q.name for q in effect.params] + list(effect.fixed(None)) if p not in fmu_parameters]
        if missing:
            raise DiagnoseError(f"{users.path}: candidate '{name}': '{missing[0]}' is not a parameter of the FMU "
                                f"({users.fmu or system.fmu}); allowed: {', '.join(sorted(fmu_parameters))}")
    return dataclasses.replace(system, effects={**system.effects, **users.effects})


@dataclass
class Prepared:
    """A diagnosis's inputs read and checked (prepare): the FMU and its runner, the system with the described
    nominal and the user's candidates, the dataset split, the settings asked for and those used (the drive's
    upsampling set), the excited band [Hz] and the nominal start's linear modes."""

    fmu: str
    runner: FmuRunner
    system: System
    described: NominalModel | None
    users: user_candidates.UserCandidates | None
    data: Dataset
    requested: DiagnoseConfig
    cfg: DiagnoseConfig
    band: tuple[float, float]
    modes: list


def prepare(model: str, data_dir, cfg: DiagnoseConfig, fmu_dir="fmus", nominal: NominalModel | str | None = None,
            candidates=None) -> Prepared:
    """Read and check everything a diagnosis takes before its first fit: the nominal description against the
    FMU, the user's candidates, the dataset against the FMU's variables and units, its split, and that the
    excited band holds a resonance of the nominal (or of a start from the measured peaks); DiagnoseError
    otherwise."""
    users = user_candidates.load(candidates) if isinstance(candidates, (str, pathlib.Path)) else candidates
    fmu = str(users.fmu) if users and users.fmu else str(ensure_fmu(family_fmu(model), pathlib.Path(fmu_dir)))
    runner = FmuRunner(fmu)
    described = load_nominal(nominal) if isinstance(nominal, (str, pathlib.Path)) else nominal
    if described is not None:
        if described.family != model:
            raise DiagnoseError(f"{described.path}: [nominal.family] = '{described.family}' but the diagnosis is "
                                f"of '{model}'")
        described.check_against(runner.parameters())
    system = make_system(model, fmu_defaults(runner), described)
    if users:
        system = _with_user_candidates(system, users, set(runner.parameter_names()))
    data = _load(data_dir, system, cfg, runner)
    lo, hi = localise.excited_range(data.records)
    modes = linear_modes(fmu, {**system.nominal_fixed, **system.start(data.cal)})

    def in_band(start):  # a start whose linear model has a resonance in the excited band
        return any(lo <= m.f_n <= hi for m in linear_modes(fmu, {**system.nominal_fixed, **start}))

    if modes and not any(lo <= m.f_n <= hi for m in modes) and \
            not any(in_band(s) for s in system.data_starts(data.cal, lambda p: linear_modes(fmu, p))):
        raise DiagnoseError(f"{data_dir}: the inputs excite {lo:.1f}-{hi:.1f} Hz but the nominal model's resonances "
                            f"are at {', '.join(f'{m.f_n:.1f}' for m in modes)} Hz and no start from the measured "
                            "resonance peaks moves one into that band; allowed: an excitation band that holds at "
                            "least one resonance (the data cannot calibrate the model otherwise)")
    return Prepared(fmu, runner, system, described, users, data, cfg, with_drive(cfg, system, data.rate), (lo, hi),
                    modes)


def _run_key(p: Prepared, model: str) -> str:
    """The key a run's stored fits are valid for: the data, the settings that change how a fit is made (not how
    results are judged), the model, its description, the user's candidates, the candidates' fitted parameters
    and the calibration files."""
    judging = set(settings_with_role(JUDGING))
    settings = json.dumps({k: v for k, v in asdict(p.cfg).items() if k not in judging}, sort_keys=True)
    described = p.described
    description = json.dumps({"fixed": described.fixed, "free": {k: asdict(v) for k, v in described.free.items()}}
                             if described else {}, sort_keys=True)
    declared = p.users.text + hashlib.sha256(pathlib.Path(p.fmu).read_bytes()).hexdigest() if p.users else ""
    coordinates = ";".join(f"{n}:{','.join(q.name for q in e.params)}" for n, e in p.system.effects.items())
    return hashlib.sha256((p.data.key + settings + model + description + declared + coordinates
                           + ",".join(r.name for r in p.data.cal)).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class Calibrated:
    """The calibrated nominal and what follows from it: the records with their simulations' time limits, the data
    scale, the nominal's simulations of every record, the bands [Hz] and the gap."""

    nominal: Fit
    records: list
    cal: list
    held: list
    scale: object
    sims: dict
    bands: list
    gap: Gap


def _calibrate(p: Prepared, out: pathlib.Path, key: str, workers, data_dir, clock: StageClock) -> Calibrated:
    """The nominal calibrated (or read from its stored fit), then where it misfits the held-out files."""
    system, cfg, runner, data = p.system, p.cfg, p.runner, p.data
    path = out / "fits" / "nominal.json"
    nominal = stored(path, key) or fit_and_store((nominal_task(
        system, p.fmu, data.cal, cfg.nominal_budget, cfg.upsample, threads=workers or os.cpu_count() or 1), path, key))
    # from here on a simulation that takes SLOW_FACTOR times the calibrated nominal's on the same record counts as
    # failed (a stiff parameter set the integrator crawls through: sim.with_time_limits)
    limited = {r.name: r for r in sim.with_time_limits(runner, data.records, nominal.params, cfg.upsample,
                                                       system.lead_periods)}
    records, cal, held = ([limited[r.name] for r in rs] for rs in (data.records, data.cal, data.held))
    clock.end("nominal calibration")
    deflections = []
    for r in cal:
        moved = sim.simulate(runner, r, nominal.params, cfg.upsample, system.lead_periods,
                             outputs=system.deflection_outputs)
        if moved is None:
            raise DiagnoseError(f"{r.name}: the calibrated nominal model fails on this file (parameters "
                                f"{ {n: nominal.params[n] for n in nominal.free} })")
        deflections.append(system.deflection(moved, r))
    scale = system.scale(deflections, cal[0].fs, nominal.params, cal)
    sims = simulated_on(runner, records, nominal.params, system, cfg)
    bands = [tuple(b) for b in cfg.bands_hz] if cfg.bands_hz else localise.default_bands(records)
    gap = judge.nominal_gap(sims, records, held, bands, cfg)
    _check_signs(system, p.fmu, cal, cfg, nominal, judge.best_calibration_nrmse(gap)[0], data_dir, workers)
    clock.end("where (nominal gap)")
    return Calibrated(nominal, records, cal, held, scale, sims, bands, gap)


def _screening(p: Prepared, c: Calibrated, out: pathlib.Path, key: str, effects: list) -> tuple[dict, dict]:
    """The screening's share of the nominal residual each effect's sensitivity explains, and the strengths its
    Gauss-Newton step reaches (stored as fits/screening.json)."""
    path = out / "fits" / "screening.json"
    kept = json.loads(path.read_text()) if path.is_file() else {}
    if kept.get("key") == key and "strengths" in kept:
        return kept["fractions"], kept["strengths"]
    shares, strengths = screen(p.system, p.fmu, c.cal, c.nominal, c.scale, p.cfg.upsample, effects)
    path.write_text(json.dumps({"key": key, "fractions": shares, "strengths": strengths}, indent=1))
    return shares, strengths


def _single_refits(p: Prepared, c: Calibrated, out, key, effects, strengths, workers, progress) -> dict[str, Fit]:
    """Each effect refitted beside the nominal (or read from its stored fit), also from the linear system where an
    amplitude-dependent effect is weakest: the lowest calibration level's."""
    system, cfg = p.system, p.cfg
    lowest = min(c.cal, key=lambda r: r.level_value)
    linear_starts = tuple(system.data_starts([lowest], lambda q: linear_modes(p.fmu, q),
                                             {n: c.nominal.params[n] for n in system.linear}))
    fits, jobs = {}, []
    for name in effects:
        path = out / "fits" / f"{name}.json"
        fits[name] = stored(path, key)
        if fits[name] is None:
            jobs.append((effect_task(system, system.effects[name], p.fmu, c.cal, c.nominal, c.scale, cfg.refit_budget,
                                     cfg.upsample, strengths.get(name), linear_starts), str(path), key))
    jobs.sort(key=lambda job: job[0].basin is None)  # the longest (a refit from each basin) first
    for fit in run_fits(jobs, workers or os.cpu_count() or 1, workers, progress, "refits"):
        fits[fit.effect] = fit
    return fits


@dataclass(frozen=True)
class Which:
    """What the refits and the model search found: the system with the combinations tried, every model's fit and
    held-out simulations, the screening's shares, the gap (with the refits' detection) and the model selected."""

    system: System
    fits: dict
    sims: dict
    screening: dict
    gap: Gap
    selected: str | None


def _which(p: Prepared, c: Calibrated, out, key, workers, progress, clock: StageClock) -> Which:
    """Screening, single refits, and the model search where the gap is significant. Nothing to attribute when the
    nominal fits the held-out files within the noise threshold, unless cfg.refit_within_noise: an effect too weak
    for that threshold is still told from noise when its refit removes part of the held-out misfit."""
    system, cfg, gap = p.system, p.cfg, c.gap
    if not (gap.significant or cfg.refit_within_noise):
        return Which(system, {}, {}, {}, gap, None)
    effects = tried_effects(system, cfg)
    screening, strengths = _screening(p, c, out, key, effects)
    clock.end("screening")
    fits = _single_refits(p, c, out, key, effects, strengths, workers, progress)
    sims = {name: simulated_on(p.runner, c.held, f.params, system, cfg) for name, f in fits.items()}
    clock.end("refits with each effect")
    if not gap.significant:
        detection = _detection(system, fits, sims, c.held, gap, c.scale, p.runner, cfg)
        gap = dataclasses.replace(gap, detection=detection, significant=detection.detected)
    selected = None
    if gap.significant:
        ctx = SearchContext(system, cfg, p.fmu, p.runner, c.cal, c.held, c.nominal, c.scale, gap, screening, out, key,
                            workers, progress)
        system, selected = ModelSearch(ctx, fits, sims).run()
    clock.end("combinations of effects")
    return Which(system, fits, sims, screening, gap, selected)


def _judged(p: Prepared, c: Calibrated, w: Which, model: str, data_dir, clock: StageClock) -> Diagnosis:
    """The Diagnosis: the judgement (judge.assemble; with the best model's prediction band where it decides), the
    stated confidence, where two close leaders differ, the test that would decide where the report is not decisive
    (proposal.next_test), and what the data were."""
    cfg, sims = p.cfg, {"nominal": c.sims, **w.sims}
    args = (w.system, cfg, c.records, c.cal, c.held, c.nominal, w.fits, sims, w.screening, c.bands, c.scale, w.gap,
            w.selected)
    d = judge.assemble(*args)
    banded = judge.needs_band(d, cfg.min_shrink_pct)
    if banded:  # a confined misfit: does the best prediction the calibration files allow meet the criterion?
        within = band.prediction_band(p.runner, w.fits[banded], w.system.effects[banded].derived(c.scale), c.cal,
                                      c.held, cfg.upsample, w.system.lead_periods)
        d = judge.assemble(*args, within)
        clock.end("prediction band")
    calibration = confidence.load(confidence.settings_of(asdict(p.requested)), model)  # of the settings asked for
    stated = confidence.stated(d.verdict.value, d.chosen_name, d.best.shrink_pct if d.best else None, calibration)
    separation = judge.separation(p.runner, d, c.records, w.fits, c.bands, cfg.upsample, w.system.lead_periods)
    clock.end("verdict")
    proposed = proposal.next_test(p.runner, d, c.records, cfg.upsample, w.system.lead_periods,
                                  bool(w.system.motion_inputs))
    p.runner.close()
    if proposed:
        clock.end("next test")
    data = p.data
    return dataclasses.replace(
        d, source=str(data_dir), confidence=stated, separation=separation, next_test=proposed,
        level_order=data.order,
        set_aside={name: {"period_scatter": s, "lower_floor": f} for name, (s, f) in data.aside.items()},
        voltage_channels=tuple(data.voltages), clipped_channels=data.clipped,
        analysis_rate={**asdict(data.rate), "drive_upsample": cfg.upsample, "recorded_hz": data.recorded_hz},
        compared_from_hz={r.name: r.compared_from_hz for r in c.records if r.compared_from_hz},
        stage_s=dict(clock.stages), figures=report.figures_for(c.records, d.nominal.params))


@on_one_blas_thread
def diagnose(model: str, data_dir, out_dir, cfg: DiagnoseConfig | None = None, fmu_dir="fmus",
             workers: int | None = None, progress: bool = True, nominal: NominalModel | str | None = None,
             candidates=None) -> Diagnosis:
    """Diagnose the dataset against the nominal model `model` ('sdof' or 'damper'); writes OUT/report.json,
    OUT/report.md and figures; returns the Diagnosis. `nominal`: the user's description of the nominal model (a
    NominalModel or a TOML file, pyfit.io.nominal; None: the FMU's defaults). `candidates`: the user's declared
    candidate effects (pyfit.gap.user_candidates, or its TOML file), ranked with the built-in ones."""
    clock = StageClock()
    p = prepare(model, data_dir, cfg or DiagnoseConfig(), fmu_dir, nominal, candidates)
    clock.end("reading and checking the data")
    out = pathlib.Path(out_dir)
    (out / "fits").mkdir(parents=True, exist_ok=True)
    key = _run_key(p, model)
    c = _calibrate(p, out, key, workers, data_dir, clock)
    w = _which(p, c, out, key, workers, progress, clock)
    d = _judged(p, c, w, model, data_dir, clock)
    report.write(d, c.records, c.held, {"nominal": c.sims, **w.sims}, c.bands, out)
    return d


@dataclass(frozen=True)
class SplitMisfit:
    """One parameter set's NRMSE on a dataset as `diagnose` splits it: RMS over the held-out files and over the
    calibration files (inf when a simulation fails)."""

    held_out: float
    calibration: float


def misfit_at(model: str, data_dir, params: dict, cfg: DiagnoseConfig | None = None, fmu_dir="fmus",
              nominal: NominalModel | str | None = None) -> SplitMisfit:
    """The FMU of `model` at `params` (over the described nominal's fixed values and the FMU's defaults) on the
    files of `data_dir`, split into calibration and held-out files as `diagnose` splits them with `cfg`: e.g. a
    known truth's misfit, which tells a miss the data cannot decide from a miss of the search."""
    p = prepare(model, data_dir, cfg or DiagnoseConfig(), fmu_dir, nominal)
    try:
        values = {**p.system.nominal_fixed, **params}
        return SplitMisfit(*(selection.heldout_nrmse(simulated_on(p.runner, files, values, p.system, p.cfg), files)
                             for files in (p.data.held, p.data.cal)))
    finally:
        p.runner.close()
