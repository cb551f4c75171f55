"""Excitation signals of theory §2, as functions of time that work on numpy arrays and on CasADi symbols.

The same formulas are built into the FMUs (Modelica `Sources.Excitation`); these are an independent
implementation, used to drive the CasADi reference and to make input arrays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

KINDS = {0: "off", 1: "sine", 2: "linear sweep", 3: "log sweep", 4: "constant-velocity linear sweep",
         5: "constant-velocity log sweep"}


@dataclass(frozen=True)
class Excitation:
    """Built-in excitation: kind as in the FMUs' exc_type; amplitude in the signal's unit (kinds 1-3) or
    velocity amplitude in m/s with a displacement signal (kinds 4-5). Frequencies in Hz, rate in Hz/s,
    octaves_per_minute for log sweeps, t_ramp [s] for a C2-smooth ramp-in from zero."""

    kind: int = 0
    amplitude: float = 1.0
    f_start: float = 1.0
    f_end: float = 60.0
    rate: float = 0.5
    octaves_per_minute: float = 1.0
    t_ramp: float = 0.0

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"excitation kind {self.kind} unknown; valid: {KINDS}")
        if self.kind in (3, 4, 5) and self.f_start <= 0:
            raise ValueError("log and constant-velocity sweeps need f_start > 0")

    def frequency(self, t):
        """Instantaneous frequency [Hz]."""
        xp = _ops(t)
        if self.kind == 1:
            return self.f_start + 0 * t
        if self.kind in (2, 4):
            return self.f_start + self.rate * xp.minimum(t, self._t_end())
        k = self.octaves_per_minute / 60.0
        return self.f_start * 2.0 ** (k * xp.minimum(t, self._t_end()))

    def _t_end(self):
        if self.kind in (2, 4):
            return (self.f_end - self.f_start) / self.rate
        if self.kind in (3, 5):
            return np.log2(self.f_end / self.f_start) / (self.octaves_per_minute / 60.0)
        return np.inf

    def phase(self, t):
        """Phase [rad], continuous; after the sweep the frequency stays at f_end."""
        xp = _ops(t)
        if self.kind == 1:
            return 2 * np.pi * self.f_start * t
        te = xp.minimum(t, self._t_end())
        if self.kind in (2, 4):
            return 2 * np.pi * (self.f_start * te + 0.5 * self.rate * te**2 + self.f_end * (t - te))
        k = self.octaves_per_minute / 60.0
        return 2 * np.pi * (self.f_start * (2.0 ** (k * te) - 1) / (k * np.log(2)) + self.f_end * (t - te))

    def envelope(self, t):
        """C2-smooth ramp 10s^3 - 15s^4 + 6s^5 over t_ramp, then 1."""
        if self.t_ramp <= 0:
            return 1.0 + 0 * t
        return smooth_step(_ops(t).minimum(t / self.t_ramp, 1.0))

    def __call__(self, t):
        """The signal at time(s) t (numpy array or CasADi expression)."""
        if self.kind == 0:
            return 0 * t
        xp = _ops(t)
        a = self.amplitude * self.envelope(t)
        if self.kind >= 4:
            a = a / (2 * np.pi * self.frequency(t))
        return a * xp.sin(self.phase(t))


def _is_symbolic(t) -> bool:
    """A CasADi expression (CasADi itself is imported only when one is passed)."""
    return type(t).__module__.startswith("casadi")


def _ops(t):
    """numpy, or CasADi's functions of the same names for a symbolic t."""
    if not _is_symbolic(t):
        return np
    import casadi as ca

    class _Casadi:
        minimum = staticmethod(ca.fmin)
        maximum = staticmethod(ca.fmax)
        sin = staticmethod(ca.sin)

    return _Casadi


def multisine(n_samples: int, fs: float, f_min: float, f_max: float, rms: float, seed: int = 0,
              odd: bool = False) -> np.ndarray:
    """One period of a random-phase multisine with flat amplitude spectrum on [f_min, f_max] Hz, scaled to rms.

    odd=True: a random-odd multisine (only odd multiples of fs/n_samples, one of every four left out), so
    that odd and even nonlinear distortion show on the lines left unexcited (Pintelon & Schoukens).
    Periodic with n_samples per period, so a whole number of periods is leakage-free.
    """
    rng = np.random.default_rng(seed)
    spec = np.zeros(n_samples // 2 + 1, complex)
    f = np.fft.rfftfreq(n_samples, 1 / fs)
    band = (f >= f_min) & (f <= f_max) & (f > 0)
    if odd:  # odd lines only, one left out at random in every group of four: detection lines
        lines = np.flatnonzero(band & (np.arange(len(f)) % 2 == 1))
        band[:] = False
        for g in range(0, len(lines), 4):
            group = lines[g:g + 4]
            band[np.delete(group, rng.integers(len(group))) if len(group) == 4 else group] = True
    if not band.any():
        raise ValueError(f"no frequency line of a {n_samples}-sample period at {fs} Hz lies in [{f_min}, {f_max}]")
    spec[band] = np.exp(2j * np.pi * rng.random(band.sum()))
    u = np.fft.irfft(spec, n_samples)
    return u * rms / np.sqrt(np.mean(u**2))


@dataclass(frozen=True)
class MultisineInput:
    """A force input of whole periods of a random-phase multisine: band [Hz], RMS [N], samples per period."""

    f_min: float
    f_max: float
    rms: float
    samples_per_period: int
    periods: int
    seed: int = 0
    odd: bool = False  # random-odd multisine (detection lines for odd/even distortion)

    def __call__(self, fs: float) -> np.ndarray:
        """All periods at the sensor rate fs [Hz]."""
        return np.tile(multisine(self.samples_per_period, fs, self.f_min, self.f_max, self.rms, self.seed,
                                 self.odd), self.periods)


class SineSum:
    """A sum of sines, mean + sum_i a_i cos(w_i t + p_i), optionally ramped in from rest (the C2 ramp of
    `Excitation.envelope` over t_ramp [s]), evaluated at any time t [s] (numpy arrays or CasADi expressions):
    the exact continuous-time input an integrator with its own steps needs."""

    kind = -1  # not a built-in FMU excitation

    def __init__(self, amplitudes, omegas, phases, mean: float = 0.0, t_ramp: float = 0.0):
        self.amplitudes, self.omegas = np.asarray(amplitudes, float), np.asarray(omegas, float)
        self.phases, self.mean, self.t_ramp = np.asarray(phases, float), float(mean), float(t_ramp)

    def derivative(self, t: np.ndarray, order: int) -> np.ndarray:
        """The order-th time derivative at times t [s] (numpy), exact; a ramped signal only after its ramp."""
        if self.t_ramp > 0 and np.min(t) < self.t_ramp:
            raise ValueError("derivative of a ramped sum of sines is given after the ramp only; use "
                             "motion_with_derivatives")
        t = np.asarray(t, float)
        w = self.omegas[:, None]
        return np.sum(self.amplitudes[:, None] * w**order * np.cos(w * t.ravel() + self.phases[:, None]
                                                                  + order * np.pi / 2), axis=0).reshape(t.shape)

    def __call__(self, t):
        ramp = Excitation(1, t_ramp=self.t_ramp).envelope(t)
        if _is_symbolic(t):
            import casadi as ca

            out = 0.0
            for a, w, p in zip(self.amplitudes, self.omegas, self.phases):
                out = out + a * ca.cos(w * t + p)
            return self.mean + ramp * out
        t = np.asarray(t, float)
        waves = np.sum(self.amplitudes[:, None] * np.cos(np.outer(self.omegas, t.ravel()) + self.phases[:, None]),
                       axis=0).reshape(t.shape)
        return self.mean + ramp * waves


class PeriodicSignal(SineSum):
    """A band-limited periodic signal given by one period of samples at fs [Hz], as the sum of its DFT lines."""

    def __init__(self, period_samples: np.ndarray, fs: float):
        n = len(period_samples)
        spec = np.fft.rfft(period_samples) / n
        lines = np.flatnonzero(np.abs(spec) > 1e-12 * np.abs(spec).max())
        lines = lines[lines > 0]
        scale = np.where(2 * lines == n, 1.0, 2.0)
        super().__init__(scale * np.abs(spec[lines]), 2 * np.pi * lines * fs / n, np.angle(spec[lines]),
                         float(spec[0].real))


def band_noise(f_min: float, f_max: float, rms: float, seed: int = 0, lines: int = 150,
               t_ramp: float = 1.0) -> SineSum:
    """Band-limited random noise on [f_min, f_max] Hz with the given RMS (after the ramp), as a shaker fed
    by a noise generator gives it: `lines` sines at frequencies drawn uniformly in the band (not on a common
    grid, so the signal never repeats), Rayleigh amplitudes and uniform phases: a Gaussian process with a flat
    spectrum by the central limit theorem."""
    rng = np.random.default_rng(seed)
    amplitudes = rng.rayleigh(1.0, lines)
    amplitudes *= rms / np.sqrt(np.sum(amplitudes**2) / 2)
    return SineSum(amplitudes, 2 * np.pi * rng.uniform(f_min, f_max, lines), rng.uniform(0, 2 * np.pi, lines),
                   t_ramp=t_ramp)


@dataclass(frozen=True)
class SteppedSine:
    """A stepped sine as a sine-test controller plays it: `amplitude` (the signal's unit) at each frequency
    of `frequencies` [Hz] for `dwell_s` seconds, the phase continuous across a step, ramped in from rest over
    t_ramp [s]; after the last step the last frequency holds. Works on numpy arrays and CasADi expressions.

    glide_s > 0: the frequency glides to the next step's over the first glide_s seconds of it (the C2 ramp of
    Excitation.envelope) instead of jumping, as a controller moving a shaker's motion does: with
    velocity = True, `amplitude` is the velocity amplitude [signal unit/s] and the signal (a displacement) has
    amplitude / (2 pi f(t)), so that the displacement, its velocity and its acceleration are all continuous (a
    damper's clamp under a constant-velocity stepped sine)."""

    frequencies: tuple
    dwell_s: float
    amplitude: float = 1.0
    t_ramp: float = 0.5
    glide_s: float = 0.0
    velocity: bool = False
    kind = -1  # not a built-in FMU excitation

    def __post_init__(self):
        if self.velocity and self.glide_s <= 0:
            raise ValueError("SteppedSine: velocity = True needs glide_s > 0 (a displacement of constant velocity "
                             "amplitude would jump at a step)")

    def frequency(self, t):
        """Instantaneous frequency [Hz] (numpy arrays or CasADi expressions; numpy only without a glide)."""
        if self.glide_s > 0:
            xp = _ops(t)
            f = np.asarray(self.frequencies, float)
            return f[0] + sum((f[j] - f[j - 1]) * smooth_step(xp.maximum(xp.minimum(
                (t - j * self.dwell_s) / self.glide_s, 1.0), 0.0)) for j in range(1, len(f)))
        step = np.clip(np.floor(np.asarray(t, float) / self.dwell_s).astype(int), 0, len(self.frequencies) - 1)
        return np.asarray(self.frequencies, float)[step]

    def phase(self, t):
        """Phase [rad]: 2 pi sum_j f_j (time spent in step j up to t); with a glide, 2 pi times the integral of
        frequency(t)."""
        if self.glide_s > 0:
            xp = _ops(t)
            f, g = np.asarray(self.frequencies, float), self.glide_s
            turns = f[0] * t
            for j in range(1, len(f)):
                x = (t - j * self.dwell_s) / g
                c = xp.maximum(xp.minimum(x, 1.0), 0.0)
                # the integral of the C2 ramp 10c^3 - 15c^4 + 6c^5 up to c, then 1 a second (in units of g)
                turns = turns + (f[j] - f[j - 1]) * g * (c**4 * (2.5 - 3 * c + c**2) + xp.maximum(x - 1.0, 0.0))
            return 2 * np.pi * turns
        if _is_symbolic(t):
            import casadi as ca

            clip = lambda x, hi: ca.fmin(ca.fmax(x, 0.0), hi)  # noqa: E731
        else:
            clip = lambda x, hi: np.clip(x, 0.0, hi)  # noqa: E731
        last = len(self.frequencies) - 1
        return 2 * np.pi * sum(f * clip(t - j * self.dwell_s, np.inf if j == last else self.dwell_s)
                               for j, f in enumerate(self.frequencies))

    def __call__(self, t):
        xp = _ops(t)
        amplitude = self.amplitude / (2 * np.pi * self.frequency(t)) if self.velocity else self.amplitude
        return amplitude * Excitation(1, t_ramp=self.t_ramp).envelope(t) * xp.sin(self.phase(t))


def smooth_step(c):
    """The C2 ramp 10c^3 - 15c^4 + 6c^5 from 0 to 1 over c in [0, 1] (Excitation.envelope, SteppedSine's glide;
    the Modelica Excitation source's env)."""
    return c**3 * (10 - 15 * c + 6 * c**2)


def motion_with_derivatives(exc: Excitation, t: np.ndarray, names: tuple[str, ...]) -> dict[str, np.ndarray]:
    """A prescribed motion and its exact first and second derivatives on the grid t [s] (CasADi AD), named
    by `names` (e.g. x_base, v_base, a_base)."""
    import casadi as ca

    ts = ca.SX.sym("t")
    x = exc(ts)
    dx = ca.jacobian(x, ts)
    f = ca.Function("motion", [ts], [x, dx, ca.jacobian(dx, ts)])
    cols = [np.array(c).ravel() for c in f.map(len(t))(t[None, :])]
    return dict(zip(names, cols))
