"""The same fit done by the tools an engineer would pick instead of NNO, each through its own public API, on the
same FMU, target, bounds and (where the tool takes one) objective, with the same budget of FMU evaluations.

Every true evaluation is traced (its parameters and wall time); the answer a tool gives after N evaluations is
its best point so far by its own objective (for a staged fit, by the objective of the stage it is in). From the
trace follow: the evaluations and seconds until that answer recovers every parameter (and identifiable product)
within `RECOVERY_TARGET`, and the recovery it has at the evaluations and at the wall time NNO used.

Peers: CMA-ES (`cma`), scipy's differential evolution, multi-start least squares (scipy), the direct GA
(pymoo), estim8 (drives the FMU itself, time-domain sum of squares, its scipy differential evolution) and
ModestPy (reported with the reason when it cannot run).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.stats

from pyfit.fit.fitting import open_objectives, recovery, search
from pyfit.fit.optim import baselines
from pyfit.io.fit_config import FitConfig

RECOVERY_TARGET = 0.01  # every parameter and identifiable product within 1 % of the truth


class BudgetSpent(Exception):
    """A tool used its budget of FMU evaluations (or of wall time)."""


@dataclass
class Trace:
    """Every true FMU evaluation of one run: wall time since the start, SI parameters, error, stage."""

    budget: int
    wall_limit_s: float = np.inf
    t0: float = field(default_factory=time.perf_counter)
    wall_s: list = field(default_factory=list)
    params: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    stages: list = field(default_factory=list)

    def record(self, params: dict, error: float, stage: str) -> None:
        """Keep one evaluation; BudgetSpent once the budget (evaluations or wall time) is used."""
        if len(self.params) >= self.budget or time.perf_counter() - self.t0 > self.wall_limit_s:
            raise BudgetSpent
        self.wall_s.append(time.perf_counter() - self.t0)
        self.params.append(dict(params))
        self.errors.append(float(error) if np.isfinite(error) else np.inf)
        self.stages.append(stage)

    def answers(self) -> list[int]:
        """For each evaluation N, the index of the tool's answer after N evaluations: the best point so far by
        error within the current stage (a stage's errors are of its own objective; its first evaluation is at
        the previous stage's answer, where it starts)."""
        out, best, stage, stage_best = [], None, None, np.inf
        for i, (e, s) in enumerate(zip(self.errors, self.stages)):
            if s != stage:
                stage, stage_best = s, np.inf
            if e < stage_best:
                best, stage_best = i, e
            out.append(best)
        return out


class _Traced:
    """An objective whose residuals are traced (and stop at the trace's budget)."""

    def __init__(self, objective, trace: Trace, stage: str):
        self._objective, self._trace, self._stage = objective, trace, stage
        self.log_ratio = getattr(objective, "log_ratio", None)

    def residuals(self, x):
        r = self._objective.residuals(x)
        self._trace.record(self._objective.params(np.clip(x, 0.0, 1.0)), float(np.sum(r ** 2)), self._stage)
        return r


@dataclass
class PeerRun:
    """One tool on one problem with one seed (recovery: the largest relative parameter error, 0.01 = 1 %)."""

    problem: str
    tool: str
    seed: int
    budget: int = 0  # FMU evaluations allowed
    evaluations: int = 0
    wall_s: float = 0.0
    to_target_evaluations: int | None = None
    to_target_s: float | None = None
    final_recovery: float | None = None
    recovery_at_nno_evaluations: float | None = None
    recovery_at_nno_wall: float | None = None
    objective: str = ""  # what the tool minimised
    note: str = ""  # why it could not run, when it could not


def worst_recovery(params: dict, cfg: FitConfig) -> float:
    """The largest |relative error| over the fitted parameters and identifiable products (theory §1.1)."""
    fitted = {v.name: params[v.name] for v in cfg.variables}
    return float(max(abs(v) for v in recovery(fitted, cfg).values()))


def summarise(trace: Trace, cfg: FitConfig, run: PeerRun, nno_evaluations: int | None = None,
              nno_wall_s: float | None = None) -> PeerRun:
    """Fill run's figures from its trace."""
    if not trace.params:
        run.note = run.note or "no FMU evaluation"
        return run
    answers = trace.answers()
    rec = [worst_recovery(trace.params[i], cfg) for i in answers]
    run.evaluations, run.wall_s = len(trace.params), trace.wall_s[-1]
    run.final_recovery = rec[-1]
    hit = next((n for n, r in enumerate(rec) if r <= RECOVERY_TARGET), None)
    if hit is not None:
        run.to_target_evaluations, run.to_target_s = hit + 1, trace.wall_s[hit]
    if nno_evaluations:
        run.recovery_at_nno_evaluations = rec[min(nno_evaluations, len(rec)) - 1]
    if nno_wall_s is not None:
        within = [n for n, t in enumerate(trace.wall_s) if t <= nno_wall_s]
        run.recovery_at_nno_wall = rec[within[-1]] if within else None
    return run


def _global(objective_of, trace: Trace, cfg: FitConfig) -> _Traced:
    return _Traced(objective_of(cfg.objective_kind), trace, cfg.objective_kind)


def run_nno(cfg: FitConfig, objective_of, seed: int, trace: Trace) -> str:
    """cfg's own method (NNO + polish), every stage traced."""
    search(cfg, lambda kind: _Traced(objective_of(kind), trace, kind), seed)
    return f"{cfg.objective_kind}, then polish on {', '.join(cfg.polish_kinds)}"


def run_cma(cfg: FitConfig, objective_of, seed: int, trace: Trace) -> str:
    """CMA-ES (cma) from the middle of the box, step 0.3 of the range, within the bounds."""
    import cma

    obj = _global(objective_of, trace, cfg)
    n = len(cfg.variables)
    es = cma.CMAEvolutionStrategy(np.full(n, 0.5), 0.3, {"bounds": [0.0, 1.0], "seed": seed + 1, "verbose": -9,
                                                         "maxfevals": trace.budget})
    try:
        while not es.stop():
            xs = es.ask()
            es.tell(xs, [float(np.sum(obj.residuals(x) ** 2)) for x in xs])
    except BudgetSpent:
        pass
    return cfg.objective_kind


def run_de(cfg: FitConfig, objective_of, seed: int, trace: Trace) -> str:
    """scipy's differential evolution (population 10 per parameter, no polish)."""
    try:
        baselines.differential_evolution(_global(objective_of, trace, cfg).residuals, len(cfg.variables),
                                         trace.budget, seed)
    except BudgetSpent:
        pass
    return cfg.objective_kind


def run_multistart(cfg: FitConfig, objective_of, seed: int, trace: Trace, starts: int = 5) -> str:
    """scipy least_squares (trust-region reflective) from `starts` Latin-hypercube starts, each with an equal
    share of the budget."""
    obj = _global(objective_of, trace, cfg)
    xs = scipy.stats.qmc.LatinHypercube(len(cfg.variables), seed=seed).random(starts)
    try:
        for x0 in xs:
            baselines.polish(obj.residuals, x0, budget=max(trace.budget // starts, 1))
    except BudgetSpent:
        pass
    return cfg.objective_kind


def run_ga(cfg: FitConfig, objective_of, seed: int, trace: Trace) -> str:
    """The GA (pymoo) applied directly to the FMU objective."""
    try:
        baselines.ga_direct(_global(objective_of, trace, cfg).residuals, len(cfg.variables), trace.budget,
                            cfg.ga_pop_size, seed)
    except BudgetSpent:
        pass
    return cfg.objective_kind


def run_estim8(cfg: FitConfig, objective_of, seed: int, trace: Trace) -> str:
    """estim8: its FmuModel simulates the FMU (fmpy, CVode) with the experiment's built-in source, its
    Estimator minimises the time-domain sum of squares of the measured outputs with scipy's differential
    evolution. Raises NotApplicable when the experiment needs a measured input signal."""
    import estim8
    import pandas as pd

    if cfg.use_inputs:
        raise NotApplicable("estim8's FmuModel.simulate takes parameters and start values but no input signal: "
                            "the measured force of this target cannot drive its FMU")
    obj = objective_of(cfg.objective_kind)
    m = obj.m
    columns = {ch.output: m.values[ch.column] for ch in cfg.channels}
    data = pd.DataFrame(columns, index=pd.Index(m.t - m.t[0], name="time"))
    model = estim8.models.FmuModel(str(obj.runner.path), default_parameters=dict(cfg.fixed),
                                   r_tol=cfg.tolerance)
    bounds = {v.name: [v.lower, v.upper] for v in cfg.variables}

    class Traced(estim8.Estimator):
        def objective(self, theta):
            loss = super().objective(theta)
            trace.record({**cfg.fixed, **dict(zip(bounds, theta))}, loss, "SS")
            return loss

    dt = 1.0 / m.sample_rate_hz
    est = Traced(model, bounds, data, t=[0.0, float(m.t[-1] - m.t[0]) + 0.5 * dt, dt], metric="SS")
    try:
        est.estimate("de", max_iter=10**6, optimizer_kwargs={"seed": seed, "polish": False})
    except BudgetSpent:
        pass
    return "time-domain sum of squares (its own)"


def run_modestpy(cfg: FitConfig, objective_of, seed: int, trace: Trace) -> str:
    """ModestPy: not maintained since 2021; run when it imports, else NotApplicable with the import error."""
    try:
        import modestpy  # noqa: F401
    except Exception as exc:  # an unmaintained package: any import failure is the reason reported
        raise NotApplicable(f"ModestPy does not import: {type(exc).__name__}: {exc}") from None
    raise NotApplicable("ModestPy imports, but its Estimation takes CSV inputs and a time-domain objective "
                        "through its own FMU wrapper; not wired here")


class NotApplicable(Exception):
    """The tool cannot do this problem (the message says why)."""


TOOLS = {"NNO + polish (stockbridge)": run_nno, "CMA-ES (cma)": run_cma,
         "differential evolution (scipy)": run_de, "multi-start least squares (scipy)": run_multistart,
         "GA, direct (pymoo)": run_ga, "estim8 (DE)": run_estim8, "ModestPy": run_modestpy}
NNO = "NNO + polish (stockbridge)"


WALL_FACTOR = 1.0  # a peer also stops at this multiple of NNO's wall time: equal evaluations or equal wall time


def compare(cfg: FitConfig, fmu_dir, seed: int, problem: str, tools=TOOLS) -> list[PeerRun]:
    """Every tool on cfg's problem with one seed: NNO first (its evaluations and wall time set the others'
    budgets), then each peer with NNO's configured evaluation budget, stopped early at WALL_FACTOR x NNO's
    wall time."""
    objective_of, objectives, _ = open_objectives(cfg, fmu_dir)
    runs, nno_run = [], None
    for tool, fn in tools.items():
        wall = WALL_FACTOR * nno_run.wall_s if nno_run and nno_run.wall_s else np.inf
        trace = Trace(budget=cfg.budget if tool != NNO else 10**9, wall_limit_s=wall)
        run = PeerRun(problem, tool, seed, budget=trace.budget if tool != NNO else 0)
        try:
            run.objective = fn(cfg, objective_of, seed, trace)
        except NotApplicable as exc:
            run.note = str(exc)
        except ImportError as exc:
            run.note = f"not installed ({exc.name}): pip install -e \".[peers]\""
        summarise(trace, cfg, run, nno_run.evaluations if nno_run else None, nno_run.wall_s if nno_run else None)
        if tool == NNO:
            run.budget, nno_run = run.evaluations, run
        runs.append(run)
    for o in objectives.values():
        o.close()
    return runs


def _median(values) -> float | None:
    values = [v for v in values if v is not None]
    return float(np.median(values)) if values else None


def _pct(v: float | None) -> str:
    if v is None:
        return "—"
    return f"{100 * v:.2g} %" if 100 * v < 10 else f"{100 * v:.0f} %"


def table(runs: list[PeerRun]) -> tuple[list[str], list[list]]:
    """One problem's runs as a table: per tool the share of seeds whose answer reached RECOVERY_TARGET, the
    median evaluations and seconds to it (over those seeds), the median worst parameter error at the end, at
    NNO's evaluations and at NNO's wall time, and the evaluations to the target relative to NNO's."""
    header = ["tool", "objective", "seeds reaching 1 %", "evaluations to 1 % (median)", "wall to 1 % [s]",
              "worst parameter error at the end", "at NNO's evaluations", "at NNO's wall time",
              "evaluations to 1 % ÷ NNO's", "budget / note"]
    tools = list(dict.fromkeys(r.tool for r in runs))
    nno = _median(r.to_target_evaluations for r in runs if r.tool == NNO)
    rows = []
    for tool in tools:
        mine = [r for r in runs if r.tool == tool]
        ran = [r for r in mine if r.evaluations]
        if not ran:
            rows.append([tool, "—", "—", "—", "—", "—", "—", "—", "—", mine[0].note])
            continue
        hits = [r for r in ran if r.to_target_evaluations is not None]
        evals = _median(r.to_target_evaluations for r in hits)
        budget = ran[0].budget
        if tool == NNO:
            ratio = "1" if evals else "—"
        elif nno and evals:
            ratio = f"{evals / nno:.2g}"
        elif nno:
            ratio = f"> {budget / nno:.2g} (not within {budget})"
        else:
            ratio = "—"
        if tool == NNO:
            note = f"its own: {_median(r.evaluations for r in ran):.0f} evaluations (median)"
        else:
            cut = sum(r.evaluations < r.budget for r in ran)
            note = f"{budget} evaluations" + (f"; {cut} of {len(ran)} runs stopped earlier, at NNO's wall time "
                                              f"({_median(r.evaluations for r in ran):.0f} evaluations, median)"
                                              if cut else "")
        rows.append([tool, ran[0].objective, f"{len(hits)}/{len(ran)}", "—" if evals is None else f"{evals:.0f}",
                     "—" if not hits else f"{_median(r.to_target_s for r in hits):.0f}",
                     _pct(_median(r.final_recovery for r in ran)),
                     "—" if tool == NNO else _pct(_median(r.recovery_at_nno_evaluations for r in ran)),
                     "—" if tool == NNO else _pct(_median(r.recovery_at_nno_wall for r in ran)),
                     ratio, note + (f"; {ran[0].note}" if ran[0].note else "")])
    return header, rows
