"""Independent assembly of the damper finite-element model of theory §1.3 (numpy only, not the
Modelica sources): consistent Euler-Bernoulli beam matrices plus the eccentric end masses, default
parameters. DOFs [x1, phi1, xc, phic, x2, phi2]; the clamp's own mass is not included."""
import numpy as np

EI, MU, L1, L2 = 10.0, 0.3, 0.17, 0.12  # N·m², kg/m, m, m
ALPHA_PD, BETA_PD = 2.0, 2e-4  # 1/s, s (Rayleigh damping, relative to the clamp)
FREE = [0, 1, 4, 5]  # the clamp DOFs (2, 3) follow the shaker
TRANSLATION = np.array([1.0, 0, 1.0, 0, 1.0, 0])  # rigid vertical translation of every node


def full_matrices():
    """Mass and stiffness matrices (6 x 6) of the damper, clamp DOFs included."""
    K = np.zeros((6, 6))
    M = np.zeros((6, 6))
    for i, L in ((0, L1), (2, L2)):
        K[i:i + 4, i:i + 4] += EI / L**3 * np.array(
            [[12, 6 * L, -12, 6 * L], [6 * L, 4 * L**2, -6 * L, 2 * L**2],
             [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L**2, -6 * L, 4 * L**2]])
        M[i:i + 4, i:i + 4] += MU * L / 420 * np.array(
            [[156, 22 * L, 54, -13 * L], [22 * L, 4 * L**2, 13 * L, -3 * L**2],
             [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L**2, -22 * L, 4 * L**2]])
    for node, m, J, a, side in ((0, 0.8, 1.68e-3, 0.0325, -1), (4, 0.6, 1.26e-3, 0.0325, 1)):
        M[node:node + 2, node:node + 2] += [[m, side * m * a], [side * m * a, J + m * a * a]]
    return M, K


def clamped_matrices():
    """M, C, K of the four free DOFs with the clamp held (C = alpha M + beta K)."""
    M, K = full_matrices()
    M, K = M[np.ix_(FREE, FREE)], K[np.ix_(FREE, FREE)]
    return M, ALPHA_PD * M + BETA_PD * K, K


def clamp_power(f: float, amplitude: float) -> float:
    """Mean power [W] into the linear damper when its clamp moves amplitude·sin(2π f t) [m]: harmonic
    solution in coordinates relative to the clamp; the clamp force is the rate of change of momentum."""
    M6, _ = full_matrices()
    M, C, K = clamped_matrices()
    w = 2 * np.pi * f
    q_rel = np.linalg.solve(K - w**2 * M + 1j * w * C, w**2 * amplitude * (M6 @ TRANSLATION)[FREE])
    q_abs = TRANSLATION * amplitude + 0j
    q_abs[FREE] += q_rel
    force = -w**2 * TRANSLATION @ M6 @ q_abs  # complex amplitude of the clamp force
    return 0.5 * float(np.real(force * np.conj(1j * w * amplitude)))
