"""The sample rate a diagnosis works at. A diagnosis simulates and compares every sample, so its cost grows with the
rate; a file sampled far faster than its excitation needs (a 5 kHz acquisition of a 5-40 Hz sweep) is decimated to
at least RATE_FACTOR times the highest frequency the inputs excite, by a whole factor, after a zero-phase
anti-alias filter (pyfit.analysis.signals.decimated). What is lost lies above the fifth harmonic of the highest
excited frequency, which stays in the filter's flat passband (0.6 of the new Nyquist frequency).

The FMU's drive grid follows the rate: a family drives it at `System.upsample` times the sensor rate, set at
REFERENCE_HZ; a faster file is driven on the least whole multiple of its rate that keeps as many grid points per
second as that, or per sample of the slowest rate its excitation allows (drive_upsample)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from pyfit.analysis.kinematics import excited_lines
from pyfit.analysis.signals import DECIMATION_TAPS, decimated, welch_psd
from pyfit.io.data import Measurement

# analysis rate over the highest excited frequency, at least: 20 puts the new Nyquist frequency at 10 times it and the
# fifth harmonic (a strong hardening spring's or a friction's distortion reaches it) at 0.5 of it, inside the
# anti-alias filter's flat passband (within 1e-4 up to 0.6). At 12, which keeps the third, the envelope-led search
# misses a damper sweep through strong springs and a loop (damper campaign case 24, tests/test_envelope_led.py)
RATE_FACTOR = 20.0
# the sensor rate the families' drive grids (System.upsample) were set at [Hz]: the rate of every case their
# campaigns calibrated the stated confidence on, each file of which keeps its family's grid
REFERENCE_HZ = 500.0


@dataclass(frozen=True)
class AnalysisRate:
    """The files' rate [Hz], the whole factor they are decimated by (1: not at all), the highest frequency the
    inputs excite [Hz] and the least ratio of the analysis rate to it the factor keeps."""

    file_hz: float
    factor: int
    top_hz: float
    min_ratio: float

    @property
    def hz(self) -> float:
        """The rate the diagnosis simulates and compares at [Hz]."""
        return self.file_hz / self.factor


def _top(u: np.ndarray, fs: float, samples_per_period: int, fraction: float = 1e-3) -> float:
    """The highest frequency [Hz] an input excites: of whole periods, its highest excited DFT line
    (kinematics.excited_lines); otherwise the highest where its Welch spectrum over segments of a quarter of the
    record (half overlapping: together the whole record, a sweep's last seconds included) is above `fraction` of
    its peak."""
    if samples_per_period:
        lines = excited_lines(u, fs, samples_per_period)
        if lines is not None:
            return lines[1]
    f, p = welch_psd(u - np.mean(u), fs, len(u) / (4 * fs))
    return float(f[np.flatnonzero(p > fraction * p[1:].max())[-1]])


def analysis_rate(ms: list[Measurement], factor: float = RATE_FACTOR) -> AnalysisRate:
    """The rate of a dataset's files (one rate, checked by the caller) and the largest whole decimation factor that
    keeps at least `factor` times the highest frequency any input of any file excites (_top) and, for whole
    periods, divides every record's samples per period (1 when a multisine record is not whole periods)."""
    fs = ms[0].sample_rate_hz
    inputs = [(u, m.samples_per_period) for m in ms for u in m.by_variable("inputs").values() if np.ptp(u) > 0]
    if not inputs:  # nothing excited to take a band from (the diagnosis says what is wrong with such files)
        return AnalysisRate(fs, 1, fs / 2, factor)
    top = max(_top(u, fs, spp) for u, spp in inputs)
    q = max(1, int(fs // (factor * top)))
    if any(m.samples_per_period and len(m.t) % m.samples_per_period for m in ms):
        q = 1  # not whole periods: refused with the file's own numbers (simulate.record_of)
    while q > 1 and any(m.samples_per_period % q for m in ms if m.samples_per_period):
        q -= 1
    return AnalysisRate(fs, q, top, factor)


def at_rate(m: Measurement, q: int) -> Measurement:
    """The measurement decimated by q (every channel; a multisine's samples per period with it). A record that is
    not periodic loses its last DECIMATION_TAPS samples, where the anti-alias filter reaches past its end (its
    start is kept: a record from rest was at rest before it, and one that is not is compared only after its
    start-up transient, pyfit.gap.simulate.record_of)."""
    if q == 1:
        return m
    spp = m.samples_per_period
    end = None if spp else -DECIMATION_TAPS
    values = {c: decimated(v, q, periodic=bool(spp))[:end] for c, v in m.values.items()}
    excitation = {**m.excitation, "samples_per_period": spp // q} if spp else m.excitation
    t = m.t[0] + np.arange(len(next(iter(values.values())))) * q / m.sample_rate_hz
    return replace(m, t=t, values=values, excitation=excitation)


def common_rate(ms: list[Measurement]) -> tuple[list[Measurement], dict[str, float]]:
    """A dataset's files at one rate: a file recorded at a whole multiple of the slowest file's rate (a level the
    DAQ sampled faster) decimated to it after the zero-phase anti-alias filter (at_rate). Returns the files and
    the rate [Hz] each decimated one was recorded at, by name. ValueError naming the first file whose rate is no
    whole multiple of the slowest (or whose period a multisine's decimation would not keep whole)."""
    slowest = min(ms, key=lambda m: m.sample_rate_hz)
    fs = slowest.sample_rate_hz
    out, recorded = [], {}
    for m in ms:
        q = round(m.sample_rate_hz / fs)
        if abs(m.sample_rate_hz - q * fs) > 1e-6 * m.sample_rate_hz or m.samples_per_period % q:
            raise ValueError(f"{m.path.with_suffix('.toml')}: sample_rate_hz = {m.sample_rate_hz:g} but "
                             f"{slowest.path.name} has {fs:g}; allowed: one rate, or rates that are whole multiples "
                             "of the slowest file's (a multisine's samples per period too), decimated to it")
        if q > 1:
            recorded[m.name] = m.sample_rate_hz
        out.append(at_rate(m, q))
    return out, recorded


def drive_upsample(upsample: int, rate: AnalysisRate) -> int:
    """The FMU's drive grid as a multiple of the analysis rate, for a family that drives files at REFERENCE_HZ
    with `upsample`: the least whole number whose grid has at least `upsample` points per sample of REFERENCE_HZ
    or, for an excitation above that rate's Nyquist frequency, of twice the highest excited frequency; never more
    than `upsample` (a file at REFERENCE_HZ or slower keeps it). A 1 kHz damper file of a 5-40 Hz sweep is driven
    at its own rate, the 1 kHz grid a 500 Hz file's is, at the cost of one."""
    points = upsample * max(REFERENCE_HZ, 2.0 * rate.top_hz)
    return max(1, min(upsample, math.ceil(points / rate.hz - 1e-9)))
