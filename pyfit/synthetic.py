"""Synthetic 'measured' data without the inverse crime.

The truth is simulated by the independent CasADi reference (CVODES, tight tolerance) at `oversample`
times the sensor rate, passed through a sensor chain (zero-phase FIR anti-alias filter and decimation)
and measurement noise, and written as a design-section-5 measurement. The model being fitted is the
FMU (another implementation and another integrator), sampled directly at the sensor rate.
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from .data import write_measurement
from .excitation import Excitation
from .reference import integrate, models

UNITS = {"y": "m", "y1": "m", "y2": "m", "x1": "m", "x2": "m", "xg1": "m", "xg2": "m", "F_clamp": "N",
         "z": "N", "v": "m/s", "v1": "m/s", "v2": "m/s", "phi1": "rad", "phi2": "rad"}


@dataclass
class SyntheticSpec:
    """What to simulate and how the sensors see it (times in s, rates in Hz, noise in SI units)."""

    model: str
    excitation: Excitation
    stop_time: float
    sample_rate_hz: float
    outputs: list[str]
    params: dict = field(default_factory=dict)
    noise_std: dict = field(default_factory=dict)  # output -> standard deviation
    oversample: int = 10
    seed: int = 0
    level: str = ""
    level_value: float | None = None


def simulate_truth(spec: SyntheticSpec) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Sensor-rate time, measured outputs (filtered, decimated, noisy) and exact excitation input signals."""
    ref = models.by_name(spec.model)
    fine_dt = 1.0 / (spec.sample_rate_hz * spec.oversample)
    n_fine = int(round(spec.stop_time / fine_dt))
    t_fine = np.arange(n_fine + 1) * fine_dt
    truth = integrate.simulate_cvodes(ref, t_fine, params=spec.params, excitation=spec.excitation,
                                      rtol=1e-10, atol=1e-14)
    rng = np.random.default_rng(spec.seed)
    t = t_fine[::spec.oversample]
    measured = {}
    for name in spec.outputs:
        y = scipy.signal.decimate(truth[name], spec.oversample, ftype="fir", zero_phase=True)[:len(t)]
        measured[name] = y + rng.normal(0.0, spec.noise_std.get(name, 0.0), len(y))
    e = spec.excitation(t)
    inputs = {}
    if ref.input_names == ["u"] or ref.input_names == ["f"]:
        inputs[ref.input_names[0]] = e
    elif spec.excitation.kind:
        inputs["x_base"] = e
    return t, measured, inputs


def write_synthetic(path: str | pathlib.Path, spec: SyntheticSpec) -> pathlib.Path:
    """Simulate the truth and write it as a measurement file (CSV + TOML)."""
    t, measured, inputs = simulate_truth(spec)
    in_cols = {f"{k}_meas": (v, UNITS.get(k, "N" if k in ("u", "f") else "m"), k) for k, v in inputs.items()}
    out_cols = {f"{k}_meas": (v, UNITS.get(k, "m"), k) for k, v in measured.items()}
    exc = spec.excitation
    excitation = {"kind": exc.kind, "amplitude": exc.amplitude, "f_start": exc.f_start, "f_end": exc.f_end,
                  "rate": exc.rate, "octaves_per_minute": exc.octaves_per_minute, "t_ramp": exc.t_ramp}
    notes = (f"synthetic: CasADi reference (CVODES) at {spec.oversample}x the sensor rate, zero-phase FIR "
             f"anti-alias + decimation, noise std {spec.noise_std}, seed {spec.seed}")
    return write_measurement(path, spec.model, t, in_cols, out_cols, spec.level, spec.level_value, excitation, notes)
