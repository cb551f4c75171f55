"""Run the FMU on measured files: the input as measured (band-limited upsampling for periodic records,
a cubic spline otherwise), outputs on the file's time grid. A periodic record is taken as steady state:
periods are simulated in front of it and dropped. A failed or diverging run returns None."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pyfit.io.data import Measurement
from pyfit.runtime.fmu import FmuRunner
from pyfit.runtime.drive import drive


@dataclass
class Record:
    """One measurement prepared for simulation and comparison (SI units)."""

    name: str
    level: str
    level_value: float
    fs: float
    inputs: dict  # model variable -> samples
    outputs: dict  # model variable -> samples
    samples_per_period: int  # 0: not periodic

    @property
    def periodic(self) -> bool:
        return self.samples_per_period > 0

    @property
    def n(self) -> int:
        return len(next(iter(self.outputs.values())))


def record_of(m: Measurement) -> Record:
    """A Record from a measurement; periodic when its excitation says so (kind multisine, samples_per_period)."""
    exc = m.excitation or {}
    spp = int(exc.get("samples_per_period", 0)) if exc.get("kind") == "multisine" else 0
    n = len(m.t)
    if spp and n % spp:
        raise ValueError(f"{m.path}: {n} samples is not a whole number of periods of {spp} "
                         "([excitation] samples_per_period)")
    return Record(m.path.stem, m.level, float(m.level_value if m.level_value is not None else 0.0),
                  m.sample_rate_hz, m.by_variable("inputs"), m.by_variable("outputs"), spp)


def scaled(rec: Record, factor: float) -> Record:
    """The same record with its inputs multiplied by factor (outputs unchanged: for predictions only)."""
    return Record(f"{rec.name}x{factor:g}", f"{rec.level} x{factor:g}", rec.level_value * factor, rec.fs,
                  {k: v * factor for k, v in rec.inputs.items()}, rec.outputs, rec.samples_per_period)


def simulate(runner: FmuRunner, rec: Record, params: dict, upsample: int = 4, lead_periods: int = 1,
             tolerance: float = 1e-8) -> dict | None:
    """Outputs (model variable -> samples on the record's grid) for FMU parameters params; None on failure.
    A periodic record is preceded by lead_periods simulated periods (dropped)."""
    res = drive(runner, rec.inputs, rec.fs, list(rec.outputs), params, upsample, rec.samples_per_period,
                lead_periods if rec.periodic else 0, tolerance)
    return res.values if res.ok else None


def residuals(sim: dict | None, rec: Record, penalty: float = 10.0) -> np.ndarray:
    """Stacked (y_sim - y_meas) / RMS(y_meas) / sqrt(n) per channel: its sum of squares is the sum of the
    channels' squared NRMSE. A failed simulation gives the finite penalty vector."""
    parts = []
    for k, y in rec.outputs.items():
        scale = np.sqrt(np.mean(y**2)) * np.sqrt(len(y))
        parts.append(np.full(len(y), penalty / np.sqrt(len(y))) if sim is None else (sim[k] - y) / scale)
    return np.concatenate(parts)
