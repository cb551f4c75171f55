"""Signal analysis for hysteretic systems (theory §3): PSD, FRF, loops, power, metrics.

Every function takes samples on a uniform time grid; `assert_uniform` checks it before spectra.
Units follow the signals (SI); PSDs are one-sided in unit^2/Hz.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.interpolate
import scipy.signal


def assert_uniform(t: np.ndarray, rtol: float = 1e-9) -> float:
    """Return the sample period [s] of t, or raise ValueError if the grid is not uniform."""
    t = np.asarray(t, float)
    if t.ndim != 1 or len(t) < 2:
        raise ValueError("time column must be a 1-D array with at least two samples")
    dt = np.diff(t)
    if not np.all(np.isfinite(t)) or np.any(dt <= 0) or np.max(np.abs(dt - dt.mean())) > rtol * dt.mean() + 1e-12:
        raise ValueError(f"time column is not uniformly sampled (steps from {dt.min():.6g} to {dt.max():.6g} s)")
    return float(dt.mean())


def welch_psd(y: np.ndarray, fs: float, segment_s: float | None = None, overlap: float = 0.5):
    """Welch PSD with a Hann window; segment length segment_s [s] (default: the whole record / 8), overlap 50 %.

    Returns (f [Hz], PSD [unit^2/Hz]); its integral over f equals the variance of y (Parseval).
    """
    y = np.asarray(y, float)
    nper = len(y) // 8 if segment_s is None else int(round(segment_s * fs))
    nper = max(16, min(nper, len(y)))
    return scipy.signal.welch(y, fs=fs, window="hann", nperseg=nper, noverlap=int(overlap * nper), detrend=False)


def psd_peak(y: np.ndarray, fs: float, segment_s: float | None = None) -> tuple[float, float]:
    """Frequency [Hz] and value of the largest PSD bin (parabolic interpolation between bins)."""
    f, p = welch_psd(y, fs, segment_s)
    i = int(np.argmax(p[1:]) + 1)
    if 0 < i < len(p) - 1:
        a, b, c = np.log(p[i - 1:i + 2] + 1e-300)
        shift = 0.5 * (a - c) / (a - 2 * b + c) if (a - 2 * b + c) != 0 else 0.0
        return float(f[i] + shift * (f[1] - f[0])), float(p[i])
    return float(f[i]), float(p[i])


def frf_periodic(u: np.ndarray, y: np.ndarray, fs: float, period_samples: int):
    """Leakage-free FRF from whole periods of a periodic excitation (steady state): Y(f)/U(f) at excited lines.

    All whole periods at the end of the record are averaged: pass steady-state samples only. Returns
    (f [Hz], H) for the lines where |U| is above 1e-6 of its maximum.
    """
    n_per = len(u) // period_samples
    if n_per < 1:
        raise ValueError("record shorter than one period")
    uu = np.asarray(u[-n_per * period_samples:]).reshape(n_per, period_samples).mean(0)
    yy = np.asarray(y[-n_per * period_samples:]).reshape(n_per, period_samples).mean(0)
    U, Y = np.fft.rfft(uu), np.fft.rfft(yy)
    f = np.fft.rfftfreq(period_samples, 1 / fs)
    lines = np.abs(U) > 1e-6 * np.max(np.abs(U))
    lines[0] = False
    return f[lines], Y[lines] / U[lines]


def spectrogram(y: np.ndarray, fs: float, segment_s: float = 1.0, overlap: float = 0.75):
    """(f [Hz], t [s], PSD [unit^2/Hz]) with a Hann window."""
    nper = int(round(segment_s * fs))
    return scipy.signal.spectrogram(y, fs=fs, window="hann", nperseg=nper, noverlap=int(overlap * nper))


def instantaneous_frequency(y: np.ndarray, fs: float) -> np.ndarray:
    """Instantaneous frequency [Hz] from the phase of the analytic signal (Hilbert transform)."""
    phase = np.unwrap(np.angle(scipy.signal.hilbert(y - np.mean(y))))
    return np.gradient(phase) * fs / (2 * np.pi)


def loop_area(x: np.ndarray, f: np.ndarray) -> float:
    """Area of a closed loop in the (x, f) plane = the work of f over one cycle, integral f dx (shoelace)."""
    x = np.append(x, x[0])
    f = np.append(f, f[0])
    return float(0.5 * np.sum((f[1:] + f[:-1]) * (x[1:] - x[:-1])))


def last_periods(t: np.ndarray, signals: dict, frequency: float, periods: int = 1) -> dict:
    """The last whole `periods` periods of each signal (for steady-state loops); samples per period must be whole."""
    dt = assert_uniform(t)
    n = int(round(periods / frequency / dt))
    if abs(n * dt * frequency - periods) > 1e-6:
        raise ValueError(f"{periods} period(s) at {frequency} Hz are not a whole number of samples of {dt} s")
    return {k: np.asarray(v)[-n:] for k, v in signals.items()}


@dataclass
class SteadyCycle:
    """Steady-state quantities of one excitation frequency."""

    frequency: float  # Hz
    dissipated_energy: float  # J per cycle, loop area
    mean_power: float  # W, mean(F*v)
    impedance: float  # N*s/m, |F| / |v| at the excitation frequency


def steady_cycle(t, force, velocity, displacement, frequency) -> SteadyCycle:
    """Energy per cycle (loop area of force vs displacement), mean power and impedance at one frequency."""
    last = last_periods(t, {"F": force, "v": velocity, "x": displacement}, frequency)
    n = len(last["F"])
    k = 1  # one period: the fundamental is bin 1
    F1 = np.fft.rfft(last["F"])[k]
    V1 = np.fft.rfft(last["v"])[k]
    return SteadyCycle(frequency, loop_area(last["x"], last["F"]), float(np.mean(last["F"] * last["v"])),
                       float(np.abs(F1) / np.abs(V1)) if n > 2 else float("nan"))


def sweep_power_impedance(t, force, velocity, phase, frequency, at_hz, cycles: int = 8):
    """Dissipated power [W] and impedance [N*s/m] along a slow sweep (IEC 61897 / IEEE 664 quantities).

    phase(t) [rad] and frequency(t) [Hz] describe the excitation (pyfit.analysis.excitation.Excitation). Around
    the time the sweep passes each frequency of at_hz, a window of `cycles` excitation periods gives
    the mean of F*v and the ratio of the fundamental amplitudes |F1|/|V1| (least squares on the
    excitation's sine and cosine). Returns two arrays aligned with at_hz (NaN where the sweep does not
    reach a frequency).
    """
    t = np.asarray(t, float)
    assert_uniform(t)
    f_t = frequency(t)
    power = np.full(len(at_hz), np.nan)
    impedance = np.full(len(at_hz), np.nan)
    for k, f0 in enumerate(at_hz):
        hit = np.nonzero(f_t >= f0)[0]
        if not len(hit) or f0 <= 0:
            continue
        half = cycles / f0 / 2
        sel = (t >= t[hit[0]] - half) & (t <= t[hit[0]] + half)
        if t[hit[0]] - half < t[0] or t[hit[0]] + half > t[-1]:
            continue
        th = phase(t[sel])
        basis = np.column_stack([np.sin(th), np.cos(th), np.ones(sel.sum())])
        cf = np.linalg.lstsq(basis, force[sel], rcond=None)[0]
        cv = np.linalg.lstsq(basis, velocity[sel], rcond=None)[0]
        power[k] = float(np.mean(force[sel] * velocity[sel]))
        impedance[k] = float(np.hypot(*cf[:2]) / np.hypot(*cv[:2]))
    return power, impedance


def without_offset(y: np.ndarray) -> np.ndarray:
    """A channel over the compared samples less its mean. Measured and simulated outputs are compared this
    way: a sensor's zero (a displacement transducer's rest reading, a load cell carrying the damper's weight,
    a DC accelerometer's 1 g) is not dynamics, and the least-squares offset between two records is the
    difference of their means."""
    return y - np.mean(y)


def nrmse(y_ref: np.ndarray, y: np.ndarray) -> float:
    """RMS(y - y_ref) / std(y_ref)."""
    y_ref, y = np.asarray(y_ref), np.asarray(y)
    return float(np.sqrt(np.mean((y - y_ref) ** 2)) / np.std(y_ref))


def rms_db(err: np.ndarray) -> float:
    """20*log10(RMS(err)) in dB re one unit of err."""
    return float(20 * np.log10(np.sqrt(np.mean(np.asarray(err) ** 2))))


def upsample_periodic(u: np.ndarray, factor: int) -> np.ndarray:
    """Band-limited (FFT zero-padding) upsampling of one period of a periodic signal."""
    n = len(u)
    spec = np.fft.rfft(u)
    padded = np.zeros(n * factor // 2 + 1, complex)
    padded[:len(spec)] = spec
    if n % 2 == 0:
        padded[n // 2] *= 0.5  # split the Nyquist bin between +-fs/2
    return np.fft.irfft(padded, n * factor) * factor


# the anti-alias FIR of `decimated` (not periodic): cut-off at 0.8 of the new Nyquist frequency, Kaiser window
# (beta 8), DECIMATION_TAPS taps per unit of the factor on either side: a sine up to 0.6 of the new Nyquist
# frequency passes within 1e-4 of its amplitude, anything above the new Nyquist frequency is attenuated by 100 dB
DECIMATION_CUTOFF = 0.8
DECIMATION_TAPS = 24


def decimated(y: np.ndarray, factor: int, periodic: bool = False) -> np.ndarray:
    """Every `factor`-th sample of y after a zero-phase anti-alias low-pass: for whole periods (`periodic`) the DFT
    lines below the new Nyquist frequency (exact, no leakage); otherwise a polyphase FIR (scipy.signal.resample_poly,
    delay compensated; DECIMATION_CUTOFF). factor 1 returns y."""
    y = np.asarray(y, float)
    if factor == 1:
        return y
    if periodic:
        m = len(y) // factor
        spec = np.fft.rfft(y)[:m // 2 + 1]
        if m % 2 == 0:
            spec[m // 2] = spec[m // 2].real  # the new Nyquist line of a real signal
        return np.fft.irfft(spec, m) / factor
    taps = scipy.signal.firwin(2 * DECIMATION_TAPS * factor + 1, DECIMATION_CUTOFF / factor, window=("kaiser", 8.0))
    return scipy.signal.resample_poly(y, 1, factor, window=taps)


def periodic_drive(period: np.ndarray, factor: int, periods: int) -> np.ndarray:
    """`periods` repetitions of one period upsampled by `factor` (band-limited), plus the closing sample:
    an input for a simulation from rest that reaches the periodic steady state."""
    one = upsample_periodic(period, factor)
    return np.concatenate([np.tile(one, periods), one[:1]])


def upsample_spline(u: np.ndarray, factor: int) -> np.ndarray:
    """Cubic-spline upsampling of a non-periodic signal that starts from rest."""
    t = np.arange(len(u))
    tf = np.arange((len(u) - 1) * factor + 1) / factor
    return scipy.interpolate.CubicSpline(t, u, bc_type="natural")(tf)


def step_quadratics(u: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Slope and curvature [unit/s, unit/s²] at the start of each step between the samples of u (interval dt
    [s]) of the quadratic through its cubic spline (natural ends) at the step's start, middle and end: a drive
    continuous at the samples that follows the spline to fourth order over each step (the last sample: the
    spline's own derivatives)."""
    t = np.arange(len(u)) * dt
    spline = scipy.interpolate.CubicSpline(t, u, bc_type="natural")
    middle = spline(t[:-1] + 0.5 * dt)
    curvature = 4.0 * (u[1:] - 2.0 * middle + u[:-1]) / dt ** 2
    slope = (u[1:] - u[:-1]) / dt - 0.5 * dt * curvature
    return np.append(slope, spline(t[-1], 1)), np.append(curvature, spline(t[-1], 2))


HIGH_PASS_ORDER = 4  # of the zero-phase Butterworth high_passed applies (twice: forward and backward)


def high_passed(y: np.ndarray, fs: float, cutoff_hz: float) -> np.ndarray:
    """y without its content below cutoff_hz [Hz]: a zero-phase Butterworth high-pass of HIGH_PASS_ORDER, run
    forward and backward (its magnitude 1/(1 + (f_c/f)^8), 0.996 at twice the cutoff), the record's ends padded by
    odd reflection."""
    import scipy.signal

    sos = scipy.signal.butter(HIGH_PASS_ORDER, cutoff_hz, "highpass", fs=fs, output="sos")
    return scipy.signal.sosfiltfilt(sos, np.asarray(y, float), padtype="odd")


def delayed(y: np.ndarray, fs: float, delay_s: float, periodic: bool = False) -> np.ndarray:
    """y(t - delay_s) on y's own grid [s]: a periodic record by a phase shift of its DFT (exact for whole
    periods), otherwise by its cubic spline, held at the first or last sample beyond the record."""
    if delay_s == 0.0:
        return y
    if periodic:
        f = np.fft.rfftfreq(len(y), 1.0 / fs)
        return np.fft.irfft(np.fft.rfft(y) * np.exp(-2j * np.pi * f * delay_s), len(y))
    t = np.arange(len(y)) / fs
    return scipy.interpolate.CubicSpline(t, y)(np.clip(t - delay_s, 0.0, t[-1]))


CLIP_RUN = 3  # consecutive samples at the extreme value that a range limit holds and a signal's peak seldom does
CLIP_EDGE = 8.0  # the extreme value's count over its nearest distinct value's: a range limit piles the samples
# beyond it there; a sine's peak code holds about 2.4 x its neighbour's (the arcsine density at the edge)


def clipped_samples(y: np.ndarray) -> int:
    """Samples [count] held at the channel's largest or smallest value by a range limit (an overloaded sensor,
    amplifier or ADC): that value taken in runs of at least CLIP_RUN consecutive samples, and at least CLIP_EDGE
    times as often as the nearest value inside it. A signal within its range gives 0, also one quantized so
    coarsely that its peaks stay on one code for several samples."""
    y = np.asarray(y)
    values, counts = np.unique(y, return_counts=True)
    if len(values) < 3:
        return 0
    held = 0
    for edge, inner in ((0, 1), (-1, -2)):
        steps = np.diff(np.concatenate(([0], (y == values[edge]).astype(np.int8), [0])))
        longest = np.max(np.flatnonzero(steps == -1) - np.flatnonzero(steps == 1))  # the longest run at that value
        if longest >= CLIP_RUN and counts[edge] >= CLIP_EDGE * counts[inner]:
            held += int(counts[edge])
    return held
