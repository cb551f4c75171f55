"""Synthetic 'measured' data without the inverse crime.

The truth is simulated by the independent CasADi reference (CVODES at tight tolerance, or the thesis's
Newmark scheme) at `oversample` times the sensor rate, passed through a sensor chain (zero-phase FIR
anti-alias filter and decimation, or plain sampling as the Bouc-Wen benchmark did) and measurement noise,
and written as a measurement file (theory §5). The model being fitted is the FMU (another
implementation and another integrator), sampled directly at the sensor rate.

The excitation is a built-in one (sine, sweeps) or a measured force input: a random-phase multisine
(periodic, band-limited; upsampled to the fine grid in the frequency domain).
"""
from __future__ import annotations

import dataclasses
import pathlib
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from pyfit.analysis import signals
from pyfit.io.data import write_measurement
from pyfit.analysis.excitation import Excitation, MultisineInput
from pyfit.reference import integrate
from pyfit.reference import models

UNITS = {"y": "m", "y1": "m", "y2": "m", "x1": "m", "x2": "m", "xg1": "m", "xg2": "m", "F_clamp": "N",
         "z": "N", "v": "m/s", "v1": "m/s", "v2": "m/s", "phi1": "rad", "phi2": "rad",
         "a": "m/s2", "acc_x1": "m/s2", "acc_x2": "m/s2", "acc_xg1": "m/s2", "acc_xg2": "m/s2"}


@dataclass
class SyntheticSpec:
    """What to simulate and how the sensors see it (times in s, rates in Hz, noise in SI units)."""

    model: str
    excitation: Excitation | MultisineInput
    stop_time: float  # s (ignored for a multisine: periods x samples_per_period / sample_rate_hz)
    sample_rate_hz: float
    outputs: list[str]
    params: dict = field(default_factory=dict)
    noise_std: dict = field(default_factory=dict)  # output -> standard deviation
    oversample: int = 10
    seed: int = 0
    level: str = ""
    level_value: float | None = None
    solver: str = "cvodes"  # or "newmark"
    anti_alias: bool = True  # zero-phase FIR before decimation; False = plain sampling
    passband_ripple_db: float | None = None  # None: scipy's decimate FIR (Hamming, 20*q taps: +0.024 dB
    # at 58 Hz of a 1 kHz sensor); a value: a Kaiser FIR designed for this ripple (a DAQ-grade chain)
    rtol: float = 1e-10  # CVODES relative and absolute tolerances (SI units of the states)
    atol: float = 1e-14


def anti_alias_fir(oversample: int, ripple_db: float) -> np.ndarray:
    """Linear-phase low-pass FIR for decimation by `oversample`: a Kaiser window sized by kaiserord for a
    ripple of ripple_db [dB] in pass and stop band, transition from 0.8x to 1x the sensor Nyquist (a Kaiser
    design is not equiripple: it meets the ripple to 0.7x and exceeds it by up to 20 % next to 0.8x)."""
    delta = 10 ** (ripple_db / 20) - 1
    numtaps, beta = scipy.signal.kaiserord(-20 * np.log10(delta), 0.2 / oversample)
    return scipy.signal.firwin(numtaps | 1, 0.9 / oversample, window=("kaiser", beta))


def simulate_truth(spec: SyntheticSpec) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Sensor-rate time, measured outputs (sensor chain + noise) and the exact input signals."""
    if spec.solver not in ("cvodes", "newmark"):
        raise ValueError(f"solver '{spec.solver}' unknown; allowed: cvodes, newmark")
    ref = models.by_name(spec.model)
    fs = spec.sample_rate_hz
    fine_dt = 1.0 / (fs * spec.oversample)
    sampled, excitation = None, spec.excitation
    if isinstance(spec.excitation, MultisineInput):
        u = spec.excitation(fs)
        t = np.arange(len(u)) / fs
        sampled = {ref.input_names[0]: signals.upsample_periodic(u, spec.oversample)}
        t_fine = np.arange(len(u) * spec.oversample) * fine_dt
        excitation = None
    else:
        n_fine = int(round(spec.stop_time / fine_dt))
        t_fine = np.arange(n_fine + 1) * fine_dt
        t = t_fine[::spec.oversample]
    if spec.solver == "cvodes":
        truth = integrate.simulate_cvodes(ref, t_fine, params=spec.params, excitation=excitation, inputs=sampled,
                                          rtol=spec.rtol, atol=spec.atol)
    else:
        truth = integrate.simulate_newmark(ref, t_fine, params=spec.params, excitation=excitation, inputs=sampled)
    rng = np.random.default_rng(spec.seed)
    measured = {}
    for name in spec.outputs:
        if spec.anti_alias and spec.passband_ripple_db is not None:
            fir = anti_alias_fir(spec.oversample, spec.passband_ripple_db)
            y = scipy.signal.resample_poly(truth[name], 1, spec.oversample, window=fir)[:len(t)]
        elif spec.anti_alias:
            y = scipy.signal.decimate(truth[name], spec.oversample, ftype="fir", zero_phase=True)[:len(t)]
        else:
            y = truth[name][::spec.oversample][:len(t)]
        measured[name] = y + rng.normal(0.0, spec.noise_std.get(name, 0.0), len(y))
    inputs = {}
    if sampled is not None:
        inputs[ref.input_names[0]] = sampled[ref.input_names[0]][::spec.oversample]
    elif ref.input_names == ["u"] or ref.input_names == ["f"]:
        inputs[ref.input_names[0]] = spec.excitation(t)
    elif spec.excitation.kind:
        inputs["x_base"] = spec.excitation(t)
    return t, measured, inputs


def write_synthetic(path: str | pathlib.Path, spec: SyntheticSpec) -> pathlib.Path:
    """Simulate the truth and write it as a measurement file (CSV + TOML)."""
    t, measured, inputs = simulate_truth(spec)
    in_cols = {f"{k}_meas": (v, UNITS.get(k, "N" if k in ("u", "f") else "m"), k) for k, v in inputs.items()}
    out_cols = {f"{k}_meas": (v, UNITS.get(k, "m"), k) for k, v in measured.items()}
    excitation = dataclasses.asdict(spec.excitation)
    if isinstance(spec.excitation, MultisineInput):
        excitation = dict(excitation, kind="multisine")
    chain = "zero-phase FIR anti-alias + decimation" if spec.anti_alias else "plain sampling"
    if spec.anti_alias and spec.passband_ripple_db is not None:
        chain += f" (Kaiser, passband ripple {spec.passband_ripple_db} dB)"
    notes = (f"synthetic: CasADi reference ({spec.solver}) at {spec.oversample}x the sensor rate, {chain}, "
             f"noise std {spec.noise_std}, seed {spec.seed}")
    return write_measurement(path, spec.model, t, in_cols, out_cols, spec.level, spec.level_value, excitation, notes)
