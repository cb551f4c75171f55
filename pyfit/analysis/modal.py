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
