"""Which effect: calibrate the nominal model, screen every candidate effect by how much of the nominal
residual its sensitivity direction explains (a score test), then refit the model with each effect added.
Fits are local least squares (scipy, via optim.baselines.polish) on the time-domain residual of the
calibration records, in parameters scaled to their bounds."""
from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from ..fmu import FmuRunner
from ..optim.baselines import polish
from . import simulate as sim
from .systems import LINEAR_PARAMS, Effect, Scale, System


@dataclass
class Fit:
    """A calibrated model: its FMU parameters, the free ones, and how the fit went."""

    effect: str  # "nominal" or the effect's name
    params: dict  # every FMU parameter set (SI)
    free: list  # names of the fitted ones
    n_added: int  # parameters the effect adds to the nominal model
    calibration_nrmse: float
    evaluations: int
    wall_s: float

    def to_json(self) -> dict:
        return asdict(self)


def frf_linear_guess(records: list[sim.Record]) -> dict:
    """m, c, k of a linear SDOF from the measured FRF (input -> output DFT lines the input excites):
    1/H = k - w^2 m + i w c, solved by least squares weighted by |H| (relative error)."""
    rows, rhs = [], []
    for rec in records:
        u, y = next(iter(rec.inputs.values())), next(iter(rec.outputs.values()))
        U, Y = np.fft.rfft(u), np.fft.rfft(y)
        w = 2 * np.pi * np.fft.rfftfreq(len(u), 1.0 / rec.fs)
        ex = (np.abs(U) > 1e-3 * np.abs(U).max()) & (w > 0)
        G = U[ex] / Y[ex]  # 1/H
        wt = 1.0 / np.abs(G)
        rows += [np.column_stack([-w[ex] ** 2 * wt, 0 * wt, wt]), np.column_stack([0 * wt, w[ex] * wt, 0 * wt])]
        rhs += [G.real * wt, G.imag * wt]
    m, c, k = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    return {"m": float(abs(m)), "c": float(abs(c)), "k": float(abs(k))}


def data_scale(records: list[sim.Record], k: float) -> Scale:
    """RMS of the measured output and of its velocity over the records, and the stiffness k."""
    y = np.concatenate([next(iter(r.outputs.values())) for r in records])
    v = np.concatenate([np.gradient(next(iter(r.outputs.values()))) * r.fs for r in records])
    return Scale(float(np.sqrt(np.mean(y**2))), float(np.sqrt(np.mean(v**2))), k)


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


def _stacked(runner, task: FitTask, params: dict) -> np.ndarray:
    return np.concatenate([sim.residuals(sim.simulate(runner, r, params, task.upsample), r) for r in task.records])


def run_fit(task: FitTask) -> Fit:
    """Least squares on the stacked calibration residuals from task.start within task.bounds."""
    t0 = time.perf_counter()
    runner = FmuRunner(task.fmu)
    names = list(task.start)
    lo = np.array([task.bounds[n][0] for n in names])
    hi = np.array([task.bounds[n][1] for n in names])

    def params(x):
        return {**task.fixed, **dict(zip(names, lo + np.clip(x, 0, 1) * (hi - lo)))}

    x0 = (np.array([task.start[n] for n in names]) - lo) / (hi - lo)
    result = polish(lambda x: _stacked(runner, task, params(x)), x0, budget=task.budget)
    best = params(result.x)
    err = float(np.sqrt(np.sum(_stacked(runner, task, best) ** 2) / len(task.records)))
    runner.close()
    return Fit(task.effect, {k: float(v) for k, v in best.items()}, names, task.n_added, err,
               result.n_evaluations + 1, time.perf_counter() - t0)


def linear_bounds(guess: dict, hysteresis: bool = False) -> dict:
    """Bounds of m, c, k around a linear estimate (k lower when a hysteretic element shares the stiffness)."""
    return {"m": (0.5 * guess["m"], 2.0 * guess["m"]), "c": (0.1 * guess["c"], 5.0 * guess["c"]),
            "k": ((0.05 if hysteresis else 0.5) * guess["k"], 2.0 * guess["k"])}


def nominal_task(system: System, fmu: str, records: list, guess: dict, budget: int, upsample: int) -> FitTask:
    """The nominal (linear) calibration from the FRF estimate."""
    return FitTask(fmu, tuple(records), dict(system.nominal_fixed), {n: guess[n] for n in LINEAR_PARAMS},
                   linear_bounds(guess), "nominal", 0, budget, upsample)


def effect_start(effect: Effect, scale: Scale, nominal: dict) -> tuple[dict, dict, dict]:
    """Start values, bounds and fixed parameters of the nominal model with `effect` added."""
    start = {n: nominal[n] for n in LINEAR_PARAMS}
    start["k"] = nominal["k"] * (1.0 - effect.shift_stiffness)
    bounds = linear_bounds(nominal, hysteresis=effect.shift_stiffness > 0)
    for p in effect.params:
        lo, st, hi = p.range(scale)
        start[p.name], bounds[p.name] = st, (lo, hi)
    return start, bounds, effect.fixed(scale)


def effect_task(system: System, effect: Effect, fmu: str, records: list, nominal: Fit, scale: Scale,
                budget: int, upsample: int) -> FitTask:
    """The refit of the nominal model with `effect` added."""
    start, bounds, fixed = effect_start(effect, scale, nominal.params)
    return FitTask(fmu, tuple(records), {**system.nominal_fixed, **fixed}, start, bounds, effect.name,
                   len(effect.params), budget, upsample)


def screen(system: System, fmu: str, records: list, nominal: Fit, scale: Scale, upsample: int,
           probe: float = 0.05) -> dict[str, float]:
    """Fraction of the nominal residual (after re-adjusting m, c, k) that one Gauss-Newton step along each
    effect's sensitivity direction removes: 1 - |r - P_[J_lin, d] r|^2 / |r - P_J_lin r|^2. The direction
    is the output change from the nominal to the effect at a small probe strength (probe x its range; a
    hysteretic element at its start, where it is more than a stiffness)."""
    runner = FmuRunner(fmu)
    base = dict(nominal.params)

    def stacked(p):
        return np.concatenate([sim.residuals(sim.simulate(runner, r, p, upsample), r) for r in records])

    r0 = stacked(base)
    J = []
    for n in LINEAR_PARAMS:
        h = 1e-3 * base[n]
        J.append((stacked({**base, n: base[n] + h}) - r0) / h * base[n])
    J = np.column_stack(J)

    def unexplained(A):
        coef = np.linalg.lstsq(A, r0, rcond=None)[0]
        return float(np.sum((r0 - A @ coef) ** 2))

    lin = unexplained(J)
    out = {}
    for name, effect in system.effects.items():
        start, _, fixed = effect_start(effect, scale, base)
        p = {**base, **fixed, "k": start["k"]}
        for prm in effect.params:
            lo, st, hi = prm.range(scale)
            p[prm.name] = st if st != 0 else probe * (hi if hi > 0 else lo)
        d = stacked(p) - r0
        out[name] = 1.0 - unexplained(np.column_stack([J, d])) / lin if lin > 0 else 0.0
    runner.close()
    return out
