"""The systems a diagnosis knows: FMU, nominal (linear) free parameters, and the candidate effects.

Parameter bounds and start values are set from the data scale: sigma_y = RMS of the measured output,
sigma_v = RMS of its velocity, and the nominal model's calibrated stiffness k (SI units throughout).
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Scale:
    """Data scale for bounds: output RMS [m], velocity RMS [m/s], nominal stiffness [N/m]."""

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
    shift_stiffness: float = 0.0  # the effect's start adds this fraction of k, taken off the linear k


@dataclass(frozen=True)
class System:
    """A model family for the diagnosis: FMU name, the switches that make it nominal, its effects."""

    name: str
    fmu: str
    nominal_fixed: dict
    effects: dict


def _sym(scale_fn):
    return lambda s: (-scale_fn(s), 0.0, scale_fn(s))


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

SYSTEMS = {
    "sdof": System("sdof", "SDOFBoucWen",
                   {"exc_type": 0, "alpha": 0.0, "k3": 0.0, "F_c": 0.0, "c2": 0.0}, SDOF_EFFECTS),
}
LINEAR_PARAMS = ("m", "c", "k")  # the nominal SDOF's free parameters


def get_system(name: str) -> System:
    """The System called name; a clear error listing the known ones otherwise."""
    if name not in SYSTEMS:
        raise ValueError(f"--model '{name}' unknown; allowed: {', '.join(SYSTEMS)}")
    return SYSTEMS[name]
