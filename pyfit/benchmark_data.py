"""The official Bouc-Wen benchmark validation signals (Noel & Schoukens): loading and validation runs.

Used for validation and reporting only, never for estimation (see shared/data/boucwen/README.md).
"""
from __future__ import annotations

import os
import pathlib
from dataclasses import dataclass

import numpy as np
import scipy.interpolate
import scipy.io

from .signals import rms_db  # noqa: F401  (the benchmark's figure of merit, dB re 1 m)

FS_HZ = 750.0  # sampling frequency of the official signals (not stored in the files)
# ../shared/data/boucwen beside the repository, or the folder named by BOUCWEN_DATA_DIR
DEFAULT_DIR = pathlib.Path(os.environ.get("BOUCWEN_DATA_DIR")
                           or pathlib.Path(__file__).resolve().parents[2] / "shared" / "data" / "boucwen")


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
    u = scipy.io.loadmat(folder / f"uval_{name}.mat")[f"uval_{name}"].ravel().astype(float)
    y = scipy.io.loadmat(folder / f"yval_{name}.mat")[f"yval_{name}"].ravel().astype(float)
    return ValidationSignal(name, u, y, periodic=name == "multisine")


def upsample_periodic(u: np.ndarray, factor: int) -> np.ndarray:
    """Band-limited (FFT zero-padding) upsampling of one period of a periodic signal."""
    n = len(u)
    spec = np.fft.rfft(u)
    padded = np.zeros(n * factor // 2 + 1, complex)
    padded[:len(spec)] = spec
    if n % 2 == 0:
        padded[n // 2] *= 0.5  # split the Nyquist bin between +-fs/2
    return np.fft.irfft(padded, n * factor) * factor


def upsample_spline(u: np.ndarray, factor: int) -> np.ndarray:
    """Cubic-spline upsampling of a non-periodic signal that starts from rest."""
    t = np.arange(len(u))
    tf = np.arange((len(u) - 1) * factor + 1) / factor
    return scipy.interpolate.CubicSpline(t, u, bc_type="natural")(tf)


def simulate_validation(runner, signal: ValidationSignal, upsample: int = 20, periods: int = 3,
                        params: dict | None = None, tolerance: float = 1e-10) -> np.ndarray:
    """Simulate the SDOF FMU (co-simulation, input derivatives) on a validation input; return y at FS_HZ.

    Multisine: band-limited upsampling, `periods` periods, the last one returned (steady state).
    Sweep: spline upsampling, from rest.
    """
    fs = FS_HZ * upsample
    if signal.periodic:
        one = upsample_periodic(signal.u, upsample)
        u = np.concatenate([np.tile(one, periods), one[:1]])
    else:
        u = upsample_spline(signal.u, upsample)
    t = np.arange(len(u)) / fs
    p = {"exc_type": 0}
    p.update(params or {})
    res = runner.simulate(stop_time=t[-1], output_interval=1 / fs, outputs=["y"], params=p, inputs={"u": u},
                          input_time=t, tolerance=tolerance)
    if not res.ok:
        raise RuntimeError(f"benchmark simulation failed: {res.message}")
    y = res["y"][::upsample]
    if signal.periodic:
        n = len(signal.u)
        return y[(periods - 1) * n:periods * n]
    return y[:len(signal.u)]
