"""Displacement, velocity and acceleration from whichever one was recorded.

Every derived signal is band-limited to the record's excited band: a zero-phase high-pass below it
(integrating an accelerometer's offset or 1/f noise would otherwise drift without bound) and a zero-phase
low-pass above it (differentiating sensor noise would otherwise amplify it by ω or ω²). The record's mean
and linear trend (a sensor offset and drift) are removed first. Differentiation is iω in the frequency
domain, on the record mirrored (even extension) so that its ends join: a sweep or a segment cut from a long
record is not periodic; near its ends, where the mirror leaves a kink, the derivative of the record's cubic
spline is blended in. Integration of such a record is the antiderivative of its cubic spline with the
drift polynomial removed (mirroring would force the integral's ends to zero). A record of whole periods is
transformed as it is, which is exact.

Units: x [m], v [m/s], a [m/s²]; fs [Hz]; band [Hz].
"""
from __future__ import annotations

import numpy as np
import scipy.interpolate

ORDER = {"x": 0, "v": 1, "a": 2}


def excited_band(u: np.ndarray, fs: float, fraction: float = 1e-3, samples_per_period: int = 0
                  ) -> tuple[float, float]:
    """[f_lo, f_hi] Hz holding the input's power spectrum above `fraction` of its peak (Welch, 1 Hz bins or
    finer): the band a derived signal is trusted in. A record of whole periods (`samples_per_period`) gives
    its excited DFT lines instead (excited_lines)."""
    from pyfit.analysis.signals import welch_psd

    if samples_per_period and len(u) >= samples_per_period and len(u) % samples_per_period == 0:
        lines = excited_lines(u, fs, samples_per_period)
        if lines is not None:
            return lines
    f, p = welch_psd(np.asarray(u, float) - np.mean(u), fs, min(len(u) / fs, 4.0))
    on = np.flatnonzero((p > fraction * p[1:].max()) & (f > 0))
    if not on.size:
        raise ValueError("the input has no excited band (it is constant)")
    return float(f[on[0]]), float(f[on[-1]])


def energy_band(y: np.ndarray, fs: float, share: float = 0.998) -> tuple[float, float]:
    """[f_lo, f_hi] Hz holding `share` of the record's energy (its DFT, the mean removed), the rest split evenly
    below and above: a sensor's slow drift, a small share of the energy, stays outside it."""
    power = np.abs(np.fft.rfft(np.asarray(y, float) - np.mean(y))) ** 2
    f = np.fft.rfftfreq(len(y), 1.0 / fs)
    cum = np.cumsum(power)
    tail = (1.0 - share) / 2 * cum[-1]
    return float(f[np.searchsorted(cum, tail)]), float(f[min(np.searchsorted(cum, cum[-1] - tail), len(f) - 1)])


def share_below(y: np.ndarray, fs: float, cutoff_hz: float) -> float:
    """The share of the record's energy below cutoff_hz [Hz], from its Hann-windowed DFT (the mean removed): the
    window keeps the leakage of a record cut at its ends (a sweep from rest) from passing for content there."""
    y = np.asarray(y, float) - np.mean(y)
    power = np.abs(np.fft.rfft(y * np.hanning(len(y)))) ** 2
    return float(power[np.fft.rfftfreq(len(y), 1.0 / fs) < cutoff_hz].sum() / power.sum())


# a line of a periodic record is excited when its power (of the averaged period) is above LINE_FRACTION of the
# strongest line's and, with two periods or more, LINE_SNR times the noise there (the period-to-period scatter's
# median over LINE_NEIGHBOURS lines either side). A fraction of the peak alone fails on a wide multisine read by
# an accelerometer: acceleration power grows as f^4, so one flat in displacement over 3.7-69 Hz has its lowest
# line at 8e-6 of its highest (Welch at 1e-3 started that band at 12 Hz, and integration lost the lines below 4 Hz)
LINE_FRACTION = 1e-10
LINE_SNR = 100.0
LINE_NEIGHBOURS = 8


def excited_lines(u: np.ndarray, fs: float, samples_per_period: int) -> tuple[float, float] | None:
    """[f_lo, f_hi] Hz of the lowest and highest excited DFT line of a record of whole periods (see LINE_FRACTION);
    None when no line is."""
    import scipy.ndimage

    periods = np.asarray(u, float).reshape(-1, samples_per_period)
    mean = periods.mean(axis=0)
    power = np.abs(np.fft.rfft(mean - mean.mean())) ** 2
    power[0] = 0.0
    on = power > LINE_FRACTION * power.max()
    if len(periods) > 1:  # the noise of the averaged period's lines, from the scatter between periods
        scatter = np.sum(np.abs(np.fft.rfft(periods - mean, axis=1)) ** 2, axis=0) / (len(periods) - 1)
        noise = scipy.ndimage.median_filter(scatter / len(periods), size=2 * LINE_NEIGHBOURS + 1, mode="nearest")
        on &= power > LINE_SNR * noise
    on[0] = False
    lines = np.flatnonzero(on)
    if not lines.size:
        return None
    f = np.fft.rfftfreq(samples_per_period, 1.0 / fs)
    return float(f[lines[0]]), float(f[lines[-1]])


def _weights(f: np.ndarray, band: tuple[float, float], periodic: bool) -> np.ndarray:
    """Which frequency content passes: for whole periods every DFT line from band[0]/3 to 3·band[1] (exact,
    no leakage); otherwise zero-phase Butterworth magnitudes, a 4th-order high-pass at band[0]/3 and an
    8th-order low-pass at 3·band[1], which pass the band within (1/3)^8 / 2 = 8e-5."""
    lo, hi = band[0] / 3.0, 3.0 * band[1]
    if periodic:
        return ((f >= lo) & (f <= hi)).astype(float)
    ratio = np.divide(lo, f, out=np.full_like(f, np.inf), where=f > 0)
    hp = np.where(f > 0, 1.0 / np.sqrt(1.0 + np.minimum(ratio, 1e30) ** 8), 0.0)
    return hp / np.sqrt(1.0 + (f / hi) ** 16)


def _detrend(y: np.ndarray, degree: int = 1) -> np.ndarray:
    """y less its least-squares polynomial of `degree` over the record."""
    t = np.linspace(-1.0, 1.0, len(y))
    return y - np.polynomial.polynomial.polyval(t, np.polynomial.polynomial.polyfit(t, y, degree))


def _band_limit(y: np.ndarray, fs: float, band: tuple[float, float], periodic: bool, k: int = 0) -> np.ndarray:
    """Filter and multiply by (iω)^k in the frequency domain (k < 0 integrates: periodic records only); a
    non-periodic record, less its linear trend, is mirrored (even extension) so that its ends join."""
    n = len(y)
    ext = y - np.mean(y) if periodic else np.concatenate([_detrend(y), _detrend(y)[::-1]])
    f = np.fft.rfftfreq(len(ext), 1.0 / fs)
    jw = np.where(f > 0, 2j * np.pi * f, 1.0)  # the weights are zero at f = 0
    spec = np.fft.rfft(ext) * _weights(f, band, periodic) * jw ** float(k)
    return np.fft.irfft(spec, len(ext))[:n]


def convert(signal: np.ndarray, fs: float, given: str, wanted: str, band: tuple[float, float],
            periodic: bool = False) -> np.ndarray:
    """`wanted` ('x', 'v' or 'a') from a record of `given`, band-limited to `band` [Hz].

    Differentiation: iω per order in the frequency domain; for a non-periodic record the derivative of its
    cubic spline over two periods of band[0] at each end, blended in smoothly. Integration of a non-periodic
    record: the antiderivative of its cubic spline (error (ωΔt)^4/384 in the band), less a polynomial of degree m + 1
    after m integrations (sensor offset and drift integrated, and the integration constants); a periodic
    record: 1/(iω) per order."""
    y = np.asarray(signal, float)
    k = ORDER[wanted] - ORDER[given]
    if k == 0 or periodic:
        return _band_limit(y, fs, band, periodic, k)
    if k > 0:  # the mirrored record has a kink at its ends: there, the derivative of its cubic spline instead
        t = np.arange(len(y)) / fs
        inner = _band_limit(y, fs, band, False, k)
        edge = scipy.interpolate.CubicSpline(t, y).derivative(k)(t)
        n_edge = min(len(y) // 4, int(np.ceil(2 * fs / band[0])))  # two periods of the lowest excited frequency
        ramp = np.ones(len(y))
        s = 0.5 - 0.5 * np.cos(np.pi * np.arange(n_edge) / n_edge)  # smooth 0 -> 1
        ramp[:n_edge], ramp[len(y) - n_edge:] = s, s[::-1]
        return ramp * inner + (1 - ramp) * edge
    t = np.arange(len(y)) / fs
    y = _detrend(y)
    for _ in range(-k):
        y = scipy.interpolate.CubicSpline(t, y).antiderivative()(t)
    # an offset and a drift of the sensor, integrated m times, and the m integration constants: a polynomial
    # of degree m + 1, removed over the record (this is the high-pass of an integration)
    return _detrend(y, 1 - k)


def complete(motion: dict[str, np.ndarray], fs: float, band: tuple[float, float],
             periodic: bool = False) -> dict[str, np.ndarray]:
    """x, v and a from the ones recorded (any non-empty subset of 'x', 'v', 'a'): each missing one is derived
    from the recorded one of nearest order (differentiation preferred over integration); recorded ones are
    returned as they are."""
    if not motion:
        raise ValueError("no motion recorded: give one of x, v, a")
    out = dict(motion)
    for want in ("x", "v", "a"):
        if want in out:
            continue
        src = min(motion, key=lambda g: (abs(ORDER[want] - ORDER[g]), ORDER[want] < ORDER[g]))
        out[want] = convert(motion[src], fs, src, want, band, periodic)
    return out
