"""Integrators for the CasADi reference models: CVODES (variable order BDF/Adams via CasADi) and the
seed's Newmark scheme (a = 0.5, b = 0.25 on the mechanical states, trapezoidal c = 0.5 on z; predictor,
then Newton corrector through a CasADi rootfinder). Both run the whole grid inside CasADi (mapaccum).
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from pyfit.analysis.excitation import Excitation
from pyfit.reference.models import ReferenceModel


def _input_expr(model: ReferenceModel, excitation: Excitation | None, t: ca.SX) -> ca.SX:
    """The model's input vector produced by a built-in excitation at time t (exact derivatives for a clamp motion)."""
    n_u = model.u.numel()
    if excitation is None or excitation.kind == 0:
        return ca.SX.zeros(n_u)
    s = ca.SX.sym("s")
    e = excitation(s)
    if n_u > 1:
        de = ca.jacobian(e, s)
        e = ca.vertcat(e, de, ca.jacobian(de, s))
    return ca.substitute(e, s, t)


def _sampled_inputs(model: ReferenceModel, inputs: dict | None, n: int) -> np.ndarray:
    u = np.zeros((model.u.numel(), n))
    for name, values in (inputs or {}).items():
        if name not in model.input_names:
            raise KeyError(f"{model.name}: no input '{name}'; inputs: {model.input_names}")
        values = np.asarray(values, float)
        if values.shape != (n,):
            raise ValueError(f"{model.name}: input '{name}' has {values.shape} samples, the grid has {n}")
        u[model.input_names.index(name)] = values
    return u


def _check_grid(t: np.ndarray) -> float:
    t = np.asarray(t, float)
    h = np.diff(t)
    if len(t) < 2 or not np.allclose(h, h[0], rtol=1e-9, atol=0):
        raise ValueError("the time grid must be uniform with at least two points")
    return float(h[0])


def _outputs(model, X, U, p, t):
    g = model.output_function().map(X.shape[1])
    Y = np.array(g(X, U, ca.repmat(ca.DM(p), 1, X.shape[1]), ca.DM(t).T))
    return {name: Y[i] for i, name in enumerate(model.outputs)}


def simulate_cvodes(model: ReferenceModel, t: np.ndarray, params: dict | None = None,
                    excitation: Excitation | None = None, inputs: dict | None = None,
                    rtol: float = 1e-10, atol: float = 1e-14, x0: np.ndarray | None = None) -> dict:
    """Outputs on the uniform grid t; sampled inputs are linear between grid points (plus the excitation)."""
    h = _check_grid(t)
    t = np.asarray(t, float)
    p = model.param_vector(params)
    U = _sampled_inputs(model, inputs, len(t))
    tau, tk = ca.SX.sym("tau"), ca.SX.sym("tk")
    u0, slope = ca.SX.sym("u0", model.u.numel()), ca.SX.sym("slope", model.u.numel())
    u_of_t = u0 + slope * tau + _input_expr(model, excitation, tk + tau)
    ode = ca.substitute(model.rhs, ca.vertcat(model.u, model.t), ca.vertcat(u_of_t, tk + tau))
    dae = {"x": model.x, "p": ca.vertcat(model.p, u0, slope, tk), "t": tau, "ode": ode}
    opts = {"reltol": rtol, "abstol": atol, "max_num_steps": 100000}
    n = len(t) - 1
    xs = np.zeros(model.x.numel()) if x0 is None else np.asarray(x0, float)
    if not np.any(U):
        # no sampled input: one integration over the whole grid (the excitation is a function of time)
        whole = ca.integrator("whole", "cvodes", dae, 0.0, t[1:] - t[0], opts)
        P = np.concatenate([p, np.zeros(2 * model.u.numel()), [t[0]]])
        X = np.hstack([xs[:, None], np.array(whole(x0=xs, p=P)["xf"])])
    else:
        step = ca.integrator("step", "cvodes", dae, 0.0, h, opts)
        P = np.vstack([np.repeat(p[:, None], n, 1), U[:, :-1], np.diff(U, axis=1) / h, t[None, :-1]])
        run = step.mapaccum("run", n, ["x0"], ["xf"])
        X = np.hstack([xs[:, None], np.array(run(x0=xs, p=P)["xf"])])
    U_total = U + np.array(ca.Function("ue", [model.t], [_input_expr(model, excitation, model.t)]).map(len(t))(t[None, :]))
    return _outputs(model, X, U_total, p, t)


def simulate_newmark(model: ReferenceModel, t: np.ndarray, params: dict | None = None,
                     excitation: Excitation | None = None, inputs: dict | None = None,
                     a: float = 0.5, b: float = 0.25, c: float = 0.5, x0: np.ndarray | None = None) -> dict:
    """The thesis's Newmark scheme on the uniform grid t (its step is the grid spacing)."""
    h = _check_grid(t)
    t = np.asarray(t, float)
    nq, nz = model.n_q, model.n_z
    p = model.param_vector(params)
    U = _sampled_inputs(model, inputs, len(t))
    f = model.function()
    # extended state [q, v, z, acc, zdot] at step n; unknowns w = [acc, z] at step n+1
    Xn = ca.SX.sym("Xn", 2 * nq + nz + nq + nz)
    q, v, z = Xn[:nq], Xn[nq:2 * nq], Xn[2 * nq:2 * nq + nz]
    acc, zd = Xn[2 * nq + nz:3 * nq + nz], Xn[3 * nq + nz:]
    w = ca.SX.sym("w", nq + nz)
    a1, z1 = w[:nq], w[nq:]
    u1, t1 = ca.SX.sym("u1", model.u.numel()), ca.SX.sym("t1")
    pp = ca.SX.sym("p", p.size)
    q1 = q + h * v + h**2 * ((0.5 - b) * acc + b * a1)
    v1 = v + h * ((1 - a) * acc + a * a1)
    u_tot = u1 + _input_expr(model, excitation, t1)
    rate = f(ca.vertcat(q1, v1, z1), u_tot, pp, t1)
    acc1, zd1 = rate[nq:2 * nq], rate[2 * nq:]
    residual = ca.vertcat(acc1 - a1, z1 - z - h * ((1 - c) * zd + c * zd1))
    newton = ca.rootfinder("newton", "newton", ca.Function("R", [w, ca.vertcat(Xn, u1, t1, pp)], [residual]),
                           {"abstol": 1e-10, "max_iter": 50})
    guess = ca.vertcat(acc, z + h * zd)  # predictor
    w1 = newton(guess, ca.vertcat(Xn, u1, t1, pp))
    a1s, z1s = w1[:nq], w1[nq:]
    q1s = q + h * v + h**2 * ((0.5 - b) * acc + b * a1s)
    v1s = v + h * ((1 - a) * acc + a * a1s)
    zd1s = f(ca.vertcat(q1s, v1s, z1s), u_tot, pp, t1)[2 * nq:]
    step = ca.Function("step", [Xn, u1, t1, pp], [ca.vertcat(q1s, v1s, z1s, a1s, zd1s)])
    xs = np.zeros(model.x.numel()) if x0 is None else np.asarray(x0, float)
    u0 = U[:, 0] + np.array(ca.Function("ue", [model.t], [_input_expr(model, excitation, model.t)])(t[0])).ravel()
    r0 = np.array(f(xs, u0, p, t[0])).ravel()
    X0 = np.concatenate([xs, r0[nq:2 * nq], r0[2 * nq:]])
    n = len(t) - 1
    run = step.mapaccum("run", n)
    Xall = np.array(run(X0, U[:, 1:], t[None, 1:], np.repeat(p[:, None], n, 1)))
    X = np.hstack([xs[:, None], Xall[:2 * nq + nz]])
    U_total = U + np.array(ca.Function("ue", [model.t], [_input_expr(model, excitation, model.t)]).map(len(t))(t[None, :]))
    return _outputs(model, X, U_total, p, t)
