"""The textbook alternatives to the gap diagnosis, equation-error methods, run on the same SDOF measurement
files: the restoring-force surface (Masri-Caughey, here as direct parameter estimation: the force balance
regressed on the motion and a library of terms), sparse regression of the dynamics over the same library
(SINDy, pysindy) and NARMAX term selection by the error-reduction ratio (FROLS, sysidentpy).

The shared library of candidate terms and the effects they stand for (`LIBRARY`): y³ (cubic stiffness),
tanh(v/v_s) (Coulomb friction, v_s = 1 % of the velocity RMS), v·|v| (quadratic damping). None of them holds a
hysteretic state (a Bouc-Wen force has memory: no function of the present y and v is one), so these methods
cannot name hysteresis; a sensor delay is not a term of any of them either. A polynomial NARX model (sysidentpy's
Polynomial basis) has the cubic terms only.

Units: force u [N], displacement y [m], velocity v [m/s], acceleration a [m/s²]; fs [Hz].
"""
from __future__ import annotations

import pathlib
import time
from dataclasses import dataclass

import numpy as np

from pyfit.analysis import kinematics
from pyfit.gap import simulate as sim
from pyfit.io.data import read_measurement

LIBRARY = {"y^3": "cubic_stiffness", "tanh(v/v_s)": "coulomb_friction", "v|v|": "quadratic_damping"}
SIGNIFICANT = 0.01  # a term is named when it removes at least this share of the linear model's residual


@dataclass
class Motion:
    """Force and complete motion of one file (SI), the derived ones band-limited to (f_lo, 0.4 fs)."""

    u: np.ndarray
    y: np.ndarray
    v: np.ndarray
    a: np.ndarray
    fs: float


@dataclass
class Named:
    """One method's verdict on one dataset: the effect named (None: no significant nonlinearity), the share
    of the linear model's residual each library term removes, and the wall time."""

    method: str
    effect: str | None
    shares: dict
    wall_s: float
    note: str = ""


def read_motions(folder: pathlib.Path) -> list[Motion]:
    """Every measurement file of an SDOF dataset folder as force and motion (displacement y or acceleration a
    recorded; the rest derived, pyfit.analysis.kinematics)."""
    out = []
    for csv in sorted(pathlib.Path(folder).glob("*.csv")):
        rec = sim.record_of(read_measurement(csv))
        u = rec.inputs["u"][rec.first:]
        recorded = {k: rec.outputs[name] for k, name in (("x", "y"), ("a", "a")) if name in rec.outputs}
        if not recorded:
            raise ValueError(f"{csv}: the equation-error methods need y or a recorded; found "
                             f"{', '.join(rec.outputs)}")
        band = (kinematics.excited_band(u, rec.fs)[0], 0.4 * rec.fs)  # keep the harmonics above the excitation
        full = kinematics.complete(recorded, rec.fs, band, periodic=rec.periodic)
        out.append(Motion(u, full["x"], full["v"], full["a"], rec.fs))
    return out


def _terms(m: Motion, v_s: float) -> dict[str, np.ndarray]:
    return {"y^3": m.y ** 3, "tanh(v/v_s)": np.tanh(m.v / v_s), "v|v|": m.v * np.abs(m.v)}


def _velocity_scale(motions: list[Motion]) -> float:
    return 0.01 * float(np.sqrt(np.mean(np.concatenate([m.v for m in motions]) ** 2)))


def _verdict(method: str, shares: dict, t0: float, note: str = "") -> Named:
    best = max(shares, key=shares.get) if shares else None
    effect = LIBRARY[best] if best and shares[best] >= SIGNIFICANT else None
    return Named(method, effect, shares, time.perf_counter() - t0, note)


def _unexplained(A: np.ndarray, b: np.ndarray) -> float:
    scale = np.sqrt(np.mean(A ** 2, axis=0))
    coef = np.linalg.lstsq(A / scale, b, rcond=None)[0]
    return float(np.sum((b - (A / scale) @ coef) ** 2))


def restoring_force(motions: list[Motion]) -> Named:
    """The force balance u = m a + c v + k y + Σ θ_j φ_j(y, v) by least squares over every file; each library
    term's share: how much of the linear model's residual it removes when added alone."""
    t0 = time.perf_counter()
    v_s = _velocity_scale(motions)
    b = np.concatenate([m.u for m in motions])
    linear = np.column_stack([np.concatenate([getattr(m, k) for m in motions]) for k in ("a", "v", "y")])
    base = _unexplained(linear, b)
    shares = {}
    for name in LIBRARY:
        phi = np.concatenate([_terms(m, v_s)[name] for m in motions])
        shares[name] = 1.0 - _unexplained(np.column_stack([linear, phi]), b) / base
    return _verdict("restoring-force surface", shares, t0)


def sindy(motions: list[Motion], threshold: float = 0.05) -> Named:
    """pysindy: ẋ = Θ(x, u) ξ for x = (y, v) with the library (y, v, u and the candidate terms), sequentially
    thresholded least squares on normalised columns, the measured/derived v and a as ẋ; each candidate term
    kept in the v equation has the share of the linear model's residual it removes."""
    import pysindy as ps

    t0 = time.perf_counter()
    v_s = _velocity_scale(motions)
    names = ["y", "v", "u", *LIBRARY]
    funcs = [lambda y, v, u: y, lambda y, v, u: v, lambda y, v, u: u, lambda y, v, u: y ** 3,
             lambda y, v, u: np.tanh(v / v_s), lambda y, v, u: v * np.abs(v)]
    library = ps.CustomLibrary(library_functions=funcs, function_names=[lambda *a, n=n: n for n in names])
    model = ps.SINDy(optimizer=ps.STLSQ(threshold=threshold, normalize_columns=True), feature_library=library)
    xs = [np.column_stack([m.y, m.v]) for m in motions]
    model.fit(xs, t=1.0 / motions[0].fs, x_dot=[np.column_stack([m.v, m.a]) for m in motions],
              u=[m.u[:, None] for m in motions])
    coef = model.coefficients()[1]  # the v equation
    theta = np.concatenate([np.column_stack([f(m.y, m.v, m.u) for f in funcs]) for m in motions])
    a = np.concatenate([m.a for m in motions])
    linear = theta[:, :3] @ coef[:3]
    base = float(np.sum((a - linear) ** 2))
    shares = {}
    for j, name in enumerate(LIBRARY, start=3):
        if coef[j] != 0.0:
            shares[name] = 1.0 - float(np.sum((a - linear - theta[:, j] * coef[j]) ** 2)) / base
    return _verdict("SINDy (pysindy)", shares, t0)


def narmax(motions: list[Motion], lags: int = 2) -> Named:
    """sysidentpy FROLS: a polynomial NARX model of degree 3 (lags of y and u up to `lags`), terms chosen by
    the error-reduction ratio and the number of terms by AIC, on the file of the highest force level; the
    chosen terms that are products of three output lags stand for cubic stiffness, their ERR over what the
    chosen linear terms leave as share.
    The polynomial basis holds no friction or |v|v term."""
    from sysidentpy.basis_function import Polynomial
    from sysidentpy.model_structure_selection import FROLS
    from sysidentpy.parameter_estimation import LeastSquares

    t0 = time.perf_counter()
    m = max(motions, key=lambda q: np.std(q.u))
    scale_y, scale_u = np.std(m.y), np.std(m.u)
    model = FROLS(order_selection=True, n_info_values=12, ylag=lags, xlag=lags, info_criteria="aic",
                  estimator=LeastSquares(), basis_function=Polynomial(degree=3))
    model.fit(X=(m.u / scale_u)[:, None], y=(m.y / scale_y)[:, None])
    chosen = list(zip(model.final_model, model.err))
    linear = sum(float(e) for code, e in chosen if np.count_nonzero(code) == 1)
    cubic = [float(e) for code, e in chosen if np.count_nonzero(code) == 3 and all(1000 <= c < 2000 for c in code)]
    # ERR is a share of the output's variance: as a share of what the linear terms leave
    shares = {"y^3": sum(cubic) / max(1.0 - linear, 1e-12)} if cubic else {}
    return _verdict("NARMAX (sysidentpy FROLS)", shares, t0,
                    note="polynomial basis: no friction or v|v| term")


METHODS = {"restoring-force surface": restoring_force, "SINDy (pysindy)": sindy,
           "NARMAX (sysidentpy FROLS)": narmax}
