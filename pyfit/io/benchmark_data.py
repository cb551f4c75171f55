"""The official Bouc-Wen benchmark validation signals (Noël & Schoukens 2016, nonlinearbenchmark.org).

Third-party data, not shipped with the package. They are read from the folder named by the environment
variable BOUCWEN_DATA_DIR (the four files uval_/yval_multisine.mat and uval_/yval_sinesweep.mat), else
through the benchmark's official loader package `nonlinear-benchmarks` (the extra `benchmark`; it downloads
the files once, on a machine with internet). Used to validate and report, never to estimate.
"""
from __future__ import annotations

import os
import pathlib
from dataclasses import dataclass

import numpy as np
import scipy.io

FS_HZ = 750.0  # sampling frequency of the official signals (not stored in the files)
ENV_VAR = "BOUCWEN_DATA_DIR"
HOW_TO_GET = (f"set {ENV_VAR} to a folder holding uval_multisine.mat, yval_multisine.mat, uval_sinesweep.mat "
              "and yval_sinesweep.mat (the benchmark's validation signals, nonlinearbenchmark.org), or install "
              "the official loader on a machine with internet: pip install nonlinear-benchmarks")


class BenchmarkDataMissing(FileNotFoundError):
    """The benchmark signals are not on this machine; the message says how to get them."""


def data_folder() -> pathlib.Path:
    """The folder with the four validation files: BOUCWEN_DATA_DIR, else the official loader's cache."""
    named = os.environ.get(ENV_VAR)
    if named:
        return pathlib.Path(named)
    try:
        from nonlinear_benchmarks.not_splitted_benchmarks import BoucWen
    except ImportError:
        raise BenchmarkDataMissing(f"Bouc-Wen benchmark signals not found: {HOW_TO_GET}") from None
    try:
        return pathlib.Path(BoucWen(data_file_locations=True))
    except Exception as exc:  # the loader's download failed (no internet): say so, with the other way
        raise BenchmarkDataMissing(f"the nonlinear-benchmarks loader could not fetch the Bouc-Wen files ({exc}); "
                                   f"{HOW_TO_GET}") from exc


@dataclass
class ValidationSignal:
    """Force input u [N] and displacement output y [m] sampled at FS_HZ."""

    name: str
    u: np.ndarray
    y: np.ndarray
    periodic: bool


def load(name: str, folder: pathlib.Path | None = None) -> ValidationSignal:
    """Load 'multisine' (one steady-state period) or 'sinesweep' (from rest), from `folder` or data_folder()."""
    if name not in ("multisine", "sinesweep"):
        raise ValueError(f"unknown benchmark signal '{name}'; valid: multisine, sinesweep")
    folder = pathlib.Path(folder) if folder is not None else data_folder()
    for kind in "uy":
        if not (folder / f"{kind}val_{name}.mat").is_file():
            raise BenchmarkDataMissing(f"{folder / f'{kind}val_{name}.mat'}: benchmark signal not found; "
                                       f"{HOW_TO_GET}")
    u = scipy.io.loadmat(folder / f"uval_{name}.mat")[f"uval_{name}"].ravel().astype(float)
    y = scipy.io.loadmat(folder / f"yval_{name}.mat")[f"yval_{name}"].ravel().astype(float)
    return ValidationSignal(name, u, y, periodic=name == "multisine")


def write_dataset(out_dir, folder: pathlib.Path | None = None) -> pathlib.Path:
    """The two official signals as a measurement dataset (theory §5) (for the gap-diagnosis demonstration that
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
