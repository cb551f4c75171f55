"""Runs of the SDOF FMU on the official Bouc-Wen benchmark validation inputs (`pyfit.io.benchmark_data`)."""
from __future__ import annotations

import numpy as np

from pyfit.io.benchmark_data import FS_HZ, ValidationSignal
from pyfit.runtime.drive import drive


def simulate_validation(runner, signal: ValidationSignal, upsample: int = 20, periods: int = 3,
                        params: dict | None = None, tolerance: float = 1e-10) -> np.ndarray:
    """Simulate the SDOF FMU (co-simulation, input derivatives) on a validation input; return y at FS_HZ.

    Multisine: band-limited upsampling, `periods` periods, the last one returned (steady state).
    Sweep: spline upsampling, from rest.
    """
    p = {"exc_type": 0}
    p.update(params or {})
    n = len(signal.u)
    res = drive(runner, {"u": signal.u}, FS_HZ, ["y"], p, upsample, n if signal.periodic else None,
                periods - 1 if signal.periodic else 0, tolerance)
    if not res.ok:
        raise RuntimeError(f"benchmark simulation failed: {res.message}")
    return res["y"]
