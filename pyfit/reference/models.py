"""Hand-written CasADi models of theory §1, independent of the Modelica sources.

Each model is a second-order system in first-order form with states [q (n_q), qdot (n_q), z (n_z)]:
positions, velocities and first-order internal (hysteretic) variables. The right-hand side gives the
accelerations explicitly, so the same model serves CVODES and the Newmark scheme. SI units.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

SDOF_DEFAULTS = dict(m=2.0, c=10.0, k=5e4, alpha=5e4, beta=1e3, gamma=0.8, delta=-1.1, nu=1.0,
                     k3=0.0, F_c=0.0, v_s=1e-3, c2=0.0)
TWO_DOF_DEFAULTS = dict(m1=0.5, m2=1.0, k1=2000.0, k2=5000.0, k12=500.0, c1=5.0, c2=2.0, c12=1.0,
                        alpha=500.0, beta=10.0, gamma=0.8, delta=-1.1, nu=2.0, k_nl=1e6)
DAMPER_DEFAULTS = dict(EI=10.0, mu=0.3, L1=0.17, L2=0.12, m1=0.8, m2=0.6, J_G1=1.68e-3, J_G2=1.26e-3,
                       a1=0.0325, a2=0.0325, m_c=0.6, J_GC=2.5e-4, alpha_pd=2.0, beta_pd=2e-4,
                       k_bw1=300.0, k_bw2=500.0, a_bw=0.3, A=1.0, beta=0.6, gamma=0.4, nu=1.0, D=1e-3,
                       k_cs1=-5e6, k_cs2=-1.5e7, F_c1=0.0, F_c2=0.0, v_s=1e-3, c2_1=0.0, c2_2=0.0)


@dataclass
class ReferenceModel:
    """xdot = rhs(x, u, p, t) with x = [q, qdot, z]; outputs are expressions of (x, u, p, t)."""

    name: str
    n_q: int
    n_z: int
    x: ca.SX
    u: ca.SX  # inputs (force, or clamp displacement/velocity/acceleration)
    p: ca.SX
    t: ca.SX
    rhs: ca.SX
    outputs: dict[str, ca.SX]
    param_names: list[str]
    input_names: list[str]
    defaults: dict[str, float] = field(default_factory=dict)

    def function(self) -> ca.Function:
        """f(x, u, p, t) -> xdot."""
        return ca.Function(f"{self.name}_rhs", [self.x, self.u, self.p, self.t], [self.rhs])

    def output_function(self) -> ca.Function:
        """g(x, u, p, t) -> outputs (vertically stacked in the order of self.outputs)."""
        return ca.Function(f"{self.name}_out", [self.x, self.u, self.p, self.t], [ca.vertcat(*self.outputs.values())])

    def param_vector(self, overrides: dict | None = None) -> np.ndarray:
        vals = dict(self.defaults)
        for k, v in (overrides or {}).items():
            if k not in vals:
                raise KeyError(f"{self.name}: unknown parameter '{k}'; valid: {', '.join(self.param_names)}")
            vals[k] = v
        return np.array([vals[n] for n in self.param_names], float)


def _params(names):
    syms = {n: ca.SX.sym(n) for n in names}
    return syms, ca.vertcat(*[syms[n] for n in names])


def bouc_wen_rate(v, z, alpha, beta, gamma, delta, nu):
    """Classic Bouc-Wen law (theory §1.1): dz/dt = alpha*v - beta*(gamma*|v|*|z|^(nu-1)*z + delta*v*|z|^nu)."""
    az = ca.fabs(z) ** nu
    return alpha * v - beta * (gamma * ca.fabs(v) * ca.sign(z) * az + delta * v * az)


def sdof() -> ReferenceModel:
    """SDOF Bouc-Wen oscillator m*y'' + c*y' + k*y + z (+ candidate effects) = u."""
    names = list(SDOF_DEFAULTS)
    P, p = _params(names)
    y, v, z, u, t = (ca.SX.sym(n) for n in ("y", "v", "z", "u", "t"))
    f_extra = P["k3"] * y**3 + P["F_c"] * ca.tanh(v / P["v_s"]) + P["c2"] * v * ca.fabs(v)
    acc = (u - P["c"] * v - P["k"] * y - z - f_extra) / P["m"]
    zdot = bouc_wen_rate(v, z, P["alpha"], P["beta"], P["gamma"], P["delta"], P["nu"])
    x = ca.vertcat(y, v, z)
    return ReferenceModel("SDOFBoucWen", 1, 1, x, u, p, t, ca.vertcat(v, acc, zdot),
                          {"y": y, "v": v, "z": z, "a": acc}, names, ["u"], dict(SDOF_DEFAULTS))


def two_dof(config: str) -> ReferenceModel:
    """TwoDOF system of theory §1.2, configuration 'a'..'d'; force f on mass 1."""
    if config not in ("a", "b", "c", "d"):
        raise ValueError(f"TwoDOF configuration must be a, b, c or d, not {config!r}")
    names = list(TWO_DOF_DEFAULTS)
    P, p = _params(names)
    y1, y2, v1, v2, z, f, t = (ca.SX.sym(n) for n in ("y1", "y2", "v1", "v2", "z", "f", "t"))
    between = config in ("b", "d")
    r, rd = (y2 - y1, v2 - v1) if between else (y2, v2)
    element = z + (P["k_nl"] * r**3 if config in ("c", "d") else 0)  # force on mass 2 is -element
    F1 = f - P["k1"] * y1 - P["c1"] * v1 + P["k12"] * (y2 - y1) + P["c12"] * (v2 - v1)
    F2 = -P["k2"] * y2 - P["c2"] * v2 - P["k12"] * (y2 - y1) - P["c12"] * (v2 - v1) - element
    if between:
        F1 = F1 + element  # equal and opposite
    zdot = bouc_wen_rate(rd, z, P["alpha"], P["beta"], P["gamma"], P["delta"], P["nu"])
    x = ca.vertcat(y1, y2, v1, v2, z)
    rhs = ca.vertcat(v1, v2, F1 / P["m1"], F2 / P["m2"], zdot)
    return ReferenceModel(f"TwoDOF{config}", 2, 1, x, f, p, t, rhs,
                          {"y1": y1, "y2": y2, "v1": v1, "v2": v2, "z": z}, names, ["f"], dict(TWO_DOF_DEFAULTS))


def beam_matrices(EI, mu, L):
    """Euler-Bernoulli element stiffness and consistent mass matrices (DOFs w1, theta1, w2, theta2)."""
    K = EI / L**3 * ca.vertcat(
        ca.horzcat(12, 6 * L, -12, 6 * L), ca.horzcat(6 * L, 4 * L**2, -6 * L, 2 * L**2),
        ca.horzcat(-12, -6 * L, 12, -6 * L), ca.horzcat(6 * L, 2 * L**2, -6 * L, 4 * L**2))
    M = mu * L / 420 * ca.vertcat(
        ca.horzcat(156, 22 * L, 54, -13 * L), ca.horzcat(22 * L, 4 * L**2, 13 * L, -3 * L**2),
        ca.horzcat(54, 13 * L, 156, -22 * L), ca.horzcat(-13 * L, -3 * L**2, -22 * L, 4 * L**2))
    return K, M


def damper_matrices(P) -> tuple[ca.SX, ca.SX]:
    """Global K and M (DOFs x1, phi1, xc, phic, x2, phi2) of the 6-DOF damper, end masses included."""
    K = ca.SX.zeros(6, 6)
    M = ca.SX.zeros(6, 6)
    for i, L in ((0, P["L1"]), (2, P["L2"])):
        ke, me = beam_matrices(P["EI"], P["mu"], L)
        K[i:i + 4, i:i + 4] = K[i:i + 4, i:i + 4] + ke
        M[i:i + 4, i:i + 4] = M[i:i + 4, i:i + 4] + me
    for node, m, J, a, side in ((0, P["m1"], P["J_G1"], P["a1"], -1), (4, P["m2"], P["J_G2"], P["a2"], 1)):
        lump = ca.vertcat(ca.horzcat(m, side * m * a), ca.horzcat(side * m * a, J + m * a**2))
        M[node:node + 2, node:node + 2] = M[node:node + 2, node:node + 2] + lump
    return K, M


def damper_modes_hz(params: dict) -> np.ndarray:
    """Undamped natural frequencies [Hz] of the linear damper on a fixed clamp (the four free DOFs of
    damper_matrices, nonlinear elements off), ascending; params: DAMPER_DEFAULTS names, SI."""
    import scipy.linalg

    K, M = damper_matrices({**DAMPER_DEFAULTS, **params})
    free = [0, 1, 4, 5]
    Kf, Mf = (np.array(ca.evalf(X[free, free])) for X in (K, M))
    return np.sqrt(np.abs(scipy.linalg.eigh(Kf, Mf, eigvals_only=True))) / (2 * np.pi)


def damper() -> ReferenceModel:
    """Stockbridge damper on a shaker (theory §1.3): clamp displacement, velocity, acceleration prescribed."""
    names = list(DAMPER_DEFAULTS)
    P, p = _params(names)
    q = ca.SX.sym("q", 4)  # x1, phi1, x2, phi2 (absolute)
    qd = ca.SX.sym("qd", 4)
    z = ca.SX.sym("z", 2)
    xc, vc, ac, t = (ca.SX.sym(n) for n in ("x_base", "v_base", "a_base", "t"))
    K, M = damper_matrices(P)
    free, clamp = [0, 1, 4, 5], [2]
    Kff, Kfc = K[free, free], K[free, clamp]
    Mff, Mfc = M[free, free], M[free, clamp]
    T = ca.DM([1, 0, 1, 0])
    rel_v = qd - T * vc
    C = P["alpha_pd"] * Mff + P["beta_pd"] * Kff
    r = ca.vertcat(q[0] - xc, q[2] - xc)
    rd = ca.vertcat(qd[0] - vc, qd[2] - vc)
    f_nl = []
    zdot = []
    for i, (kbw, kcs, fc, c2) in enumerate(((P["k_bw1"], P["k_cs1"], P["F_c1"], P["c2_1"]),
                                            (P["k_bw2"], P["k_cs2"], P["F_c2"], P["c2_2"]))):
        az = ca.fabs(z[i]) ** P["nu"]
        zdot.append((P["A"] * rd[i] - P["beta"] * ca.fabs(rd[i]) * ca.sign(z[i]) * az
                     - P["gamma"] * rd[i] * az) / P["D"])
        f_nl.append(kbw * (P["a_bw"] * r[i] + (1 - P["a_bw"]) * P["D"] * z[i]) + kcs * r[i] ** 3
                    + fc * ca.tanh(rd[i] / P["v_s"]) + c2 * rd[i] * ca.fabs(rd[i]))
    F_nl = ca.vertcat(f_nl[0], 0, f_nl[1], 0)
    qdd = ca.solve(Mff, -(Mfc * ac + C @ rel_v + Kff @ q + Kfc * xc + F_nl))
    # clamp force = rate of change of the total vertical momentum (independent of the force path)
    q_full_dd = ca.vertcat(qdd[0], qdd[1], ac, 0, qdd[2], qdd[3])
    T_full = ca.DM([1, 0, 1, 0, 1, 0])
    F_clamp = P["m_c"] * ac + T_full.T @ M @ q_full_dd
    x = ca.vertcat(q, qd, z)
    outputs = {"x1": q[0], "x2": q[2], "phi1": q[1], "phi2": q[3],
               "xg1": q[0] - P["a1"] * q[1], "xg2": q[2] + P["a2"] * q[3], "F_clamp": F_clamp,
               "acc_x1": qdd[0], "acc_x2": qdd[2], "acc_xg1": qdd[0] - P["a1"] * qdd[1],
               "acc_xg2": qdd[2] + P["a2"] * qdd[3]}
    return ReferenceModel("StockbridgeDamper", 4, 2, x, ca.vertcat(xc, vc, ac), p, t,
                          ca.vertcat(qd, qdd, *zdot), outputs, names, ["x_base", "v_base", "a_base"],
                          dict(DAMPER_DEFAULTS))


# the examples with a hand-written reference; the element FMUs are checked against scipy in tests/test_elements.py
NAMES = ("SDOFBoucWen", "TwoDOFa", "TwoDOFb", "TwoDOFc", "TwoDOFd", "StockbridgeDamper")


def by_name(name: str) -> ReferenceModel:
    """The reference model of an exported example (SDOFBoucWen, TwoDOFa..d, StockbridgeDamper)."""
    if name == "SDOFBoucWen":
        return sdof()
    if name.startswith("TwoDOF") and len(name) == 7:
        return two_dof(name[-1])
    if name == "StockbridgeDamper":
        return damper()
    raise KeyError(f"no reference model '{name}'")
