"""A damper characteristic test (IEC 61897) made with the independent CasADi reference damper: the clamp
impedance at given frequencies and clamp velocity levels, from CVODES runs of a clamp sine (settled, then
first harmonics of F_clamp and v_clamp over whole periods), with optional measurement noise."""
from __future__ import annotations

import numpy as np

from pyfit.analysis.excitation import Excitation, motion_with_derivatives
from pyfit.reference import integrate, models


def reference_impedance(frequencies, velocity_levels, params: dict | None = None, settle: float = 6.0,
                        average: float = 2.0, ramp: float = 1.5, per_period: int = 40,
                        noise: tuple[float, float] = (0.0, 0.0), seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(amplitudes [m], impedance [N·s/m]) arrays of shape (frequencies, levels) at clamp velocity amplitudes
    velocity_levels [m/s]; noise = (relative std of |Z|, std of the phase [rad])."""
    ref = models.damper()
    rng = np.random.default_rng(seed)
    freqs = np.asarray(frequencies, float)
    amps = np.asarray(velocity_levels, float)[None, :] / (2 * np.pi * freqs[:, None])
    z = np.empty(amps.shape, complex)
    for i, f in enumerate(freqs):
        n_avg = max(2, int(round(average * f)))
        n_periods = int(np.ceil(settle * f)) + n_avg
        t = np.arange(n_periods * per_period + 1) / (per_period * f)
        for j, a in enumerate(amps[i]):
            exc = Excitation(kind=1, amplitude=float(a), f_start=float(f), t_ramp=ramp)
            out = integrate.simulate_cvodes(ref, t, params=params, excitation=exc)
            v = motion_with_derivatives(exc, t, ("x", "v"))["v"]
            n = n_avg * per_period
            rotor = np.exp(-2j * np.pi * np.arange(n) / per_period)
            z[i, j] = np.sum(out["F_clamp"][-n - 1:-1] * rotor) / np.sum(v[-n - 1:-1] * rotor)
    z = z * (1 + noise[0] * rng.standard_normal(z.shape)) * np.exp(1j * noise[1] * rng.standard_normal(z.shape))
    return amps, z
