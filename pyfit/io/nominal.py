"""The nominal model a user describes: which model family, the FMU parameters known from drawings (masses,
inertias, arm lengths, mass offsets, clamp mass: theory §1 names, SI units), and the uncertain ones
with their start values and bounds (EI, Rayleigh coefficients, ...). A TOML file:

    [nominal]
    family = "damper"                      # sdof | damper
    [nominal.fixed]                        # known: overrides of the FMU's defaults (SI)
    m1 = 1.0
    m2 = 1.0
    L1 = 0.15
    L2 = 0.15
    [nominal.free]                         # uncertain: start (optional: then the FMU default or the data) and bounds
    EI = { start = 10.0, lower = 3.0, upper = 30.0 }

A parameter left out keeps the FMU's default (for the damper: the theory §1.3 reference damper,
eccentric masses included). `free` without `start` starts from the data (SDOF: the measured FRF) or the
FMU default.
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

from pyfit.io.schema import ConfigError, check_numbers, check_sections, check_table, fail, read_toml

FAMILIES = ("sdof", "damper")


@dataclass(frozen=True)
class FreeParameter:
    """An uncertain nominal parameter: start (None: from the data or the FMU default) and bounds, SI."""

    start: float | None
    lower: float | None
    upper: float | None


@dataclass(frozen=True)
class NominalModel:
    """A family, the known parameters, the uncertain ones (empty `free`: the family's defaults)."""

    family: str
    fixed: dict[str, float] = field(default_factory=dict)
    free: dict[str, FreeParameter] = field(default_factory=dict)
    path: pathlib.Path | None = None

    def parameters(self) -> dict[str, float]:
        """FMU parameter values of the described system: the known ones and the starts of the uncertain ones."""
        return {**self.fixed, **{n: p.start for n, p in self.free.items() if p.start is not None}}

    def check_names(self, settable: set[str]) -> None:
        """Every named parameter must be one the FMU accepts."""
        for section, names in (("fixed", self.fixed), ("free", self.free)):
            for name in names:
                if name not in settable:
                    fail(self.path or "nominal", f"nominal.{section}.{name}", "not a parameter of the model",
                         ", ".join(sorted(settable)))


def load_nominal(path) -> NominalModel:
    """A NominalModel from a TOML file; one error naming file, key and what is allowed."""
    path = pathlib.Path(path)
    doc = read_toml(path, ConfigError)
    check_sections(doc, path, ("nominal",), ("nominal",))
    nom = check_table(doc["nominal"], path, "nominal", {"family": (str, True, None), "fixed": (dict, False, {}),
                                                         "free": (dict, False, {})})
    if nom["family"] not in FAMILIES:
        fail(path, "nominal.family", f"unknown family '{nom['family']}'", ", ".join(FAMILIES))
    fixed = check_numbers(nom["fixed"], path, "nominal.fixed")
    free = {}
    for name, spec in nom["free"].items():
        s = check_table(spec, path, f"nominal.free.{name}", {"start": ("number", False, None),
                                                              "lower": ("number", False, None),
                                                              "upper": ("number", False, None)})
        if (s["lower"] is None) != (s["upper"] is None):
            fail(path, f"nominal.free.{name}", "give both lower and upper, or neither")
        if s["lower"] is not None and not s["lower"] < s["upper"]:
            fail(path, f"nominal.free.{name}", f"lower {s['lower']} is not below upper {s['upper']}")
        if s["start"] is not None and s["lower"] is not None and not s["lower"] <= s["start"] <= s["upper"]:
            fail(path, f"nominal.free.{name}.start", f"{s['start']} outside [{s['lower']}, {s['upper']}]")
        if name in fixed:
            fail(path, f"nominal.free.{name}", "is also in [nominal.fixed]; a parameter is known or uncertain")
        free[name] = FreeParameter(s["start"], s["lower"], s["upper"])
    return NominalModel(nom["family"], fixed, free, path)
