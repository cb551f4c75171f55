"""The systems a diagnosis knows: FMU, nominal (linear) free parameters with their start and bounds, and
the candidate effects of design section 6.

Effect bounds and start values follow from the data scale: sigma_y = RMS of the measured deflection of the
nonlinear element (SDOF: y; damper: cable end relative to the clamp), sigma_v = RMS of its velocity, and
the nominal stiffness k of that element (SI units throughout).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Scale:
    """Data scale for bounds: element deflection RMS [m], its velocity RMS [m/s], nominal stiffness [N/m]."""

    sigma_y: float
    sigma_v: float
    k: float


@dataclass(frozen=True)
class Param:
    """A fitted parameter: name in the FMU and a function of the Scale giving (lower, start, upper)."""

    name: str
    range: callable


@dataclass(frozen=True)
class Effect:
    """A candidate unmodelled effect: its free parameters, the fixed values that switch it on, and the
    signature it leaves (used as evidence in the report)."""

    name: str
    params: tuple[Param, ...]
    fixed: callable = field(default=lambda s: {})
    signature: str = ""
    shift_stiffness: float = 0.0  # the effect's start adds this fraction of the stiffness, taken off the nominal


@dataclass(frozen=True)
class System:
    """A model family for the diagnosis."""

    name: str
    fmu: str
    nominal_fixed: dict  # switches that make the FMU the nominal model
    linear: tuple  # the nominal model's free parameters
    stiffness: str  # the one of them that a hysteretic element's tangent stiffness replaces in part
    start: callable  # records -> start values of `linear`
    bounds: callable  # (start, softened) -> bounds of `linear`
    scale: callable  # (records, nominal params) -> Scale
    effects: dict
    lead_periods: int = 1  # periods simulated before a periodic record (the decay of the slowest mode)


def _sym(scale_fn):
    return lambda s: (-scale_fn(s), 0.0, scale_fn(s))


def _first(rec, kind):
    return next(iter(getattr(rec, kind).values()))


# ---- SDOF --------------------------------------------------------------------------------------------------
def sdof_start(records) -> dict:
    """m, c, k of a linear SDOF from the measured FRF (input -> output DFT lines the input excites):
    1/H = k - w^2 m + i w c, solved by least squares weighted by |H| (relative error)."""
    rows, rhs = [], []
    for rec in records:
        u, y = _first(rec, "inputs"), _first(rec, "outputs")
        U, Y = np.fft.rfft(u), np.fft.rfft(y)
        w = 2 * np.pi * np.fft.rfftfreq(len(u), 1.0 / rec.fs)
        ex = (np.abs(U) > 1e-3 * np.abs(U).max()) & (w > 0)
        G = U[ex] / Y[ex]  # 1/H
        wt = 1.0 / np.abs(G)
        rows += [np.column_stack([-w[ex] ** 2 * wt, 0 * wt, wt]), np.column_stack([0 * wt, w[ex] * wt, 0 * wt])]
        rhs += [G.real * wt, G.imag * wt]
    m, c, k = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    return {"m": float(abs(m)), "c": float(abs(c)), "k": float(abs(k))}


def sdof_bounds(start: dict, softened: bool = False) -> dict:
    """Bounds of m, c, k around a linear estimate (k lower when a hysteretic element shares the stiffness)."""
    return {"m": (0.5 * start["m"], 2.0 * start["m"]), "c": (0.1 * start["c"], 5.0 * start["c"]),
            "k": ((0.05 if softened else 0.5) * start["k"], 2.0 * start["k"])}


def sdof_scale(records, params) -> Scale:
    """RMS of the measured displacement and of its velocity; k of the nominal fit."""
    y = np.concatenate([_first(r, "outputs") for r in records])
    v = np.concatenate([np.gradient(_first(r, "outputs")) * r.fs for r in records])
    return Scale(float(np.sqrt(np.mean(y**2))), float(np.sqrt(np.mean(v**2))), params["k"])


SDOF_EFFECTS = {
    "hysteresis": Effect(
        "hysteresis",
        (Param("alpha", lambda s: (0.0, 0.1 * s.k, 2.0 * s.k)),
         Param("gamma", lambda s: (-5.0, 0.8, 5.0)),
         Param("delta", lambda s: (-5.0, -1.1, 5.0))),
        fixed=lambda s: {"beta": 1.0 / s.sigma_y, "nu": 1.0},
        signature="amplitude-dependent stiffness and damping (softening loops), odd distortion",
        shift_stiffness=0.1),
    "cubic_stiffness": Effect(
        "cubic_stiffness", (Param("k3", _sym(lambda s: 0.3 * s.k / s.sigma_y**2)),),
        signature="resonance shift with amplitude squared, odd distortion"),
    "coulomb_friction": Effect(
        "coulomb_friction", (Param("F_c", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y)),),
        fixed=lambda s: {"v_s": 1e-3 * s.sigma_v},
        signature="damping that falls with amplitude (largest misfit at the lowest level)"),
    "quadratic_damping": Effect(
        "quadratic_damping", (Param("c2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y / s.sigma_v**2)),),
        signature="damping that grows with amplitude (largest misfit at the highest level)"),
}

# ---- Stockbridge damper ------------------------------------------------------------------------------------
DAMPER_DESIGN = {"EI": 10.0, "alpha_pd": 2.0, "beta_pd": 2e-4}  # design 1.3 values: the nominal's start
DAMPER_L1 = 0.17  # m, cable length clamp - mass 1


def damper_bounds(start: dict, softened: bool = False) -> dict:
    """Bounds of EI, alpha_pd, beta_pd around their start."""
    return {"EI": ((0.1 if softened else 0.3) * start["EI"], 3.0 * start["EI"]),
            "alpha_pd": (0.1 * start["alpha_pd"], 10.0 * start["alpha_pd"]),
            "beta_pd": (0.1 * start["beta_pd"], 10.0 * start["beta_pd"])}


def damper_scale(records, params) -> Scale:
    """RMS of the cable-end deflection relative to the clamp (x1 - x_base) and of its velocity; k = 3 EI/L1^3,
    the tip stiffness of arm 1."""
    r = np.concatenate([rec.outputs["x1"] - rec.inputs["x_base"] for rec in records])
    v = np.concatenate([np.gradient(rec.outputs["x1"] - rec.inputs["x_base"]) * rec.fs for rec in records])
    return Scale(float(np.sqrt(np.mean(r**2))), float(np.sqrt(np.mean(v**2))), 3 * params["EI"] / DAMPER_L1**3)


def _pair(name1, name2, rng):
    return (Param(name1, rng), Param(name2, rng))


DAMPER_EFFECTS = {
    "hysteresis": Effect(
        "hysteresis", _pair("k_bw1", "k_bw2", lambda s: (0.0, 0.05 * s.k, 0.5 * s.k))
        + (Param("D", lambda s: (0.1 * s.sigma_y, s.sigma_y, 10 * s.sigma_y)),),
        fixed=lambda s: {"a_bw": 0.3, "A": 1.0, "beta": 0.6, "gamma": 0.4, "nu": 1.0},
        signature="amplitude-dependent stiffness and damping of the cable (softening loops), odd distortion"),
    "cubic_stiffness": Effect(
        "cubic_stiffness", _pair("k_cs1", "k_cs2", _sym(lambda s: 0.3 * s.k / s.sigma_y**2)),
        signature="resonance shifts with amplitude squared, odd distortion"),
    "coulomb_friction": Effect(
        "coulomb_friction", _pair("F_c1", "F_c2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y)),
        fixed=lambda s: {"v_s": 1e-3 * s.sigma_v},
        signature="damping that falls with amplitude (largest misfit at the lowest level)"),
    "quadratic_damping": Effect(
        "quadratic_damping", _pair("c2_1", "c2_2", lambda s: (0.0, 0.0, 0.5 * s.k * s.sigma_y / s.sigma_v**2)),
        signature="damping that grows with amplitude (largest misfit at the highest level)"),
    "mass_eccentricity": Effect(
        "mass_eccentricity", _pair("a1", "a2", lambda s: (-0.06, 0.0, 0.06)),
        signature="amplitude-independent shift of the modes (the same misfit at every level)"),
}

SYSTEMS = {
    "sdof": System("sdof", "SDOFBoucWen", {"exc_type": 0, "alpha": 0.0, "k3": 0.0, "F_c": 0.0, "c2": 0.0},
                   ("m", "c", "k"), "k", sdof_start, sdof_bounds, sdof_scale, SDOF_EFFECTS),
    "damper": System("damper", "StockbridgeDamper",
                     {"exc_type": 0, "k_bw1": 0.0, "k_bw2": 0.0, "k_cs1": 0.0, "k_cs2": 0.0, "F_c1": 0.0,
                      "F_c2": 0.0, "c2_1": 0.0, "c2_2": 0.0, "a1": 0.0, "a2": 0.0},
                     ("EI", "alpha_pd", "beta_pd"), "EI", lambda records: dict(DAMPER_DESIGN), damper_bounds,
                     damper_scale, DAMPER_EFFECTS, lead_periods=2),
}


def get_system(name: str) -> System:
    """The System called name; a clear error listing the known ones otherwise."""
    if name not in SYSTEMS:
        raise ValueError(f"--model '{name}' unknown; allowed: {', '.join(SYSTEMS)}")
    return SYSTEMS[name]
