"""The fitting objective: FMU simulation of an experiment -> residual vector against a measurement.

kind 'psd_band': the thesis's errorVec (theory §3), (PSD_sim - PSD_meas)/PSD_meas on each channel's
bands, both from identical Welch settings, times sqrt(weight). kind 'psd_log': log(PSD_sim/PSD_meas) on
the same bins (equal to the relative error near the optimum, but bounded where a resonance is far off,
which a surrogate learns more easily). kind 'time': (y_sim - y_meas)/std(y_meas) after a warm-up, each less
its mean. Measured inputs drive the FMU less their mean too (a sensor's zero is neither a load nor a
motion). Parameters enter scaled to [0, 1] within their bounds. A failed or diverging simulation gives a
finite penalty vector and is recorded; nothing non-finite leaves this module.
"""
from __future__ import annotations


import numpy as np

from pyfit.io.fit_config import FreeParameter, ObjectiveChannel
from pyfit.analysis import signals
from pyfit.io.data import Measurement
from pyfit.runtime.drive import drive
from pyfit.runtime.fmu import FmuRunner, SimulationResult





class Objective:
    """Residual vector r(x) of unit-scaled parameters x; error = sum(r^2)."""

    def __init__(self, fmu: str, measurement: Measurement, variables: list[FreeParameter],
                 channels: list[ObjectiveChannel], fixed: dict | None = None, kind: str = "psd_band",
                 segment_s: float = 8.0, warmup_s: float = 0.0, tolerance: float = 1e-8, penalty: float = 10.0,
                 use_inputs: bool = False, input_upsample: int = 1, input_periodic: bool = False):
        if kind not in ("psd_band", "psd_log", "time"):
            raise ValueError(f"objective kind '{kind}' unknown; allowed: psd_band, psd_log, time")
        self.runner = FmuRunner(fmu)
        self.m = measurement
        self.variables = variables
        self.channels = channels
        self.fixed = dict(fixed or {})
        self.kind = kind
        self.segment_s = segment_s
        self.tolerance = tolerance
        self.penalty = penalty
        self.use_inputs = use_inputs
        self.input_upsample = int(input_upsample)
        self.input_periodic = input_periodic
        self.inputs = {k: signals.without_offset(v) for k, v in measurement.by_variable("inputs").items()}
        self.fs = measurement.sample_rate_hz
        self.t = measurement.t - measurement.t[0]
        self.first = int(round(warmup_s * self.fs))
        self._target = {}
        for ch in channels:
            if ch.column not in measurement.values:
                raise ValueError(f"{measurement.path}: no column '{ch.column}'; columns: "
                                 f"{', '.join(measurement.values)}")
            y = measurement.values[ch.column][self.first:]
            if kind != "time":
                f, p = signals.welch_psd(y, self.fs, segment_s)
                masks = [(f >= lo) & (f <= hi) for lo, hi in ch.bands]
                if not ch.bands or not all(m.any() for m in masks):
                    raise ValueError(f"channel {ch.output}: every band needs at least one PSD bin "
                                     f"(resolution {f[1] - f[0]:.4g} Hz)")
                self._target[ch.output] = (p, np.any(masks, axis=0))
            else:
                self._target[ch.output] = (signals.without_offset(y), float(np.std(y)))
        if kind != "time":
            self.size = sum(int(mask.sum()) for _, mask in self._target.values())
            self._root_w = np.concatenate([np.full(int(self._target[ch.output][1].sum()), np.sqrt(ch.weight))
                                           for ch in channels])  # per-bin sqrt(weight), for log_ratio
        else:
            self.size = sum(len(y) for y, _ in self._target.values())

    def params(self, x) -> dict:
        """FMU parameters (SI) for unit-scaled x."""
        p = dict(self.fixed)
        p.update({v.name: v.value(u) for v, u in zip(self.variables, np.clip(x, 0.0, 1.0))})
        return p

    def simulate(self, x, outputs=None) -> SimulationResult:
        """The FMU's response on the measurement's time grid (driven by the measured inputs, or by the
        FMU's built-in excitation when use_inputs is off)."""
        outputs = outputs or [c.output for c in self.channels]
        if self.use_inputs:
            return drive(self.runner, self.inputs, self.fs, outputs, self.params(x),
                         self.input_upsample, len(self.t) if self.input_periodic else None, 0, self.tolerance)
        return self.runner.simulate(self.t[-1], 1.0 / self.fs, outputs, self.params(x), tolerance=self.tolerance)

    def residuals(self, x) -> np.ndarray:
        """Residual vector (finite; the penalty vector when the simulation fails)."""
        res = self.simulate(x)
        parts = []
        ok = res.ok
        if ok:
            for ch in self.channels:
                y = res[ch.output][self.first:]
                target, aux = self._target[ch.output]
                if self.kind == "psd_band":
                    _, p = signals.welch_psd(y, self.fs, self.segment_s)
                    r = (p[aux] - target[aux]) / target[aux]
                elif self.kind == "psd_log":
                    _, p = signals.welch_psd(y, self.fs, self.segment_s)
                    r = np.log(np.maximum(p[aux], 1e-300) / target[aux])
                else:
                    r = (signals.without_offset(y) - target) / aux
                parts.append(np.sqrt(ch.weight) * r)
            r = np.concatenate(parts)
            ok = bool(np.all(np.isfinite(r)))
        if not ok:
            r = np.full(self.size, self.penalty)
        return r

    def log_ratio(self, r: np.ndarray) -> np.ndarray:
        """A 'psd_band' residual vector as log(P/P_meas) per bin (log1p of the relative error, weights kept):
        smooth in the parameters where the relative error spans decades (NNO's search transform)."""
        if self.kind != "psd_band":
            raise ValueError(f"log_ratio needs a psd_band objective, not '{self.kind}'")
        return self._root_w * np.log(np.maximum(1.0 + r / self._root_w, 1e-12))

    def __call__(self, x) -> float:
        return float(np.sum(self.residuals(x) ** 2))

    def band_error_percent(self, x) -> dict[str, float]:
        """The thesis's '% error' per channel: RMS over the band bins of (PSD - PSD_meas)/PSD_meas, in %."""
        res = self.simulate(x)
        out = {}
        for ch in self.channels:
            f, p = signals.welch_psd(res[ch.output][self.first:], self.fs, self.segment_s)
            _, pm = signals.welch_psd(self.m.values[ch.column][self.first:], self.fs, self.segment_s)
            mask = np.any([(f >= lo) & (f <= hi) for lo, hi in ch.bands], axis=0)
            out[ch.output] = float(100 * np.sqrt(np.mean(((p[mask] - pm[mask]) / pm[mask]) ** 2)))
        return out

    def close(self):
        self.runner.close()
