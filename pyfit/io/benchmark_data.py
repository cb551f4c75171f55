"""The official Bouc-Wen benchmark validation signals (Noel & Schoukens): loading and validation runs.

Used for validation and reporting only, never for estimation (see shared/data/boucwen/README.md).
"""
from __future__ import annotations

import os
import pathlib
from dataclasses import dataclass

import numpy as np
import scipy.io

from pyfit.analysis.signals import rms_db  # noqa: F401  (rms_db: the figure of merit)
from pyfit.runtime.drive import drive

FS_HZ = 750.0  # sampling frequency of the official signals (not stored in the files)
# ../shared/data/boucwen beside the repository, or the folder named by BOUCWEN_DATA_DIR
DEFAULT_DIR = pathlib.Path(os.environ.get("BOUCWEN_DATA_DIR")
                           or pathlib.Path(__file__).resolve().parents[3] / "shared" / "data" / "boucwen")


@dataclass
class ValidationSignal:
    """Force input u [N] and displacement output y [m] sampled at FS_HZ."""

    name: str
    u: np.ndarray
    y: np.ndarray
    periodic: bool


def load(name: str, folder: pathlib.Path = DEFAULT_DIR) -> ValidationSignal:
    """Load 'multisine' (one steady-state period) or 'sinesweep' (from rest)."""
    if name not in ("multisine", "sinesweep"):
        raise ValueError(f"unknown benchmark signal '{name}'; valid: multisine, sinesweep")
    folder = pathlib.Path(folder)
    for kind in "uy":
        if not (folder / f"{kind}val_{name}.mat").is_file():
            raise FileNotFoundError(f"{folder / f'{kind}val_{name}.mat'}: benchmark signal not found (put "
                                    "../shared/data/boucwen beside the repository or set BOUCWEN_DATA_DIR)")
    u = scipy.io.loadmat(folder / f"uval_{name}.mat")[f"uval_{name}"].ravel().astype(float)
    y = scipy.io.loadmat(folder / f"yval_{name}.mat")[f"yval_{name}"].ravel().astype(float)
    return ValidationSignal(name, u, y, periodic=name == "multisine")


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


def write_dataset(out_dir, folder: pathlib.Path = DEFAULT_DIR) -> pathlib.Path:
    """The two official signals as a design-section-5 dataset (for the gap-diagnosis demonstration that
    the data README allows: calibrate on the multisine, judge on the sweep)."""
    from pyfit.io.data import write_measurement

    out = pathlib.Path(out_dir)
    for name in ("multisine", "sinesweep"):
        s = load(name, folder)
        t = np.arange(len(s.u)) / FS_HZ
        rms = float(np.sqrt(np.mean(s.u**2)))
        exc = {"kind": "multisine", "samples_per_period": len(s.u), "periods": 1} if s.periodic else \
            {"kind": "sweep", "description": "40 sin(2 pi (18 t + t^2/12)), 18 -> 52 Hz"}
        write_measurement(out / f"{name}.csv", "SDOFBoucWen", t, {"u": (s.u, "N", "u")}, {"y": (s.y, "m", "y")},
                          level=f"{name}, force RMS {rms:.1f} N", level_value=rms, excitation=exc,
                          notes="official Bouc-Wen benchmark validation signal (Noel & Schoukens 2016)")
    return out
