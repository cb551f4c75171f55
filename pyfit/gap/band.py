"""The prediction band of a refitted model: the parameter sets its calibration files cannot tell apart from
its fit, and how well the best of them predicts the held-out files.

A held-out file is a prediction. Where the model's response has two steady states (a hardening spring or a
hysteretic loop dwelling near a resonance), a change of its parameters far too small to show on the
calibration files can move the held-out prediction from one state to the other, so a model close to the
truth can misfit a few seconds of a held-out file by far more than the noise. A model whose structure misfits
is hardly moved within its band: the band changes which state a prediction follows, not what the model can do.

The band is the Gauss-Newton region around the fit in which the calibration residual's sum of squares rises by
at most `tolerance(n)`: two standard errors of a white-noise record's NRMSE estimated from n samples,
sqrt(2 / n) of it, i.e. fits whose calibration NRMSE differ by less than a second recording of the same
levels would move it. Its points probed are the ends of the region's principal axes (each parameter changed
by at most MAX_CHANGE of its value: the linearisation's reach), each checked on the calibration files and
moved back towards the fit while it is outside.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pyfit.gap import simulate as sim
from pyfit.gap import selection
from pyfit.gap.attribute import stacked_residuals
from pyfit.gap.effect import with_derived

STEP = 1e-3  # relative step of the finite-difference Jacobian
MAX_CHANGE = 0.05  # largest relative change of any parameter at a probed point
BACK_OFF = 0.7  # a probed point above the band's calibration bound is moved back to this share of its step,
RETRIES = 3  # at most this often


def tolerance(samples: int) -> float:
    """The relative rise of a calibration NRMSE taken as no rise: sqrt(2 / samples), two standard errors of the
    NRMSE of a white-noise residual of `samples` samples (its square's relative standard error is sqrt(2 / n))."""
    return float(np.sqrt(2.0 / max(samples, 1)))


@dataclass(frozen=True)
class PredictionBand:
    """The best held-out prediction within a model's band: the model (`effect`), the band's tolerance (relative
    rise of the calibration NRMSE), the axis ends (two per free parameter), those kept within the band and the
    calibration evaluations that took (`probed`, back-offs included), how far each free parameter
    moves within the kept ones (`reach`: largest relative change), the best point's free parameter values (SI),
    its calibration NRMSE (the fit's: `fit_calibration`) and held-out NRMSE."""

    effect: str
    tolerance: float
    ends: int
    kept: int
    probed: int
    reach: dict
    params: dict
    calibration_nrmse: float
    fit_calibration: float
    heldout_nrmse: float


def prediction_band(runner, fit, derived: tuple, cal, held, upsample: int, lead_periods: int) -> PredictionBand:
    """The band of `fit` (attribute.Fit; `derived`: its effect's rules for the parameters that follow the fitted
    ones) on the calibration records `cal`, and its best held-out NRMSE over `held` (the fit's own among them)."""
    free = [n for n in fit.free if fit.params[n] != 0.0]
    base = np.array([fit.params[n] for n in free])
    declared = [runner.variables[n] for n in free]  # the FMU's declared limits
    lo = np.array([-np.inf if v.min is None else float(v.min) for v in declared])
    hi = np.array([np.inf if v.max is None else float(v.max) for v in declared])

    def at(u) -> dict:
        return with_derived({**fit.params, **dict(zip(free, np.clip(base * (1.0 + u), lo, hi)))}, derived)

    r0 = stacked_residuals(runner, cal, fit.params, upsample, lead_periods)
    ssr0 = float(r0 @ r0)
    channels = sum(sum(r.weights.get(k, 1.0) for k in r.outputs) for r in cal)
    tol = tolerance(sum(r.n * len(r.outputs) for r in cal))
    bound = ssr0 * (1.0 + tol) ** 2
    J = np.column_stack([(stacked_residuals(runner, cal, at(STEP * e), upsample, lead_periods) - r0) / STEP
                         for e in np.eye(len(free))]) if free else np.zeros((len(r0), 0))
    lam, axes = np.linalg.eigh(J.T @ J) if free else (np.zeros(0), np.zeros((0, 0)))
    points, probed = [(np.zeros(len(free)), ssr0)], 0
    for k in range(len(free)):
        reach = np.sqrt((bound - ssr0) / max(lam[k], 1e-300))
        for sign in (1.0, -1.0):
            u = sign * reach * axes[:, k]
            u *= min(1.0, MAX_CHANGE / max(np.max(np.abs(u)), 1e-300))
            for _ in range(RETRIES + 1):
                probed += 1
                r = stacked_residuals(runner, cal, at(u), upsample, lead_periods)
                if float(r @ r) <= bound:
                    points.append((u, float(r @ r)))
                    break
                u = BACK_OFF * u
    best = None
    for u, ssr in points:
        values = at(u)
        after = selection.heldout_nrmse({r.name: sim.simulate(runner, r, values, upsample, lead_periods)
                                         for r in held}, held)
        if best is None or after < best[0]:
            best = (after, values, ssr)
    after, values, ssr = best
    moved = np.max([np.abs(np.clip(base * (1.0 + u), lo, hi) / base - 1.0) for u, _ in points], axis=0)
    return PredictionBand(fit.effect, tol, 2 * len(free), len(points) - 1, probed, dict(zip(free, map(float, moved))),
                          {n: float(values[n]) for n in fit.free},
                          float(np.sqrt(ssr / channels)), float(np.sqrt(ssr0 / channels)), float(after))
