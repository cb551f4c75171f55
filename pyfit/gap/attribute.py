"""Which effect: calibrate the nominal model, screen every candidate effect by how much of the nominal
residual its sensitivity direction explains (a score test), then refit the model with each effect added.
Fits are local least squares (scipy, via optim.baselines.polish) on the time-domain residual of the
calibration records, in parameters scaled to their bounds."""
from __future__ import annotations

import dataclasses
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass

import numpy as np

from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.linearize import linear_modes
from pyfit.fit.optim.baselines import polish
from pyfit.gap import simulate as sim
from pyfit.gap.effect import Effect, Scale, with_derived
from pyfit.gap.systems import System


@dataclass
class Fit:
    """A calibrated model: its FMU parameters, the free ones, and how the fit went."""

    effect: str  # "nominal" or the effect's name
    params: dict  # every FMU parameter set (SI)
    free: list  # names of the fitted ones
    n_added: int  # strength parameters the effect adds to the nominal model (shape parameters not counted)
    calibration_nrmse: float
    evaluations: int
    wall_s: float
    from_envelopes: bool = False  # refitted on the waveforms from a fit to the amplitude envelopes (the diagnosis's
    # envelope-led stage, when no model refitted on the waveforms alone explained the data)

    def to_json(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class FitTask:
    """Everything one fit needs, picklable for a process pool (SI units)."""

    fmu: str
    records: tuple
    fixed: dict
    start: dict  # free parameter -> start value
    bounds: dict  # free parameter -> (lower, upper)
    effect: str
    n_added: int
    budget: int
    upsample: int
    lead_periods: int = 1
    alternatives: tuple = ()  # other starts (dicts of parameter overrides): the least squares starts from the best
    threads: int = 1  # records simulated at once (one FMU instance each; the compiled loop releases the GIL)
    continuation: bool = True  # envelopes first, then the lowest level, then all (see run_fit)
    log_scaled: tuple = ()  # free parameters scaled to their bounds on a log scale (positive, spanning decades)
    floor: dict | None = None  # a point the result must not be worse than (the nominal: the effect at zero)
    derived: tuple = ()  # rules giving fixed parameters from fitted ones (effect.LoopCoordinates)
    basin: callable = None  # start values -> their basin: refit from the best start of each (a module-level
    # function, so the task pickles to a worker)
    probes: int = 1  # without a basin: the best starts descended before the best of them goes on
    probed: tuple = ()  # starts (dicts of parameter overrides) descended as probes too, whatever their misfit
    envelopes: bool = False  # minimise the amplitude envelopes' residual (sim.envelope_residuals), not the
    # waveforms': starts ranked, stages and least squares on it (the Fit's calibration_nrmse is then the envelopes')


class UnitScaling:
    """Free parameters scaled to [0, 1] within their bounds, linearly or (names in `log`) on a log scale."""

    def __init__(self, names, bounds: dict, log=()):
        self.names = list(names)
        self.log = np.array([n in log for n in self.names], bool)
        self.lo = np.array([bounds[n][0] for n in self.names], float)
        self.hi = np.array([bounds[n][1] for n in self.names], float)
        self.lo[self.log], self.hi[self.log] = np.log(self.lo[self.log]), np.log(self.hi[self.log])

    def values(self, x) -> dict:
        """Parameter values (SI) at unit-scaled x (clipped to [0, 1])."""
        v = self.lo + np.clip(x, 0, 1) * (self.hi - self.lo)
        v[self.log] = np.exp(v[self.log])
        return dict(zip(self.names, v))

    def scaled(self, values: dict) -> np.ndarray:
        """Unit-scaled x of parameter values (clipped into the bounds)."""
        v = np.array([values[n] for n in self.names], float)
        v[self.log] = np.log(v[self.log])
        return np.clip((v - self.lo) / (self.hi - self.lo), 0.0, 1.0)


def stacked_residuals(runner, records, params: dict, upsample: int, lead_periods: int, pool=None,
                      of=sim.residuals) -> np.ndarray:
    """The calibration records' residuals (`of`: sim.residuals, or sim.envelope_residuals), stacked. runner: one
    FmuRunner, or one per record when `pool` (a thread pool) simulates the records at once; the result is the
    same either way."""
    runners = runner if isinstance(runner, list) else [runner] * len(records)

    def one(k):
        return of(sim.simulate(runners[k], records[k], params, upsample, lead_periods), records[k])

    return np.concatenate(list(pool.map(one, range(len(records))) if pool else map(one, range(len(records)))))


# more than SCREEN_FROM starts (a loop's grid of shapes, widths and shares; a combination's members' starts) are
# ranked first with the FMU's input grid at the sensor rate (upsample 1: under half the cost, and the starts in
# nearly the same order: tests/test_gap_loop_friction.py), then the best SCREEN_KEPT of each basin (or of all, at
# least task.probes) again at task.upsample
SCREEN_FROM = 40
SCREEN_KEPT = 3
BASIN_SHARE = 1 / 3  # of a refit's budget, for the probe of each basin before the best goes on
# basins whose probes go on with the whole budget: a third of the way along, the probes rank the basins poorly (a
# loop started at ν = 2 with the right share and shape can still misfit more there than a weaker loop at ν = 1, and
# yet go on to the noise floor where the weaker one stops at twice it)
BASINS_ON = 2
# share of a parameter's range a least-squares start is moved off its bounds (optim.baselines.polish): an effect
# strength started at zero whose value is far below 1 % of its range (a weak quadratic damping beside a strong
# cubic spring) would otherwise start ten times too strong and end worse than zero
BOUND_MARGIN = 1e-3


class _Evaluator:
    """A fit's simulations: its FMU instances (one per record simulated at once), the unit scaling of its free
    parameters and the residual it minimises (the waveforms', or the amplitude envelopes')."""

    def __init__(self, task: FitTask):
        self.task = task
        threads = max(1, min(task.threads, len(task.records)))
        self.runner = [FmuRunner(task.fmu) for _ in task.records] if threads > 1 else FmuRunner(task.fmu)
        self.pool = ThreadPoolExecutor(threads) if threads > 1 else None
        self.unit = UnitScaling(list(task.start), task.bounds, task.log_scaled)
        self.objective = sim.envelope_residuals if task.envelopes else sim.residuals

    def params(self, x) -> dict:
        return with_derived({**self.task.fixed, **self.unit.values(x)}, self.task.derived)

    def residuals(self, p, records=None, of=None, upsample=None) -> np.ndarray:
        t = self.task
        return stacked_residuals(self.runner, t.records if records is None else records, p,
                                 t.upsample if upsample is None else upsample, t.lead_periods, self.pool,
                                 of or self.objective)

    def cost(self, x, upsample=None) -> float:
        return float(np.sum(self.residuals(self.params(x), upsample=upsample) ** 2))

    def close(self) -> None:
        for r in self.runner if isinstance(self.runner, list) else [self.runner]:
            r.close()
        if self.pool:
            self.pool.shutdown()


def _ranked_starts(task: FitTask, ev: _Evaluator) -> tuple[list, list, range, int]:
    """The starts (unit-scaled), each one's cost (inf where not evaluated), the indices of task.probed among them
    and the evaluations spent: more than SCREEN_FROM starts are ranked at upsample 1 first, then the best
    SCREEN_KEPT of each basin (at least task.probes) again at task.upsample."""
    candidates = [ev.unit.scaled(task.start)] + [ev.unit.scaled({**task.start, **alt})
                                                 for alt in task.alternatives + task.probed]
    forced = range(len(candidates) - len(task.probed), len(candidates))
    kept, used = range(len(candidates)), 0
    if len(candidates) > SCREEN_FROM and task.upsample > 1:
        coarse = [ev.cost(x, upsample=1) for x in candidates]
        group = (lambda k: task.basin(ev.unit.values(candidates[k]))) if task.basin else (lambda k: None)
        ranked = {}
        for k in np.argsort(coarse):
            ranked.setdefault(group(k), []).append(int(k))
        kept = {0, *forced, *(k for ks in ranked.values() for k in ks[:max(SCREEN_KEPT, task.probes)])}
        used = len(candidates)
    errors = [ev.cost(x) if k in kept else np.inf for k, x in enumerate(candidates)]
    return candidates, errors, forced, used + len(kept)


def _stages(task: FitTask, objective) -> list[tuple]:
    """The continuation's stages (records, residual, part of the budget): a sweep's envelopes first (smooth in the
    parameters where the waveform is not), then the lowest level alone (where an amplitude-dependent effect is
    weakest and the residual smooth)."""
    stages = []
    if task.continuation and not task.envelopes and not any(r.periodic for r in task.records):
        stages.append((task.records, sim.envelope_residuals, 3))
    levels = sorted({r.level_value for r in task.records})
    if task.continuation and len(levels) > 1:
        stages.append(([r for r in task.records if r.level_value == levels[0]], objective, 4))
    return stages


def _descend(ev: _Evaluator, stages, x0, e0, budget) -> tuple:
    """The stages (each 1/part of the budget) then least squares on every record with what is left, each from the
    best point so far; never worse than the start. Returns (x, cost, evaluations)."""
    n, whole = 0, budget
    for records, of, part in stages:
        stage = polish(lambda x: ev.residuals(ev.params(x), records, of), x0, budget=whole // part,
                       margin=BOUND_MARGIN)
        e = ev.cost(stage.x)
        x0, e0 = (stage.x, e) if e < e0 else (x0, e0)
        n, budget = n + 1 + stage.n_evaluations, budget - stage.n_evaluations
    result = polish(lambda x: ev.residuals(ev.params(x)), x0, budget=budget, margin=BOUND_MARGIN)
    n += result.n_evaluations
    return (result.x, result.error, n) if result.error <= e0 else (x0, e0, n)


def _probe_starts(task: FitTask, ev: _Evaluator, candidates, order, forced) -> dict:
    """The starts descended as probes: with task.basin the best of each basin, else the task.probes best and
    task.probed ({} when none: the best start goes on alone)."""
    firsts = {}
    if task.basin:
        for k in order:
            firsts.setdefault(task.basin(ev.unit.values(candidates[k])), k)
    elif task.probes > 1 or task.probed:
        firsts = dict(enumerate(order[:task.probes]))
        firsts.update({f"probed {k}": k for k in forced if k not in firsts.values()})
    return firsts


def run_fit(task: FitTask) -> Fit:
    """Least squares on the stacked calibration residuals within task.bounds, from the best of task.start and
    task.alternatives (_ranked_starts); with task.continuation in stages (_stages), each from the best point so
    far. Never worse than the best start. With task.basin the same from the best start of each basin (an SDOF loop
    has one at each ν: effects.sdof_loop_basin), each with BASIN_SHARE of the budget first, then the BASINS_ON best
    of them with the whole budget; without it, likewise from the task.probes best starts and task.probed. With
    task.envelopes, all of it on the amplitude envelopes instead of the waveforms; never worse than task.floor."""
    t0 = time.perf_counter()
    ev = _Evaluator(task)
    candidates, errors, forced, used = _ranked_starts(task, ev)
    stages = _stages(task, ev.objective)
    order = np.argsort(errors)
    firsts = _probe_starts(task, ev, candidates, order, forced)
    probed = [_descend(ev, stages, candidates[k], errors[k], max(1, int(task.budget * BASIN_SHARE)))
              for k in firsts.values()]
    used += sum(n for _, _, n in probed)
    ahead = sorted(probed, key=lambda end: end[1])[:BASINS_ON if task.basin else 1] or \
        [(candidates[order[0]], errors[order[0]], 0)]
    ends = [_descend(ev, stages, x, e, task.budget) for x, e, _ in ahead]
    used += sum(n for _, _, n in ends)
    best_x, error, _ = min(ends, key=lambda end: end[1])
    best = ev.params(best_x)
    if task.floor is not None:  # never worse than the nominal model (the effect at zero)
        floor = with_derived({**task.fixed, **task.floor}, task.derived)
        e = float(np.sum(ev.residuals(floor) ** 2))
        used += 1
        if e < error:
            best, error = floor, e
    # the stacked residual's sum of squares is the weighted sum of every channel's squared NRMSE
    channels = sum(sum(r.weights.get(k, 1.0) for k in r.outputs) for r in task.records)
    ev.close()
    return Fit(task.effect, {k: float(v) for k, v in best.items()}, list(task.start), task.n_added,
               float(np.sqrt(error / channels)), used, time.perf_counter() - t0)


def _free_basin(basin, free: dict):
    """`basin` when it reads only parameters in `free` (a loop's shape fitted beside a held partner), else None (a
    loop held at its refit has no basins left to descend from)."""
    if basin is None:
        return None
    try:
        basin(free)
    except KeyError:
        return None
    return basin


def pinned(task: FitTask, values: dict, budget: int) -> FitTask:
    """`task` with the parameters of `values` held at those values (no longer fitted), its starts that then
    coincide taken once, and `budget` evaluations from the best of them only (no probes; from each basin's best
    when the basins' parameters are all still free: a loop refitted beside a held spring): e.g. an effect refitted
    beside the model it extends held at that model's refit, before the two are refitted together (that joint
    refit then probes from the best starts, this result among them)."""
    free = {n: v for n, v in task.start.items() if n not in values}
    alternatives = {tuple(sorted(a.items())): a for a in
                    ({n: v for n, v in alt.items() if n not in values} for alt in task.alternatives)}
    return dataclasses.replace(task, fixed={**task.fixed, **values}, start=free,
                               bounds={n: task.bounds[n] for n in free}, alternatives=tuple(alternatives.values()),
                               log_scaled=tuple(n for n in task.log_scaled if n in free), budget=budget, probes=1,
                               probed=(), basin=_free_basin(task.basin, free))


STIFFNESS_SCAN = (0.25, 0.5, 1.0, 2.0, 4.0)  # factors on the nominal stiffness tried before the least squares
DAMPING_SCAN = (0.1, 0.3, 3.0, 10.0)  # factors on the nominal damping (system.damping together) tried likewise
STRENGTH_FACTORS = (0.25, 0.5, 1.0)  # factors on the screening's Gauss-Newton effect strength tried likewise
# the nominal calibration's best starts descended before the best of them goes on: a start with the right EI but
# damping five times off can misfit a noise record more than one whose two lowest resonances lie below the band,
# from which the least squares does not climb out (a noise record of campaign 100 seed 1, case 41: 0.66 against
# 0.009 from the third best start); only a descent tells such starts apart
NOMINAL_PROBES = 3


def _covering(system: System, starts: list[dict], softened: bool = False) -> dict:
    """Bounds that hold every start: per parameter the lowest and highest of system.bounds over them."""
    each = [system.bounds(s, softened) for s in starts]
    return {n: (min(b[n][0] for b in each), max(b[n][1] for b in each)) for n in each[0]}


def _widened(bounds: dict, other: dict) -> dict:
    """`bounds` widened to hold `other`'s bounds of the parameters both have."""
    return {n: (min(lo, other[n][0]), max(hi, other[n][1])) if n in other else (lo, hi)
            for n, (lo, hi) in bounds.items()}


def nominal_task(system: System, fmu: str, records: list, budget: int, upsample: int, threads: int = 1) -> FitTask:
    """The nominal (linear) calibration: from the best (time-domain residual) of the system's start (the SDOF:
    the FRF of all files; the damper: the described values), the starts from the data (system.data_starts:
    each file's FRF; the lowest resonance moved onto each measured peak), the stiffness scaled by
    STIFFNESS_SCAN and, for a family with damping parameters (the damper's Rayleigh coefficients), each of those
    with the damping scaled by DAMPING_SCAN, then least squares from the NOMINAL_PROBES best starts (never worse
    than the best start); `threads` records simulated at once (it runs alone, so it may use every core)."""
    start = {n: v for n, v in system.start(records).items() if n in system.linear}
    found = system.data_starts(records, lambda p: linear_modes(fmu, p))
    scan = [{system.stiffness: start[system.stiffness] * f} for f in STIFFNESS_SCAN if f != 1.0] \
        if system.stiffness in start else []
    alternatives = tuple(found) + tuple(scan)
    bounds = _covering(system, [start] + [{**start, **a} for a in alternatives])
    # the start and each stiffness of the scan with its damping scaled by DAMPING_SCAN (within the bounds): where
    # no resonance peak shows (a joint stuck at the lowest level, an overdamped response) no data start sets it
    alternatives += tuple({**a, **{n: float(np.clip(start[n] * g, *bounds[n])) for n in system.damping}}
                          for a in [{}] + scan for g in DAMPING_SCAN) if system.damping else ()
    return FitTask(fmu, tuple(records), dict(system.nominal_fixed), start, bounds, "nominal", 0, budget, upsample,
                   system.lead_periods, alternatives, threads, probes=NOMINAL_PROBES)


def effect_start(system: System, effect: Effect, scale: Scale, nominal: dict, linear: dict | None = None
                 ) -> tuple[dict, dict, dict]:
    """Start values, bounds and fixed parameters of the nominal model with `effect` added; the linear
    parameters from `linear` (default: the calibrated nominal's)."""
    start = {n: (linear or nominal)[n] for n in system.linear}
    if system.stiffness in start:  # a hysteretic element takes over part of the stiffness
        start[system.stiffness] *= 1.0 - effect.shift_stiffness
    bounds = _covering(system, [nominal] + ([linear] if linear else []), softened=effect.shift_stiffness > 0)
    for p in effect.params:
        lo, st, hi = p.range(scale)
        start[p.name], bounds[p.name] = st, (lo, hi)
    return start, bounds, effect.fixed(scale)


def effect_task(system: System, effect: Effect, fmu: str, records: list, nominal: Fit, scale: Scale,
                budget: int, upsample: int, strength: dict | None = None, linear_starts: tuple = (),
                seeds: tuple = ()) -> FitTask:
    """The refit of the nominal model with `effect` added, from the best of: the effect's default start; its
    other starts (effect.starts: loop shapes, cubic strengths spanning the family); the screening's Gauss-Newton
    `strength` (parameter -> value) scaled by STRENGTH_FACTORS (the step linearises an effect that is not
    linear in its strength: it can overshoot), each with the calibrated nominal's linear parameters and with
    each of `linear_starts` (e.g. the linear system estimated from the lowest level, where an
    amplitude-dependent effect is weakest: the nominal's compromise over all levels can be far from it); and
    `seeds` (parameter values of earlier fits, e.g. each member's own refit for a combination; the bounds
    widened to hold a seed's linear values)."""
    start, bounds, fixed = effect_start(system, effect, scale, nominal.params)
    strengths = [{}] + [{n: v * f for n, v in strength.items()} for f in STRENGTH_FACTORS] if strength else [{}]
    shapes = list(effect.starts(scale))
    alternatives = [s for s in strengths if s] + shapes
    for linear in linear_starts:
        lin_start, lin_bounds, _ = effect_start(system, effect, scale, nominal.params, linear)
        bounds = _widened(bounds, lin_bounds)
        alternatives += [{**{n: lin_start[n] for n in system.linear}, **s} for s in strengths + shapes]
    for seed in seeds:
        alternatives.append({n: seed[n] for n in start if n in seed})
        # a seed whose linear values lie outside the bounds (a member's refit from the lowest level's linear
        # system, far from the nominal) widens them to its own: clipped, it would no longer be the model it is
        if any(not bounds[n][0] <= seed[n] <= bounds[n][1] for n in system.linear if n in seed):
            bounds = _widened(bounds, _covering(system, [{n: seed.get(n, start[n]) for n in system.linear}],
                                                softened=effect.shift_stiffness > 0))
    # the effect at zero is the calibrated nominal: the refit keeps it when it ends worse than that
    floor = {**{n: nominal.params[n] for n in system.linear}, **effect.absent(scale)}
    return FitTask(fmu, tuple(records), {**system.nominal_fixed, **fixed}, start, bounds, effect.name,
                   effect.strengths, budget, upsample, system.lead_periods, tuple(alternatives),
                   log_scaled=tuple(p.name for p in effect.params if p.log), floor=floor,
                   derived=effect.derived(scale),
                   basin=effect.basin(scale) if effect.basin else None)


def screen(system: System, fmu: str, records: list, nominal: Fit, scale: Scale, upsample: int, effects: list,
           probe: float = 0.05) -> tuple[dict[str, float], dict[str, dict]]:
    """For each of `effects`: the fraction of the nominal residual (after re-adjusting the linear
    parameters) that one Gauss-Newton step along the effect's sensitivity direction removes,
    1 - |r - P_[J_lin, d] r|^2 / |r - P_J_lin r|^2, and the effect strength that step reaches (the refit's
    start: parameter -> value; not for a hysteretic element, whose start is more than a strength). The
    direction is the output change from the nominal to the effect at a small probe strength (probe x its
    range; a hysteretic element at its start, where it is more than a stiffness)."""
    runner = FmuRunner(fmu)
    base = dict(nominal.params)

    def stacked(p):
        return stacked_residuals(runner, records, p, upsample, system.lead_periods)

    r0 = stacked(base)
    J = []
    for n in system.linear:
        h = 1e-3 * base[n]
        J.append((stacked({**base, n: base[n] + h}) - r0) / h * base[n])
    J = np.column_stack(J)

    def unexplained(A):
        coef = np.linalg.lstsq(A, r0, rcond=None)[0]
        return float(np.sum((r0 - A @ coef) ** 2)), coef

    lin = unexplained(J)[0]
    out, strengths = {}, {}
    for name in effects:
        effect = system.effects[name]
        start, _, fixed = effect_start(system, effect, scale, base)
        p = {**base, **fixed, **{n: start[n] for n in system.linear}}
        for prm in effect.params:
            lo, st, hi = prm.range(scale)
            # a hysteretic element or a shape parameter at its start (a hysteretic element is more than a
            # stiffness there); any other a small step from it
            p[prm.name] = st if effect.shift_stiffness > 0 or prm.shape else st + probe * (hi - st)
        p = with_derived(p, effect.derived(scale))
        d = stacked(p) - r0
        rest, coef = unexplained(np.column_stack([J, d]))
        out[name] = 1.0 - rest / lin if lin > 0 else 0.0
        if effect.shift_stiffness == 0:  # the residual is data - model: the step is -coef along d
            strengths[name] = {}
            for prm in (q for q in effect.params if not q.shape):
                lo, st, hi = prm.range(scale)
                step = probe * (hi - st)
                strengths[name][prm.name] = float(np.clip(st - coef[-1] * step, lo, hi))
    runner.close()
    return out, strengths
