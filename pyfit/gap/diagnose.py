"""The diagnosis run: dataset -> nominal calibration -> where (gap on held-out files) -> which (screening,
refits, ranking) -> how far (shrink) -> report. Finished fits are stored under OUT/fits/ with a key of the
dataset and settings, so an interrupted diagnosis resumes from them."""
from __future__ import annotations

import hashlib
import json
import os
import pathlib
import dataclasses
import functools
import itertools
from dataclasses import asdict, dataclass, fields

import threadpoolctl

from pyfit.runtime.batch import map_tasks
from pyfit.runtime.clock import StageClock
from pyfit.analysis.signals import clipped_samples
from pyfit.io.data import MeasurementError, check_quantities, read_dataset_with_order
from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.linearize import linear_modes
from pyfit.runtime.examples import ensure_fmu
from pyfit.io.schema import ConfigError, check_sections, check_table, fail, read_toml
from pyfit.gap import band, confidence, localise, polarity, selection, user_candidates
from pyfit.gap import simulate as sim
from pyfit.gap.attribute import STRENGTH_FACTORS, Fit, effect_task, nominal_task, pinned, run_fit, screen
from pyfit.gap.rate import AnalysisRate, analysis_rate, at_rate, common_rate, drive_upsample
from pyfit.gap.systems import System, combine, family_fmu, make_system, strength_grid
from pyfit.io.nominal import NominalModel, load_nominal


class DiagnoseError(ConfigError):
    """Bad input to a diagnosis; names the file and field and what is allowed."""


@dataclass
class DiagnoseConfig:
    """Settings of a diagnosis (all optional)."""

    effects: list | None = None  # candidate effects to test (default: all of the system's)
    calibration: list | None = None  # file stems to calibrate on (default: default_calibration)
    bands_hz: list | None = None  # [[lo, hi], ...] (default: localise.default_bands, 8 over the excited range)
    nominal_budget: int = 60  # FMU evaluations of the nominal calibration
    refit_budget: int = 120  # FMU evaluations per refit with an effect
    upsample: int | None = None  # FMU input grid = analysis rate x upsample (None: the family's System.upsample, for
    # a file faster than pyfit.gap.rate.REFERENCE_HZ the fewer its rate needs: rate.drive_upsample)
    transient_s: float = 4.0  # a record that does not start at rest: seconds simulated from rest, not compared
    min_gap: float = 0.005  # NRMSE a gap must exceed beyond the noise floor to count
    noise_factor: float = 1.2  # ... and the noise floor times this
    close_points: float = 15.0  # runner-up within this many score points: reported as close
    min_shrink_pct: float = 50.0  # the best effect must shrink the gap by this much to be chosen
    explain_factor: float = 3.0  # ... and bring the held-out NRMSE within explain_factor x the noise floor
    explain_margin: float = 0.02  # ... or within the floor + explain_margin (the absolute criterion)
    nominal_max_nrmse: float = 0.8  # a nominal whose NRMSE on its best calibration file exceeds this "does not fit"
    max_effects: int = 2  # effects combined at most (forward selection, while the misfit is above the noise)
    partners: int = 4  # candidates tried as the next member of a combination (by the screening at that model)
    beam: int = 2  # single effects the forward selection starts from (the best-scoring ones)
    min_excess_cut: float = 0.5  # share of the misfit above the noise floor a larger combination must remove
    combination_probes: int = 3  # a combination's best starts each refitted a while before the best goes on
    combination_min_gap: float = 0.0  # NRMSE a model's held-out misfit must exceed beyond the floor to add a member
    extend_factor: float = 1.1  # ... and the floor (should the noise grow) times this: a weaker test than the
    # nominal's noise_factor (a pair whose single member lands just above the noise is still extended)
    min_partner_explained: float = 0.005  # a model meeting the absolute criterion is extended only when a
    # candidate's sensitivity explains this share of its calibration residual (the screening at that model)
    grid_models: int = 3  # when no model meets the absolute criterion: the best ones by held-out misfit, each
    # refitted from the best point of a grid over its members' strengths (systems.strength_grid)
    refit_within_noise: bool = True  # refit the single effects also when the nominal's held-out misfit is
    # within the noise threshold (an effect too weak for the nominal's test told from noise by its refit; false:
    # the nominal's test alone decides, and a dataset without a gap costs no refits)
    min_detect_cut: float = 0.05  # with refit_within_noise: the gap counts when a single effect's refit removes
    # this share of the held-out misfit (selection.detected_by_refit; against the nominal's and against the refit's
    # own linear values with the effect at zero or reduced to its linear part)


_SPEC = {f.name: ((list if f.name in ("effects", "calibration", "bands_hz") else
                   bool if isinstance(f.default, bool) else
                   int if f.name in ("nominal_budget", "refit_budget", "upsample", "max_effects", "partners",
                                 "combination_probes", "grid_models")
                   else "number"), False, f.default)
         for f in fields(DiagnoseConfig)}


def load_config(path) -> DiagnoseConfig:
    """A DiagnoseConfig from the [diagnose] table of a TOML file; one clear error per problem."""
    path = pathlib.Path(path)
    raw = read_toml(path, DiagnoseError)
    check_sections(raw, path, ("diagnose",), error=DiagnoseError)
    cfg = DiagnoseConfig(**check_table(raw.get("diagnose", {}), path, "diagnose", _SPEC, DiagnoseError))
    for lo_hi in cfg.bands_hz or []:
        if not (isinstance(lo_hi, list) and len(lo_hi) == 2 and 0 <= lo_hi[0] < lo_hi[1]):
            fail(path, "diagnose.bands_hz", f"{lo_hi!r} is not [lo, hi]", "0 <= lo < hi [Hz]", DiagnoseError)
    return cfg


@dataclass(frozen=True)
class Dataset:
    """A dataset as the diagnosis reads it (_load)."""

    records: list  # every record, in level order (pyfit.gap.simulate.Record)
    cal: list  # the records calibrated on
    held: list  # the records held out
    key: str  # the data's digest
    order: str  # what the level order rests on (pyfit.io.data.level_order)
    aside: dict  # records the default split set aside (localise.unsettled: name -> period scatter, lower floor)
    voltages: list  # 'column (model_variable)' of each channel recorded as a voltage (System.gains_free)
    rate: AnalysisRate  # the rate the records are analysed at (the files' or decimated: pyfit.gap.rate)
    recorded_hz: dict  # name -> the rate a file was recorded at, where it was faster than the dataset's
    # (rate.common_rate: decimated to the slowest file's rate)
    measurements: list  # the files as read, in level order (pyfit.io.data.Measurement: columns, units, SI values)
    clipped: dict  # 'file column' -> samples held at the column's extreme by a range limit (signals.clipped_samples)


def default_calibration(records: list) -> list:
    """The records calibrated on by default (`records` ordered by level): of three levels or more, every file of
    the lowest and of the highest level (the levels between are held out: more levels hold more out, not more into
    every fit's simulations); of two, every file of the lower (the higher is held out); of one, every other file
    from the first (a dataset of one level in several files, e.g. a stepped sine's frequencies: the calibration
    spans them), the first alone of two files."""
    levels = sorted({r.level_value for r in records})
    if len(levels) >= 3:
        return [r for r in records if r.level_value in (levels[0], levels[-1])]
    if len(levels) == 2:
        return [r for r in records if r.level_value == levels[0]]
    return records[::2] if len(records) >= 3 else records[:1]


def _load(data_dir, system, cfg: DiagnoseConfig, runner: FmuRunner) -> Dataset:
    """Records of the dataset, validated against the FMU's variables and their units, split into calibration
    and held-out."""
    data_dir = pathlib.Path(data_dir)
    md_vars = runner.model_description.modelVariables
    variables = {v.name for v in md_vars}
    units = {v.name: v.unit or "" for v in md_vars}
    allowed = {"inputs": [v.name for v in md_vars if v.causality == "input"],
               "outputs": [v.name for v in md_vars if v.causality == "output"]}
    try:
        ms, order = read_dataset_with_order(data_dir)
        read = list(ms)
    except MeasurementError as exc:
        raise DiagnoseError(str(exc)) from exc
    if len(ms) < 2:
        raise DiagnoseError(f"{data_dir}: a diagnosis needs at least two files (one to calibrate on, one held "
                            f"out); found {len(ms)}")
    voltages = set()  # 'column (model_variable)' of the channels recorded as voltages
    for m in ms:
        if m.model != system.fmu:
            raise DiagnoseError(f"{m.path.with_suffix('.toml')}: model = '{m.model}' but --model {system.name} "
                                f"expects '{system.fmu}'")
        try:
            voltages.update(check_quantities(m, units, system.gains_free))
        except MeasurementError as exc:
            raise DiagnoseError(str(exc)) from exc
    try:
        ms, recorded_hz = common_rate(ms)
    except ValueError as exc:
        raise DiagnoseError(str(exc)) from exc
    rate = analysis_rate(ms)
    ms = [at_rate(m, rate.factor) for m in ms]
    unknown = [e for e in (cfg.effects or []) if e not in system.effects]
    if unknown:
        raise DiagnoseError(f"effects: '{unknown[0]}' unknown for {system.name}; allowed: "
                            f"{', '.join(system.effects)}")
    try:
        records = [sim.record_of(m, system.motion_inputs, cfg.transient_s, system.smooth_inputs) for m in ms]
    except ValueError as exc:
        raise DiagnoseError(str(exc)) from exc
    for m, r in zip(ms, records):
        for kind, names in (("inputs", r.inputs), ("outputs", r.outputs)):
            bad = [n for n in names if n not in variables]
            if bad:
                raise DiagnoseError(f"{m.path.with_suffix('.toml')}: [{kind}] model_variable '{bad[0]}' is not a "
                                    f"variable of {system.fmu}; allowed: {', '.join(sorted(allowed[kind]))}")
    names = [r.name for r in records]
    # the default split leaves out a record whose response does not repeat between periods (no steady state:
    # a simulation cannot follow it sample by sample, and calibrating on it pulls every parameter off)
    aside = {} if cfg.calibration else localise.unsettled(records)
    if len(records) - len(aside) < 2:
        raise DiagnoseError(f"{data_dir}: the response of {', '.join(aside)} does not repeat from one period to the "
                            "next (no steady state), which leaves fewer than two files to calibrate on and hold "
                            "out; allowed: name the files to calibrate on in [diagnose] calibration to use them all")
    records = [r for r in records if r.name not in aside]
    if cfg.calibration:
        bad = [c for c in cfg.calibration if c not in names]
        if bad:
            raise DiagnoseError(f"calibration: no file '{bad[0]}' in {data_dir}; files: {', '.join(names)}")
        cal = [r for r in records if r.name in cfg.calibration]
    else:
        cal = default_calibration(records)
    held = [r for r in records if r not in cal]
    if not held or not cal:
        raise DiagnoseError(f"calibration: the split leaves {'no held-out' if not held else 'no calibration'} file")
    digest = hashlib.sha256(str(rate.factor).encode())
    for m in ms:
        digest.update(m.path.read_bytes())
        digest.update(m.path.with_suffix(".toml").read_bytes())
    clipped = {f"{m.name} {col}": n for m in read for col, v in m.values.items() if (n := clipped_samples(v))}
    return Dataset(records, cal, held, digest.hexdigest()[:16], order, aside, sorted(voltages), rate, recorded_hz,
                   read, clipped)


def tried_effects(system, cfg: DiagnoseConfig) -> list[str]:
    """The effects a diagnosis screens and refits: those `cfg.effects` names, else every effect of the system but
    the ones offered only on request (systems.Effect.opt_in)."""
    return cfg.effects or [n for n, e in system.effects.items() if not e.opt_in]


def _simulated(runner, records, values: dict, system, cfg: DiagnoseConfig) -> dict:
    """Each of `records` simulated with `values` (record name -> outputs; None where a simulation failed)."""
    return {r.name: sim.simulate(runner, r, values, cfg.upsample, system.lead_periods) for r in records}


def _on_one_blas_thread(func):
    """`func` run with the BLAS libraries on one thread (threadpoolctl): a multi-threaded BLAS rounds by its thread
    count, and a multistart least squares amplifies a last-digit difference into another path, so the same files
    gave another verdict diagnosed alone than on a Dask worker (which starts with one BLAS thread). A diagnosis
    and each fit it runs in a worker process hold to it."""
    @functools.wraps(func)
    def run(*args, **kwargs):
        with threadpoolctl.threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)
    return run


@_on_one_blas_thread
def _fit_and_store(job) -> Fit:
    """Run one fit (in a worker) and store it at once, so an interrupted diagnosis keeps it. A job may carry
    stages: fits run first, whose results the fit then also starts from (their evaluations and wall time are
    counted in the fit's)."""
    task, path, key, *stages = job
    staged = [run_fit(stage) for stage in stages]
    fit = run_fit(dataclasses.replace(task, alternatives=task.alternatives + tuple(
        {n: s.params[n] for n in task.start} for s in staged)))
    # the stages' cost is the fit's: its evaluations and wall time include theirs
    fit = dataclasses.replace(fit, evaluations=fit.evaluations + sum(s.evaluations for s in staged),
                              wall_s=fit.wall_s + sum(s.wall_s for s in staged))
    pathlib.Path(path).write_text(json.dumps({"key": key, "fit": fit.to_json()}, indent=1))
    return fit


def _stored(path: pathlib.Path, key: str) -> Fit | None:
    if path.is_file():
        d = json.loads(path.read_text())
        if d.get("key") == key:
            return Fit(**d["fit"])
    return None


def _fits_of(jobs, key: str, alone: int, workers, progress: bool, desc: str) -> dict[str, Fit]:
    """The fits of `jobs` ((task, path, *stages): see _fit_and_store) by their effect's name: each stored one read
    from its path, the others run (in workers: _run_fits)."""
    done = {job[0].effect: _stored(pathlib.Path(job[1]), key) for job in jobs}
    todo = [(task, str(path), key, *stages) for task, path, *stages in jobs if done[task.effect] is None]
    for fit in _run_fits(todo, alone, workers, progress, desc):
        done[fit.effect] = fit
    return done


def _run_fits(jobs, alone: int, workers, progress: bool, desc: str) -> list[Fit]:
    """_fit_and_store of each job (task, path, key, *stages) in workers, each fit simulating its records on up to
    `alone` threads (the cores a fit running alone has): the fits that run while others end take up the cores
    those leave idle (three fits on two cores, or one long refit behind short ones, no longer end on one core).
    A fit's result does not depend on its threads."""
    jobs = [(dataclasses.replace(task, threads=alone), path, key,
             *(dataclasses.replace(stage, threads=alone) for stage in stages)) for task, path, key, *stages in jobs]
    return map_tasks(_fit_and_store, jobs, workers=workers, progress=progress, desc=desc)


def with_drive(cfg: DiagnoseConfig, system, rate: AnalysisRate) -> DiagnoseConfig:
    """cfg with the FMU's drive grid set: its own upsample when it sets one, else the family's for the rate the
    records are analysed at (rate.drive_upsample)."""
    return cfg if cfg.upsample is not None else dataclasses.replace(cfg, upsample=drive_upsample(system.upsample,
                                                                                               rate))


def _stem(name: str) -> str:
    """The file stem a model's fit is stored under (a combination 'a + b' as 'a+b')."""
    return name.replace(" + ", "+")


def _combination_seeds(system, scale, current: dict, members: list, partner_fit: dict, partner: str,
                       strength: dict) -> tuple[dict, ...]:
    """Starts of a combination's joint refit, each a model the combination holds: the model so far (`current`:
    its parameter values, the partner absent); the partner's own refit (the model so far's effects absent: a
    first effect that over-compensates for the second starts better at zero); the model so far with the
    partner's parameters from that refit, with the model so far's linear parameters or with the partner's (a
    hysteretic element's refit moves the linear stiffness: its linear parameters belong with its loop); the model
    so far with the partner's strength from the Gauss-Newton step at that model (`strength`, screen's) scaled by
    attribute.STRENGTH_FACTORS; the model so far with each listed start of the partner (effect.starts: loop
    shapes, cubic strengths); and the partner's own refit with each listed start of the model so far's
    `members` (a free-shape loop refitted alone bends into a strong element that stands in for a hardening
    spring: the pair's basin is then the spring's refit with a weak loop of the family's shapes). A listed
    start's linear values are shares of the nominal's, applied to the refit it is added to."""
    own = {p.name for p in system.effects[partner].params}
    linear = set(system.linear)

    def added(base: dict, start: dict) -> dict:
        return {**base, **{n: base[n] * v / scale.nominal[n] if n in linear else v for n, v in start.items()}}

    return ((current, partner_fit, {**current, **{n: partner_fit[n] for n in own}},
             {**current, **{n: v for n, v in partner_fit.items() if n in own or n in linear}})
            + tuple({**current, **{n: v * f for n, v in strength.items()}} for f in STRENGTH_FACTORS if strength)
            + tuple(added(current, st) for st in system.effects[partner].starts(scale))
            + tuple(added(partner_fit, st) for m in members for st in system.effects[m].starts(scale)))


def _combinations(system, cfg: DiagnoseConfig, fmu, cal, held, nominal: Fit, scale, fits: dict, sims: dict, gap,
                  screening: dict, runner, out: pathlib.Path, key: str, workers, progress):
    """Forward selection while a model's held-out misfit is above the noise (selection.significant with
    `cfg.extend_factor` and `cfg.combination_min_gap`), from each of the `cfg.beam` best single effects (by score;
    a flexible stand-in can lead, the true first member come second; a change of the linear system below the first
    whose refit removes less than `cfg.min_shrink_pct` of the gap starts none: selection.worth_a_path): extend
    the model by each of the `cfg.partners` other effects whose sensitivity at that model explains most of its calibration residual (the
    screening repeated there; none when the model already meets the absolute criterion and no candidate explains
    `cfg.min_partner_explained` of that residual: the path ends there, and so does the search unless that model
    holds a free-shape loop whose misfit is still above the noise, a possible stand-in). Each partner is refitted
    beside the model so far held at its own refit (attribute.pinned); the one that helps most there, the best of
    those with fewer parameters than it that cuts a quarter of its cut there (selection.leaner_best: a free-shape
    loop absorbs most beside a held model), and the one that helps least (the control), are then refitted
    jointly (from each member's own refit, the effects' starts, the partner's refit beside the model and the
    members refitted beside the partner's refit; a combination reached from two paths is refitted beside each path's
    model, the better kept, and its joint refit probes from its own path's refit beside too; a pair refitted
    jointly on its partner's path, where it added too little, is refitted jointly again from this path's starts
    (rejoined below); the best joint refit without a free-shape loop is refitted on when one with a loop fits
    better: selection.lean_rival). Go on from the best combination (the lowest misfit; of two within the noise,
    the one with fewer parameters) when it removes `min_excess_cut` of the misfit above the floor that the model
    it extends leaves once refitted on with a combination's budget (the combinations start from that refit and
    never end worse than it) or, when lower, the misfit of the control's joint refit (what the combination's
    extra evaluations alone buy the model it extends, counted with the control's partner at zero:
    selection.budget_control), up to `cfg.max_effects` members. Where
    the control at zero fits the held-out files better than the model it extends, that model is refitted on from
    there (and takes the fit when it fits the calibration files better): the longer fit the control stands for.
    The noise these tests measure a misfit above is the floor should the sensor noise grow with the level
    (gap["noise_floor_scaled"]): a floor taken too low asks a right pair to remove half of a misfit that is noise.
    A path's end is checked backward: the model without each of its members is refitted from the end's
    values, and the end is kept only when it still removes `min_excess_cut` of what each refit leaves; an end
    still above the absolute criterion is then refitted on from its own values. A path whose start is a member
    of an earlier path's end that explains the data (and is no possible stand-in: a model with a free-shape
    member, systems.Effect.free_shape, still above the noise, unless its loop has no basins and was found beside
    the lean effect its path began at) is not tried. When the best-scoring single effect is a loop without basins
    still above the noise that fits the calibration files worse than the effect whose sensitivity explains most
    of the nominal residual (`screening`), the path from that effect goes first. When a path ends at a possible
    stand-in whose loop has no basins (the damper's: its refit descends from a list of starts), the single effect
    whose sensitivity explains most of the nominal residual (`screening`: the share per effect) starts a path
    too, if none has yet: such a loop can take up a strong spring's refit score where the spring's sensitivity
    still shows it, and the loop beside the spring's refit is found on that path (a loop with basins is refitted
    from each, a weak loop's among them). Of the ends of
    these paths, a larger model is selected only by the same rule, and of two as large whose misfits are both
    within the noise, the one with fewer parameters (selection.simpler_or_better; a model holding a change of
    the linear system wins only on a lower misfit). When the best single effect is already within the noise,
    nothing is added: the single effect kept by that rule is the model selected. When then no single effect
    and not the model selected meets the absolute criterion and the calibration records are not periodic
    (sweeps, stepped sines, noise), the single effects and pairs of the best of them are fitted to the amplitude
    envelopes first and refitted on the waveforms from there (enveloped, below), and the selection weighs those
    pairs too. When still nothing meets it, the `cfg.grid_models` models with the lowest held-out misfit are
    each refitted from the best point of a grid over their members' strengths (systems.strength_grid; a pair's
    valley where a descent from its members' refits stops short), and the selection is made again with them (the
    envelopes go first: a few fits, where the grid simulates hundreds of points). Adds the fits and held-out
    simulations to `fits` and `sims`; returns the system with the combined effects among its effects and the
    model selected (None when no single effect was refitted)."""
    before, floor = gap["overall"], gap["noise_floor"]
    above = gap["noise_floor_scaled"]  # the noise the selection measures a misfit above (at least the floor)
    explained_below = selection.explained_below(floor, cfg.explain_factor, cfg.explain_margin)
    settled = set()  # models that meet the absolute criterion and leave nothing a candidate's sensitivity explains
    alone = workers or os.cpu_count() or 1  # a fit that runs alone simulates its records at once

    def left(name):  # a model's held-out misfit is above the noise (a weaker test than the nominal's): go on adding
        return selection.significant(after[name], above, cfg.extend_factor, cfg.combination_min_gap)

    after = {n: selection.heldout_nrmse(sims[n], held) for n in fits}

    def score(name):
        return selection.score(before, after[name], floor, fits[name].n_added)

    ranked = sorted(fits, key=lambda n: -score(n))
    if not ranked:
        return system, None
    effects = dict(system.effects)
    named = {frozenset([n]): n for n in fits}  # members -> the name their model is stored under
    beside_only = set()  # combinations whose fit so far is a refit beside one path's model (no joint refit)
    controls = {}  # a combination -> what refitting on alone bought the model it extends (selection.budget_control)

    def on_held(values):  # the held-out records simulated with `values`
        return _simulated(runner, held, values, system, cfg)

    def simulated(name):
        sims[name] = on_held(fits[name].params)
        after[name] = selection.heldout_nrmse(sims[name], held)

    def without_partner(name, task, added: dict):
        # the held-out misfit of a combination's joint refit with its last member at zero: the model it extends at
        # the values that refit found (a control whose partner stands in for the true one, a loop for a hardening
        # spring, then does not count as what more evaluations alone buy the model it extends)
        return selection.heldout_nrmse(on_held({**fits[name].params, **{n: task.floor[n] for n in added}}), held)

    def grow(current):
        while len(effects[current].members or (current,)) < cfg.max_effects and left(current):
            members = list(effects[current].members or (current,))
            # the model so far, refitted on from its own result with a combination's budget: a combination must
            # beat more evaluations of its first member(s), not only the first refit; the partners then start from
            # (and never end worse than) the model so far at its best
            again_path = out / "fits" / f"{_stem(current)}.continued.json"
            again = _stored(again_path, key) or _fit_and_store((dataclasses.replace(
                effect_task(system, effects[current], fmu, cal, nominal, scale, cfg.refit_budget, cfg.upsample,
                            seeds=(fits[current].params,)), threads=alone), str(again_path), key))
            if again.calibration_nrmse < fits[current].calibration_nrmse:
                fits[current] = again
                simulated(current)
            if not left(current):
                break  # the model so far, refitted on, reaches the noise: nothing left to add
            names, new = [], []
            # the next member: the candidates whose sensitivity at the model so far explains most of its
            # residual on the calibration files (the screening's score test, repeated at that model)
            others = [n for n in system.effects if n not in members and n in fits]
            explained, strength = screen(system, fmu, cal, fits[current], scale, cfg.upsample, others)
            if selection.nothing_to_add(after[current], explained_below, list(explained.values()),
                                        cfg.min_partner_explained):
                settled.add(current)  # it explains the data and no candidate explains what is left: done
                break
            again = []  # pairs refitted jointly on the partner's path that added too little there: rejoined
            for partner in sorted(others, key=lambda n: -explained[n])[:cfg.partners]:
                together = frozenset(members + [partner])
                # new, or reached from another path that held only its other member(s) at their refit: refitted
                # beside this path's model too (a weak loop beside a strong spring is found beside the spring);
                # one refitted jointly on the partner's path is refitted again only when it added too little there
                combo = effects[named[together]] if together in named else combine(
                    [system.effects[m] for m in members + [partner]])
                effects[combo.name], named[together] = combo, combo.name
                names.append(combo.name)
                seeds = _combination_seeds(system, scale, fits[current].params, members, fits[partner].params,
                                           partner, strength.get(partner, {}))
                task = effect_task(system, combo, fmu, cal, nominal, scale, cfg.refit_budget, cfg.upsample,
                                   seeds=seeds)
                # never worse than the model it extends (the partner at zero is that model)
                added = {q.name for q in system.effects[partner].params}
                at_zero = {**task.floor, **{n: v for n, v in fits[current].params.items()
                                            if n in task.floor and n not in added}}
                task = dataclasses.replace(task, floor=at_zero, probes=cfg.combination_probes)
                # each side refitted beside the other held at its own refit (attribute.pinned): the partner
                # beside the model so far (its members' own parameters fixed), and the members beside the
                # partner's refit. A weak effect beside a strong one is found there, where the joint descent
                # from the same starts lets the weak one take over the strong one's part
                so_far = {n: v for n, v in fits[current].params.items()
                          if n in task.start and n not in added and n not in system.linear}
                tried_here = (combo.name, task, so_far, {n: fits[partner].params[n] for n in added})
                if combo.name not in fits or combo.name in beside_only:
                    new.append(tried_here)
                elif len(together) == 2 and not selection.adds_enough(after[partner], after[combo.name], above,
                                                                      cfg.min_excess_cut):
                    again.append(tried_here)  # refitted jointly on the partner's path, adding too little there
            rejoined(current, again)
            # every partner first beside the model so far held (half a refit's budget, no probes); the joint
            # refit then only for the partner that helps most there and, as the control, the one that helps least
            beside = beside_refits(new, current, "partners beside")
            own = dict(beside)  # the refits beside this path's model (a joint refit starts from them too)
            for name, fit in own.items():  # a refit beside another path's model stays when it fits better
                if name in fits and fits[name].calibration_nrmse <= fit.calibration_nrmse:
                    beside[name] = fits[name]
            # (by the calibration misfit the refits beside minimised: a hardening spring held at its own refit
            # can jump on a held-out sweep where the partner's refit beside it does not tell that partner apart)
            order = sorted(beside, key=lambda n: beside[n].calibration_nrmse)
            joint = {order[0], order[-1]} if len(names) >= selection.CONTROL_SIBLINGS else set(order[:1])
            # a partner with many free parameters (a free-shape loop) absorbs more beside a held model than one
            # with few, whose member held at a refit that made up for it holds it back (a cubic spring stiffened
            # less, a viscous damper raised for a quadratic one): the best of the leaner ones is refitted jointly too,
            # when it cuts a quarter of what the leader cuts beside the model (selection.LEANER_MIN_SHARE)
            sizes = {n: len(effects[n].params) for n in order}
            cuts = {n: fits[current].calibration_nrmse - beside[n].calibration_nrmse for n in order}
            joint |= set(selection.leaner_best(order, sizes, cuts))
            # and a free-shape loop without basins (the damper's) refitted beside from its one best start only: a
            # rough estimate, which a leaner partner can lead taking up the loop's dissipation (friction beside a
            # cubic spring held at its own refit): the best such richer partner is refitted jointly too
            rough = {n for n in order if (lambda e: e.free_shape and e.basin is None)(
                system.effects[effects[n].members[-1]])}
            joint |= set(selection.richer_best(order, sizes, rough))
            for name in set(beside) - joint:  # its fit is the best one beside a path's model so far
                if fits.get(name) is not beside[name]:
                    fits[name] = beside[name]
                    sims.pop(name, None)
                beside_only.add(name)
            # (from the best refit beside a path's model among its starts, and probed from this path's own: a weak
            # loop beside a strong spring's refit misfits more than a loop standing in for the spring)
            jointly = _fits_of([joint_job(task, side, beside[name], own[name], _stem(name))
                                for name, task, _, side in new if name in joint],
                               key, alone, workers, progress, "combinations")
            for name, fit in jointly.items():  # its cost includes the refit beside the model so far
                fits[name] = dataclasses.replace(fit, evaluations=fit.evaluations + beside[name].evaluations,
                                                 wall_s=fit.wall_s + beside[name].wall_s)
                sims.pop(name, None)
                beside_only.discard(name)
            for name in names:
                if name not in after or name not in sims:
                    simulated(name)
            least = order[-1] if order else None
            # a free-shape loop can take up part of any effect: the best jointly refitted pair without one, when a
            # pair with one fits the held-out files better, is first refitted on with a path end's polish budget
            rival = selection.lean_rival(
                jointly, {n for n in jointly if any(system.effects[m].free_shape for m in effects[n].members)},
                after, least)
            if rival is not None:
                onward(rival, fits[rival].params, 2 * cfg.refit_budget, f"{_stem(rival)}.against_loop")
            best = functools.reduce(kept, names) if names else None  # the lowest misfit, or the leanest at the noise
            tried = {n: (task, side) for n, task, _, side in new}
            at_zero = without_partner(least, *tried[least]) if least not in (None, best) else float("inf")
            if at_zero < after[current]:
                # the control with its partner at zero is the model so far at other values (a wide loop, where
                # the model's own refit stopped in a narrow one): refitted on from there, it replaces the model's
                # fit when it fits the calibration files better (the longer fit the control stands for, taken)
                task, side = tried[least]
                onward(current, {**fits[least].params, **{n: task.floor[n] for n in side}},
                       cfg.refit_budget // 2, f"{_stem(current)}.from.{_stem(least)}")
            control = selection.budget_control(at_zero, len(names))
            for name in names:  # the lowest control any of its refits met
                controls[name] = min(controls.get(name, float("inf")), control)
            if best is None or not selection.adds_enough(min(after[current], controls[best]), after[best], above,
                                                         cfg.min_excess_cut):
                break
            current = best
        return pruned(current)

    def beside_refits(tried, current, desc):
        # each combination of `tried` (name, task, the model's values held, the partner's own) refitted beside the
        # model `current` held at those values (half a refit's budget), stored as fits/<name>.beside.<current>.json
        return _fits_of([(pinned(task, so_far, cfg.refit_budget // 2),
                          out / "fits" / f"{_stem(n)}.beside.{_stem(current)}.json")
                         for n, task, so_far, _ in tried], key, alone, workers, progress, desc)

    def joint_job(task, side, start: Fit, probe: Fit, stored_as):
        # a combination's joint refit (a _fit_and_store job) that also starts from `start`'s values and probes
        # from `probe`'s, after its members refitted beside the partner's own values (`side`) as a stage
        return (dataclasses.replace(task, alternatives=task.alternatives + ({n: start.params[n] for n in task.start},),
                                    probed=({n: probe.params[n] for n in task.start},)),
                out / "fits" / f"{stored_as}.json", pinned(task, side, cfg.refit_budget // 2))

    def rejoined(current, again):
        # each pair refitted jointly on its partner's path where it added too little (`again`: as `new` in grow),
        # refitted beside the model `current` held (half a refit's budget) and jointly from this path's starts and
        # that refit (stored as fits/<pair>.on.<current>.json); its fit replaced when that fits the calibration
        # files better. From a loop's path the loop can stand in for the other member in the joint refit too;
        # from the other member's own refit the loop explains only what that member leaves
        beside = beside_refits(again, current, "pairs again beside")
        jobs = [joint_job(task, side, beside[name], beside[name], f"{_stem(name)}.on.{_stem(current)}")
                for name, task, _, side in again]
        for name, fit in _fits_of(jobs, key, alone, workers, progress, "pairs again").items():
            if fit.calibration_nrmse < fits[name].calibration_nrmse:  # its cost includes both refits
                fits[name] = dataclasses.replace(fit, evaluations=fit.evaluations + beside[name].evaluations
                                                 + fits[name].evaluations, wall_s=fit.wall_s + beside[name].wall_s
                                                 + fits[name].wall_s)
                simulated(name)

    def onward(name, values, budget, stored_as, grid=()):
        # the model `name` refitted from `values` (or the best of `grid`, points overriding them), with `budget`
        # evaluations on every core, stored as fits/<stored_as>.json; it replaces the model's fit when its
        # calibration misfit is lower
        path = out / "fits" / f"{stored_as}.json"
        task = effect_task(system, effects[name], fmu, cal, nominal, scale, budget, cfg.upsample, seeds=(values,))
        fit = _stored(path, key) or _fit_and_store((dataclasses.replace(
            task, start=task.alternatives[-1], alternatives=grid, basin=None, threads=alone), str(path), key))
        if fit.calibration_nrmse < fits[name].calibration_nrmse:  # its cost includes the fit it goes on from
            fits[name] = dataclasses.replace(fit, evaluations=fit.evaluations + fits[name].evaluations,
                                             wall_s=fit.wall_s + fits[name].wall_s)
            simulated(name)

    def pruned(end):
        # the backward step: the model without each of its members in turn (the last-added, and the first: a path
        # that began at a spring can end at the spring plus a loop that holds all of the effect), each refitted
        # from the larger model's values with half a refit's budget (a loop refitted alone can stop short in a
        # slow valley whose misfit a stand-in partner then takes up; from the pair's loop it goes on to where the
        # partner adds too little); the larger model stays only when it still adds enough to every such refit,
        # else the smaller model it adds least to is the end
        # (the model it extended, without the last-added member, also against what its control's evaluations
        # bought it: selection.budget_control)
        members = effects[end].members or ()
        rests = {named[frozenset(members) - {m}]: controls.get(end, float("inf")) if m == members[-1]
                 else float("inf") for m in members if frozenset(members) - {m} in named}
        for rest in rests:
            onward(rest, fits[end].params, cfg.refit_budget // 2, f"{_stem(end)}.reduced_to.{_stem(rest)}")
        short = [r for r, bar in rests.items()
                 if not selection.adds_enough(min(after[r], bar), after[end], above, cfg.min_excess_cut)]
        return min(short, key=lambda r: after[r]) if short else end

    def kept(a, b):  # of two models (path ends, a path's combinations), the one kept (selection.simpler_or_better)
        sized = [(len(effects[n].members or (n,)), after[n]) for n in (a, b)]
        larger = (a, b)[sized[1][0] > sized[0][0]]
        return (a, b)[selection.simpler_or_better(
            *sized, above, cfg.min_excess_cut, controls.get(larger, float("inf")),
            parameters=(len(effects[a].params), len(effects[b].params)),
            noise=selection.noise_level(above, cfg.noise_factor, cfg.combination_min_gap),
            linear=any(system.effects[m].linear for n in (a, b) for m in effects[n].members or (n,)))]

    if not left(ranked[0]):
        # a single effect reaches the noise: nothing to add; of the single effects, the one kept by the same rule
        # (a loop of free shape and a cubic spring that both reach the noise on the same records, within ALIKE
        # of each other: the spring, the data no longer tell them apart)
        return system, functools.reduce(kept, ranked)

    def stand_in(name):  # a free-shape loop still above the noise: it may hold another's part
        return any(system.effects[m].free_shape for m in effects[name].members or (name,)) and left(name)

    def polished(end):
        # a path's end still above the absolute criterion, refitted on from its own values with twice a refit's
        # budget before it is judged (which model the path ends at is settled; a joint refit of many parameters
        # can stop short of the floor its effects reach)
        if after[end] > explained_below:
            onward(end, fits[end].params, 2 * cfg.refit_budget, f"{_stem(end)}.polished")
        return end

    def basin_free_stand_in(name):  # a possible stand-in whose loop has no basins (the damper's)
        return stand_in(name) and effects[name].basin is None

    def found_beside(end):  # such a loop, found beside the lean effect its path began at
        return basin_free_stand_in(end) and not system.effects[(effects[end].members or (end,))[0]].free_shape

    def envelope_fits(models, seeds_of, probes=1, stored_as="envelopes"):
        # each model fitted to the calibration files' amplitude envelopes from its starts and `seeds_of(model)`
        # (attribute.FitTask.envelopes), stored as fits/<model>.<stored_as>.json
        return _fits_of([(dataclasses.replace(effect_task(system, effects[n], fmu, cal, nominal, scale,
                                                          cfg.refit_budget, cfg.upsample, seeds=seeds_of(n)),
                                              envelopes=True, probes=probes),
                          out / "fits" / f"{_stem(n)}.{stored_as}.json") for n in models],
                        key, alone, workers, progress, "envelope fits")

    def enveloped(models):
        # nothing explains a sweep or stepped sine: the waveform refits can all stop a cycle or more off the data
        # (a strong hardening spring beside a loop jumps at another frequency in every refit, and no single
        # effect, nor a pair built from them, comes near), where the amplitude envelopes are smooth in the
        # parameters. Each single effect is fitted to the envelopes (from its starts and its waveform refit);
        # each pair of the `cfg.grid_models` best of them by that fit twice, from its members' waveform refits
        # and from their envelope fits (_combination_seeds of each: the envelopes have basins of their own, a
        # loop's shape barely changes them). Each model is then refitted on the waveforms from its envelope
        # fit(s) (both descended a while, the better one on), replacing its fit when that fits the calibration
        # files better. Returns the pairs (the models the selection also weighs)
        alone_fits = envelope_fits(models, lambda n: (fits[n].params,))
        best = sorted(alone_fits, key=lambda n: alone_fits[n].calibration_nrmse)[:cfg.grid_models]
        pairs = []
        for a, b in itertools.combinations(best, 2):
            together = frozenset([a, b])
            if together not in named:
                combo = combine([system.effects[a], system.effects[b]])
                effects[combo.name], named[together] = combo, combo.name
            pairs.append(named[together])

        def seeds_from(members_fits):  # a pair's starts from its members' fits (_combination_seeds)
            def seeds(pair):
                first, second = effects[pair].members
                return _combination_seeds(system, scale, members_fits[first].params, [first],
                                          members_fits[second].params, second, {})
            return seeds

        on_envelopes = {n: [f] for n, f in alone_fits.items()}
        for members_fits, stored_as in ((fits, "envelopes"), (alone_fits, "envelopes_from_envelopes")):
            for name, fit in envelope_fits(pairs, seeds_from(members_fits), cfg.combination_probes,
                                           stored_as).items():
                on_envelopes.setdefault(name, []).append(fit)
        jobs = []
        for name, found in on_envelopes.items():
            # the envelope fits as seeds: the bounds widened to hold their linear values, then the starts
            task = effect_task(system, effects[name], fmu, cal, nominal, scale, cfg.refit_budget, cfg.upsample,
                               seeds=tuple(f.params for f in found))
            values = task.alternatives[-len(found):]
            jobs.append((dataclasses.replace(task, start=values[0], alternatives=values[1:], basin=None,
                                             probes=len(values), continuation=False),
                         out / "fits" / f"{_stem(name)}.from_envelopes.json"))
        for name, fit in _fits_of(jobs, key, alone, workers, progress, "waveforms from the envelopes").items():
            if name not in fits or fit.calibration_nrmse < fits[name].calibration_nrmse:
                # its cost includes the envelope fits it starts from
                fits[name] = dataclasses.replace(fit, evaluations=fit.evaluations + sum(
                    f.evaluations for f in on_envelopes[name]), wall_s=fit.wall_s + sum(
                    f.wall_s for f in on_envelopes[name]), from_envelopes=True)
                simulated(name)
        return pairs

    ends, starts = [], ranked[:cfg.beam]
    screened = max(ranked, key=lambda n: screening.get(n, 0.0))  # the single effects, by their sensitivity
    if (basin_free_stand_in(starts[0]) and screened != starts[0]
            and fits[screened].calibration_nrmse < fits[starts[0]].calibration_nrmse):
        # a loop without basins leads by its held-out score but fits the calibration files worse than the effect
        # whose sensitivity explains most of the nominal residual: it may stand in for that effect (a hardening
        # spring's jump on a held-out sweep costs the spring its score), so the path from that effect goes first
        starts = [screened] + [n for n in starts if n != screened]
    for rank, start in enumerate(starts):
        if rank and not selection.worth_a_path(selection.shrink_pct(before, after[start], floor),
                                               effects[start].linear, cfg.min_shrink_pct):
            continue  # a linear change that removes little of the gap: its path would add the first path's partners
        if any(after[e] <= explained_below and start in (effects[e].members or (e,))
               and (not stand_in(e) or found_beside(e)) for e in ends):
            break  # an earlier path's end explains the data and holds this start already (a loop found beside
            # a lean effect's refit does not stand in for it: the path from the loop alone is not needed)
        ends.append(polished(grow(start)))
        if basin_free_stand_in(ends[-1]) and screened not in starts:
            starts.append(screened)  # the effect the loop may stand in for, by its sensitivity
        if not left(ends[-1]) or (ends[-1] in settled and not stand_in(ends[-1])):
            break  # a path that reaches the noise, or explains the data with nothing a candidate explains left
        # (not so a free-shape loop still above the noise: it can take up a strong spring's part beyond the reach
        # of its sensitivity to the spring, where the path from the spring finds the weak loop beside it)
    selected = functools.reduce(kept, ends)
    singles = [n for n in fits if not effects[n].members]

    def unexplained():  # no single effect and not the model selected meets the absolute criterion
        return all(after[n] > explained_below for n in singles + [selected])

    if unexplained() and not any(r.periodic for r in cal):
        # sweeps, stepped sines, noise: the amplitude envelopes first (a few fits; the grid below simulates
        # hundreds of points, stiff ones crawling to their time limit)
        selected = functools.reduce(kept, [selected] + enveloped(singles))
    if unexplained():
        # nothing explains the data: the best models, each refitted from the best point of a grid over its
        # members' strengths (its other parameters at its refit); then selected again among the paths' ends
        gridded = sorted(after, key=after.get)[:cfg.grid_models]
        for name in gridded:
            members = [system.effects[m] for m in effects[name].members or (name,)]
            onward(name, fits[name].params, cfg.refit_budget, f"{_stem(name)}.gridded",
                   strength_grid(members, scale, fits[name].params))
        selected = functools.reduce(kept, list(dict.fromkeys([selected] + ends + gridded)))
    return dataclasses.replace(system, effects=effects), selected


def _detection(system, fits: dict, sims: dict, held, gap: dict, scale, runner, cfg: DiagnoseConfig) -> dict:
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
    linear_only = min(selection.heldout_nrmse(_simulated(runner, held, {**refit, **values}, system, cfg), held)
                      for values in [effect.absent(scale), *parts])
    before = min(gap["overall"], linear_only)
    return {"effect": best, "heldout_after": after[best], "linear_only": linear_only, "reduced": bool(parts),
            "cut": 1.0 - after[best] / before if before > 0 else 0.0, "min_cut": cfg.min_detect_cut,
            "detected": not effect.linear and selection.detected_by_refit(before, after[best], cfg.min_detect_cut)}


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


@_on_one_blas_thread
def diagnose(model: str, data_dir, out_dir, cfg: DiagnoseConfig | None = None, fmu_dir="fmus",
             workers: int | None = None, progress: bool = True, nominal: NominalModel | str | None = None,
             candidates=None) -> dict:
    """Diagnose the dataset against the nominal model `model` ('sdof' or 'damper'); writes OUT/report.json,
    OUT/report.md and figures; returns the report. When the nominal model already fits the held-out files
    within the noise threshold, the verdict is 'no significant gap' unless cfg.refit_within_noise: then the single
    effects are refitted all the same, and the gap is significant when the best of them removes
    cfg.min_detect_cut of the held-out misfit.

    nominal: the user's description of the nominal model (a NominalModel or a TOML file, see
    pyfit.io.nominal); None: the FMU's defaults (for the damper, the theory §1.3 reference damper).
    candidates: the user's declared candidate effects (pyfit.gap.user_candidates, or its TOML file): screened,
    refitted and ranked with the built-in ones, in the FMU the file names."""
    from pyfit.gap import report

    clock = StageClock()

    p = prepare(model, data_dir, cfg or DiagnoseConfig(), fmu_dir, nominal, candidates)
    fmu, runner, system, described, users, data = p.fmu, p.runner, p.system, p.described, p.users, p.data
    requested, cfg = p.requested, p.cfg
    records, cal, held, data_key = data.records, data.cal, data.held, data.key
    clock.end("reading and checking the data")
    out = pathlib.Path(out_dir)
    (out / "fits").mkdir(parents=True, exist_ok=True)
    judging = ("min_gap", "noise_factor", "extend_factor", "close_points", "min_shrink_pct", "explain_factor",
               "explain_margin", "nominal_max_nrmse", "max_effects", "partners", "min_excess_cut", "beam",
               "combination_min_gap", "min_partner_explained", "grid_models", "min_detect_cut", "refit_within_noise")
    # (how results are judged and which combinations are tried, not how a fit is made: stored fits stay valid)
    settings = json.dumps({k: v for k, v in asdict(cfg).items() if k not in judging}, sort_keys=True)
    description = json.dumps({"fixed": described.fixed, "free": {k: asdict(v) for k, v in described.free.items()}}
                             if described else {}, sort_keys=True)
    declared = users.text + hashlib.sha256(pathlib.Path(fmu).read_bytes()).hexdigest() if users else ""
    key = hashlib.sha256((data_key + settings + model + description + declared + ",".join(r.name for r in cal)
                          ).encode()).hexdigest()[:16]

    nominal = _stored(out / "fits" / "nominal.json", key)
    if nominal is None:
        task = nominal_task(system, fmu, cal, cfg.nominal_budget, cfg.upsample,
                            threads=workers or os.cpu_count() or 1)
        nominal = _fit_and_store((task, out / "fits" / "nominal.json", key))
    # from here on a simulation that takes SLOW_FACTOR times the calibrated nominal's on the same record counts as
    # failed (a stiff parameter set the integrator crawls through: sim.with_time_limits)
    limited = {r.name: r for r in sim.with_time_limits(runner, records, nominal.params, cfg.upsample,
                                                       system.lead_periods)}
    records, cal, held = ([limited[r.name] for r in rs] for rs in (records, cal, held))
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
    sims = {"nominal": _simulated(runner, records, nominal.params, system, cfg)}
    bands = [tuple(b) for b in cfg.bands_hz] if cfg.bands_hz else localise.default_bands(records)
    gap = report.nominal_gap(sims["nominal"], records, held, bands, cfg)
    _check_signs(system, fmu, cal, cfg, nominal, report.best_calibration_nrmse(gap)[0], data_dir, workers)
    clock.end("where (nominal gap)")
    screening, fits, selected = {}, {}, None
    effects = tried_effects(system, cfg)
    # nothing to attribute when the nominal model fits the held-out files within the noise threshold, unless
    # cfg.refit_within_noise: an effect too weak for that threshold is still told from noise when its refit removes
    # part of the held-out misfit (below). When the nominal fits none of its own calibration files the effects are
    # refitted all the same: a strong amplitude-dependent effect leaves no linear model fitting any level, and the
    # verdict is "does not fit" only if no effect fits either
    if gap["significant"] or cfg.refit_within_noise:
        screening_path = out / "fits" / "screening.json"
        stored = json.loads(screening_path.read_text()) if screening_path.is_file() else {}
        if stored.get("key") == key and "strengths" in stored:
            screening, strengths = stored["fractions"], stored["strengths"]
        else:
            screening, strengths = screen(system, fmu, cal, nominal, scale, cfg.upsample, effects)
            screening_path.write_text(json.dumps({"key": key, "fractions": screening, "strengths": strengths},
                                                 indent=1))
        # the linear system where an amplitude-dependent effect is weakest: the lowest calibration level's (its
        # peaks on the calibrated nominal's nearest resonances)
        lowest = min(cal, key=lambda r: r.level_value)
        linear_starts = tuple(system.data_starts([lowest], lambda p: linear_modes(fmu, p),
                                                 {n: nominal.params[n] for n in system.linear}))
        clock.end("screening")
        jobs = []
        for name in effects:
            path = out / "fits" / f"{name}.json"
            fits[name] = _stored(path, key)
            if fits[name] is None:
                jobs.append((effect_task(system, system.effects[name], fmu, cal, nominal, scale, cfg.refit_budget,
                                         cfg.upsample, strengths.get(name), linear_starts), str(path), key))
        jobs.sort(key=lambda job: job[0].basin is None)  # the longest (a refit from each basin) first
        for fit in _run_fits(jobs, workers or os.cpu_count() or 1, workers, progress, "refits"):
            fits[fit.effect] = fit
        for name, f in fits.items():  # an effect is judged on the held-out files only
            sims[name] = _simulated(runner, held, f.params, system, cfg)
        clock.end("refits with each effect")
        if not gap["significant"]:
            gap["detection"] = _detection(system, fits, sims, held, gap, scale, runner, cfg)
            gap["significant"] = gap["detection"]["detected"]
        if gap["significant"]:
            system, selected = _combinations(system, cfg, fmu, cal, held, nominal, scale, fits, sims, gap,
                                             screening, runner, out, key, workers, progress)
        clock.end("combinations of effects")
    result = report.assemble(system, cfg, records, cal, held, nominal, fits, sims, screening, bands, scale, gap,
                             selected)
    banded = report.needs_band(result, cfg.min_shrink_pct)
    if banded:  # a confined misfit: does the best prediction the calibration files allow meet the criterion?
        within = band.prediction_band(runner, fits[banded], system.effects[banded].derived(scale), cal, held,
                                      cfg.upsample, system.lead_periods)
        result = report.assemble(system, cfg, records, cal, held, nominal, fits, sims, screening, bands, scale, gap,
                                 selected, within)
        clock.end("prediction band")
    result["level_order"] = data.order
    result["set_aside"] = {name: {"period_scatter": s, "lower_floor": f} for name, (s, f) in data.aside.items()}
    result["voltage_channels"] = data.voltages
    result["clipped_channels"] = data.clipped
    result["analysis_rate"] = {**asdict(data.rate), "drive_upsample": cfg.upsample, "recorded_hz": data.recorded_hz}
    top = result["ranking"][0]["shrink_pct"] if result["ranking"] else None
    calibration = confidence.load(confidence.settings_of(asdict(requested)), model)  # of the settings asked for
    result["confidence"] = confidence.stated(result["verdict"], result["chosen_effect"], top, calibration)
    result["separation"] = report.separation(runner, result, records, fits, bands, cfg.upsample, system.lead_periods)
    runner.close()
    clock.end("verdict")
    result["stage_s"] = clock.stages
    report.write(result, records, held, sims, bands, out)
    return result


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
        return SplitMisfit(*(selection.heldout_nrmse(_simulated(p.runner, files, values, p.system, p.cfg), files)
                             for files in (p.data.held, p.data.cal)))
    finally:
        p.runner.close()
