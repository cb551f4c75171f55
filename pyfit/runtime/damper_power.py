"""The damper's clamp power and impedance over a grid of frequencies and clamp amplitudes: the DamperElement
FMU under its built-in clamp sine, run as one batch (or a measured impedance test read into the same table).
Used by the impedance fit and by the span design checks."""
from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass, field

import numpy as np

from pyfit.io.impedance import write_impedance
from pyfit.runtime.batch import RunSpec, run_batch


@dataclass
class DamperPowerTable:
    """The damper at frequencies[i] [Hz] and clamp amplitudes[j] [m] (or amplitudes[i, j]: a measured
    table's own amplitudes at each frequency): mean power [W] and clamp impedance [N·s/m], NaN where the
    simulation failed; drift[i, j]: relative change of the power between the two halves of the averaging
    window (how steady the state was)."""

    frequencies: np.ndarray
    amplitudes: np.ndarray
    power: np.ndarray
    drift: np.ndarray = field(default=None)
    impedance: np.ndarray = field(default=None)  # complex Z = F̂_clamp / v̂_clamp [N·s/m], first harmonics

    @classmethod
    def from_test(cls, test) -> "DamperPowerTable":
        """The table of a measured impedance test (`pyfit.io.impedance.ImpedanceTest`): power ½ Re Z ω² a²."""
        power = 0.5 * test.impedance.real * (2 * np.pi * test.frequencies[:, None]) ** 2 * test.amplitudes ** 2
        return cls(test.frequencies, test.amplitudes, power, np.zeros(power.shape), test.impedance)

    def amplitudes_at(self, i: int) -> np.ndarray:
        """Clamp amplitudes [m] of the table's row at frequencies[i]."""
        return self.amplitudes if self.amplitudes.ndim == 1 else self.amplitudes[i]

    def impedance_at(self, i: int, a):
        """Impedance [N·s/m] at frequencies[i] and clamp amplitude(s) a [m]: real and imaginary parts linear in
        log a; the smallest amplitude's below the table (the linear range); NaN above it or next to a failed
        run."""
        a = np.asarray(a, float)
        amps, z = self.amplitudes_at(i), self.impedance[i]
        j = np.clip(np.searchsorted(amps, a), 1, len(amps) - 1)
        s = np.log(np.maximum(a, amps[0]) / amps[j - 1]) / np.log(amps[j] / amps[j - 1])
        out = np.where(a <= amps[0], z[0], (1 - s) * z[j - 1] + s * z[j])
        return np.where(a > amps[-1], np.nan + 0j, out)

    def save(self, path) -> None:
        """CSV: one row per frequency [Hz], one column per clamp amplitude [m], mean power [W]; and, beside it,
        <stem>_impedance.csv + .toml, the IEC 61897 impedance test file that `pyfit.io.impedance` reads."""
        path = pathlib.Path(path)
        if self.amplitudes.ndim == 1:
            header = "frequency_hz," + ",".join(f"P_at_{a:.4g}_m" for a in self.amplitudes)
            np.savetxt(path, np.column_stack([self.frequencies, self.power]), delimiter=",", header=header,
                       comments="", fmt="%.6g")
        if self.impedance is not None:
            amps = np.array([self.amplitudes_at(i) for i in range(len(self.frequencies))])
            write_impedance(path.with_name(path.stem + "_impedance.csv"), self.frequencies, amps, self.impedance,
                            "damper FMU: clamp sine, first harmonics over whole periods of the steady state")


def damper_power_table(fmu, frequencies, amplitudes, params: dict | None = None, settle: float = 6.0,
                       average: float = 2.0, ramp: float = 1.5, workers: int | None = None,
                       progress: bool = True) -> DamperPowerTable:
    """Simulate the damper FMU (DamperElement) under its built-in clamp sine at every frequency [Hz] and
    clamp amplitude [m] (one list for all frequencies, or one row per frequency): smooth ramp-in over the
    first `ramp` s, steady state after `settle` s (the default damper's slowest mode, 10 Hz at ζ ≈ 2.2 %,
    decays to 2e-4 in 6 s), then the mean of F_clamp · v_clamp and the first harmonics of F_clamp and
    v_clamp over the whole periods of the next `average` s."""
    freqs, amps = np.asarray(frequencies, float), np.asarray(amplitudes, float)
    rows = amps if amps.ndim == 2 else np.repeat(amps[None, :], len(freqs), axis=0)  # amplitudes per frequency
    specs, windows = [], []
    for f, row in zip(freqs, rows):
        n_avg = max(2, int(round(average * f)))  # whole periods averaged
        periods = int(math.ceil(settle * f)) + n_avg
        per = 40  # samples per period: the mean over whole periods is exact for harmonics below 20
        windows.append((n_avg * per, per))
        for a in row:
            specs.append(RunSpec(str(fmu), periods / f, 1.0 / (per * f), ("F_clamp", "v_clamp"),
                                 {**(params or {}), "exc_type": 1, "exc_amplitude": float(a),
                                  "exc_f_start": float(f), "exc_t_ramp": ramp},
                                 label=f"{f:g} Hz {a:.3g} m"))
    results = run_batch(specs, workers=workers, progress=progress, desc="damper power")
    power = np.full(rows.shape, np.nan)
    drift = np.full_like(power, np.nan)
    impedance = np.full(power.shape, np.nan + 0j)
    for k, r in enumerate(results):
        i, j = divmod(k, rows.shape[1])
        if not r.ok:
            continue
        n, per = windows[i]
        force, velocity = r["F_clamp"][-n - 1:-1], r["v_clamp"][-n - 1:-1]
        p = force * velocity
        if not np.all(np.isfinite(p)):
            continue
        half = len(p) // 2
        power[i, j] = float(np.mean(p))
        drift[i, j] = float(abs(np.mean(p[:half]) - np.mean(p[half:])) / max(abs(power[i, j]), 1e-300))
        rotor = np.exp(-2j * np.pi * np.arange(n) / per)  # first harmonic over whole periods
        impedance[i, j] = np.sum(force * rotor) / np.sum(velocity * rotor)
    return DamperPowerTable(freqs, amps, power, drift, impedance)
