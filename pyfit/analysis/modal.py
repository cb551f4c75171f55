"""Modal parameters estimated from simulated or measured responses (no model parameters used)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class Mode:
    """One estimated mode: undamped natural frequency f_n [Hz], damped frequency f_d [Hz], damping ratio zeta [1]."""

    f_n: float
    f_d: float
    zeta: float


def free_decay_modes(y: np.ndarray, dt: float, n_modes: int, rows: int | None = None) -> list[Mode]:
    """Eigensystem Realization Algorithm on a free decay.

    y: samples (n_samples,) or (n_samples, n_channels) of a free response, dt: sample period [s].
    Returns the n_modes under-damped modes, sorted by frequency. Exact (to rounding) for noise-free
    responses of linear systems sampled above twice the highest frequency.
    """
    y = np.asarray(y, float)
    if y.ndim == 1:
        y = y[:, None]
    n, p = y.shape
    order = 2 * n_modes
    rows = rows or max(4 * order, 20)
    cols = n - rows
    if cols <= order:
        raise ValueError("free decay too short for the requested number of modes")
    scale = np.max(np.abs(y), axis=0)
    scale[scale == 0] = 1.0
    ys = y / scale
    H0 = np.empty((rows * p, cols))
    H1 = np.empty((rows * p, cols))
    for i in range(rows):
        H0[i * p:(i + 1) * p] = ys[i:i + cols].T
        H1[i * p:(i + 1) * p] = ys[i + 1:i + 1 + cols].T
    U, s, Vt = np.linalg.svd(H0, full_matrices=False)
    U, s, Vt = U[:, :order], s[:order], Vt[:order]
    S_half_inv = np.diag(1.0 / np.sqrt(s))
    A = S_half_inv @ U.T @ H1 @ Vt.T @ S_half_inv
    mu = np.linalg.eigvals(A)
    lam = np.log(mu.astype(complex)) / dt
    lam = lam[lam.imag > 0]
    modes = [Mode(f_n=abs(l) / (2 * np.pi), f_d=l.imag / (2 * np.pi), zeta=-l.real / abs(l)) for l in lam]
    return sorted(modes, key=lambda m: m.f_n)


def state_space_modes(M: np.ndarray, C: np.ndarray, K: np.ndarray) -> list[Mode]:
    """Damped modes of M q'' + C q' + K q = 0 from the eigenvalues of its first-order form."""
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ K, -Minv @ C]])
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 0]
    modes = [Mode(f_n=abs(l) / (2 * np.pi), f_d=l.imag / (2 * np.pi), zeta=-l.real / abs(l)) for l in lam]
    return sorted(modes, key=lambda m: m.f_n)


def frf_peaks(u: np.ndarray, y: np.ndarray, fs: float, band: tuple[float, float], output_order: int = 0,
              segment_s: float | None = 8.0, prominence: float = 0.3) -> list[Mode]:
    """Resonance peaks of a measured FRF y/u inside `band` [Hz], lowest first, from any input (sweep,
    stepped sine, noise, multisine): the H1 estimate S_uy/S_uu from Welch segments (Hann) of segment_s
    seconds (at most the record), or with segment_s None the ratio of the whole record's DFTs (no window:
    exact for a response from rest that has died out by the end, however fast the sweep; noisy for a
    random input); |H| divided by (2πf)^output_order (an acceleration output over a displacement input:
    order 2), on the lines where the input's power is at least 1e-3 of its largest, peaks standing out by
    `prominence` x the largest, the peak frequency refined by a parabola
    through log|H| at the three lines around it, and the damping ratio from the half-power width
    (zeta = Δf / (2 f_n); at least the line spacing)."""
    import scipy.signal

    seg = len(u) if segment_s is None else int(min(len(u), segment_s * fs))
    window = "boxcar" if segment_s is None else "hann"
    f, suu = scipy.signal.welch(u, fs, window=window, nperseg=seg)
    _, suy = scipy.signal.csd(u, y, fs, window=window, nperseg=seg)
    # lines where the input has power (a sweep's spectrum falls by decades outside the swept band)
    inside = (f >= band[0]) & (f <= band[1]) & (f > 0) & (suu > 1e-3 * suu[1:].max())
    if inside.sum() < 5:
        return []
    f, mag = f[inside], np.abs(suy[inside] / suu[inside]) / (2 * np.pi * f[inside]) ** output_order
    peaks, _ = scipy.signal.find_peaks(mag, prominence=prominence * mag.max())
    df = f[1] - f[0]
    modes = []
    for p in peaks:
        f_n = f[p]
        if 0 < p < len(f) - 1:
            a, b, c = np.log(mag[p - 1:p + 2])
            if a - 2 * b + c < 0:
                f_n = f[p] + 0.5 * df * (a - c) / (a - 2 * b + c)
        half = mag[p] / np.sqrt(2.0)
        lo, hi = p, p
        while lo > 0 and mag[lo] > half:
            lo -= 1
        while hi < len(f) - 1 and mag[hi] > half:
            hi += 1
        width = max(float(np.interp(half, [mag[hi], mag[hi - 1]], [f[hi], f[hi - 1]]) -
                          np.interp(half, [mag[lo], mag[lo + 1]], [f[lo], f[lo + 1]])), df)
        modes.append(Mode(f_n=float(f_n), f_d=float(f_n), zeta=width / (2 * f_n)))
    return modes
