"""Scores of candidate models on the held-out files, shared by the ranking and the forward selection of
effect combinations (SI units; NRMSE is dimensionless)."""
from __future__ import annotations

import numpy as np

from pyfit.gap import localise

PENALTY_POINTS = 5.0  # score points charged per strength parameter beyond the first


def heldout_nrmse(sims: dict, held) -> float:
    """RMS over the held-out files of a model's NRMSE (inf when a simulation failed)."""
    done = [localise.nrmse(sims[r.name], r) for r in held if sims.get(r.name) is not None]
    return float(np.sqrt(np.mean(np.square(done)))) if done and len(done) == len(held) else float("inf")


def shrink_pct(before: float, after: float, reference: float) -> float:
    """How much of the gap above `reference` a model removes, in %: 100 (before - after) / (before - reference)."""
    return 100.0 * (before - after) / (before - reference) if before > reference else 0.0


def score(before: float, after: float, reference: float, strengths: int) -> float:
    """Shrink [%] less PENALTY_POINTS per strength parameter beyond the first: what a candidate pays for."""
    return shrink_pct(before, after, reference) - PENALTY_POINTS * (strengths - 1)
