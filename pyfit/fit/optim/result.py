"""What every optimiser returns."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class OptimResult:
    """Best point ever evaluated (unit-scaled), its error, the number of true evaluations and the history."""

    x: np.ndarray
    error: float
    n_evaluations: int
    stop_reason: str
    history: list[dict]
    wall_s: float
