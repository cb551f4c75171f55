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

A number is in SI units; a value in another unit is a string with its unit (`L1 = "150 mm"`,
`J_G1 = "2000 kg.mm2"`, `EI = { start = "12 N·m²" }`: pyfit.io.units), converted to SI here and checked against
the unit the FMU declares (`NominalModel.check_against`). A damper's geometry outside what a Stockbridge damper
can have (PLAUSIBLE) is refused: such a number is most often millimetres or grams written as SI.
"""
from __future__ import annotations

import pathlib
from dataclasses import dataclass, field

from pyfit.io.schema import ConfigError, check_sections, check_table, fail, read_toml
from pyfit.io.units import Unit, parse_quantity, parse_unit

FAMILIES = ("sdof", "damper")
# What a Stockbridge damper's geometry can be [SI]: a decade or more beyond the catalogue ranges each way (masses
# 0.5-4 kg, arms 0.1-0.3 m, offsets 0-50 mm, radii of gyration 30-60 mm, messenger EI 5-60 N·m²); a slip of
# units (mm as m: x1000; g as kg; kg·mm² as kg·m²: x1e6) lands outside
PLAUSIBLE = {"damper": {**{f"m{i}": (0.05, 40.0, "kg") for i in (1, 2)}, "m_c": (0.01, 40.0, "kg"),
                        **{f"L{i}": (0.01, 3.0, "m") for i in (1, 2)}, **{f"a{i}": (-0.5, 0.5, "m") for i in (1, 2)},
                        **{f"J_G{i}": (1e-7, 10.0, "kg.m2") for i in (1, 2)}, "J_GC": (1e-7, 10.0, "kg.m2"),
                        "EI": (0.05, 6000.0, "N.m2"), "mu": (0.003, 30.0, "kg/m")}}
RADIUS_OF_GYRATION = (0.003, 0.5)  # sqrt(J_Gi / mi) of a damper's mass [m] (catalogue 30-60 mm)


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
    units: dict[str, tuple[str, Unit]] = field(default_factory=dict)  # parameter -> (key, unit) where written
    # with a unit (the values above are SI all the same)

    def parameters(self) -> dict[str, float]:
        """FMU parameter values of the described system: the known ones and the starts of the uncertain ones."""
        return {**self.fixed, **{n: p.start for n, p in self.free.items() if p.start is not None}}

    def check_against(self, parameters: dict) -> None:
        """Every named parameter must be one of the FMU's (`parameters`: name -> fmpy ScalarVariable), a value
        written with a unit must have the dimension of the unit the FMU declares (in coherent SI), and every value
        must lie within the FMU's declared min and max."""
        where = self.path or "nominal"
        values = [("fixed", n, v) for n, v in self.fixed.items()] + [
            ("free", n, v) for n, p in self.free.items() for v in (p.start, p.lower, p.upper) if v is not None]
        for section, name, value in values:
            var = parameters.get(name)
            if var is None:
                fail(where, f"nominal.{section}.{name}", "not a parameter of the model", ", ".join(sorted(parameters)))
            if name in self.units:
                _check_dimension(where, *self.units[name], name, var.unit)
            lo, hi = (float(b) if b is not None else None for b in (var.min, var.max))
            if (lo is not None and value < lo) or (hi is not None and value > hi):
                span = f"{lo if lo is not None else '-inf'} to {hi if hi is not None else 'inf'} {var.unit or ''}"
                fail(where, f"nominal.{section}.{name}", f"{value:g} is outside the model's range", span.rstrip())


def load_nominal(path) -> NominalModel:
    """A NominalModel from a TOML file; one error naming file, key and what is allowed."""
    path = pathlib.Path(path)
    doc = read_toml(path, ConfigError)
    check_sections(doc, path, ("nominal",), ("nominal",))
    nom = check_table(doc["nominal"], path, "nominal", {"family": (str, True, None), "fixed": (dict, False, {}),
                                                         "free": (dict, False, {})})
    if nom["family"] not in FAMILIES:
        fail(path, "nominal.family", f"unknown family '{nom['family']}'", ", ".join(FAMILIES))
    if not isinstance(nom["fixed"], dict):
        fail(path, "nominal.fixed", f"must be a table of name = value, not {nom['fixed']!r}")
    units = {}  # parameter -> (key, Unit) of its first value written with a unit
    fixed = {n: _in_si(path, v, f"nominal.fixed.{n}", n, units) for n, v in nom["fixed"].items()}
    free = {}
    for name, spec in nom["free"].items():
        s = check_table(spec, path, f"nominal.free.{name}", {"start": (None, False, None), "lower": (None, False, None),
                                                              "upper": (None, False, None)})
        s = {k: _in_si(path, v, f"nominal.free.{name}.{k}", name, units) for k, v in s.items()}
        if (s["lower"] is None) != (s["upper"] is None):
            fail(path, f"nominal.free.{name}", "give both lower and upper, or neither")
        if s["lower"] is not None and not s["lower"] < s["upper"]:
            fail(path, f"nominal.free.{name}", f"lower {s['lower']} is not below upper {s['upper']}")
        if s["start"] is not None and s["lower"] is not None and not s["lower"] <= s["start"] <= s["upper"]:
            fail(path, f"nominal.free.{name}.start", f"{s['start']} outside [{s['lower']}, {s['upper']}]")
        if name in fixed:
            fail(path, f"nominal.free.{name}", "is also in [nominal.fixed]; a parameter is known or uncertain")
        free[name] = FreeParameter(s["start"], s["lower"], s["upper"])
    _check_plausible(path, nom["family"], fixed, free, units)
    return NominalModel(nom["family"], fixed, free, path, units)


def _in_si(path, value, key: str, name: str, units: dict) -> float | None:
    """A number (SI) or a string 'NUMBER UNIT' as SI; the unit is noted in `units` (name -> (key, Unit)), where
    every value of one parameter must have the same dimension."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        fail(path, key, f"must be a number (SI) or a string 'NUMBER UNIT', not {value!r}")
    if not isinstance(value, str):
        return float(value)
    try:
        number, unit = parse_quantity(value)
    except ValueError as exc:
        fail(path, key, f"'{value}': {exc}", 'a number in SI units, or a string such as "150 mm", "1.2 kg", '
             '"2000 kg.mm2", "12 N·m²"')
    if unit is not None:
        if name in units and units[name][1].dimension != unit.dimension:
            fail(path, key, f"'{unit.text}' is {unit.describe()}, but {units[name][0]} is in '{units[name][1].text}'")
        units.setdefault(name, (key, unit))
    return number


def _check_dimension(path, key: str, unit: Unit, name: str, declared: str | None) -> None:
    """A value written in `unit` for parameter `name` declared in `declared` (coherent SI, or None: no unit)."""
    model = parse_unit(declared) if declared else None
    if model is None or model.factor != 1.0 or model.dimension != unit.dimension:
        allowed = (f"a number in {declared} or a value in a unit of {model.describe()}" if model and model.factor == 1.0
                   else "a number (the model declares no SI unit)")
        fail(path, key, f"'{unit.text}' is {unit.describe()}, but {name} is in {declared or 'no declared unit'}",
             allowed)


def _check_plausible(path, family: str, fixed: dict, free: dict, units: dict) -> None:
    """Refuse a described value (known, or an uncertain one's start) outside what the family's device can have."""
    given = {**{n: (f"nominal.fixed.{n}", v) for n, v in fixed.items()},
             **{n: (f"nominal.free.{n}.start", p.start) for n, p in free.items() if p.start is not None}}
    hint = "the file's numbers are SI (kg, m, kg·m², N·m²); write another unit with the number, e.g. \"150 mm\""
    for name, (lo, hi, si_unit) in PLAUSIBLE.get(family, {}).items():
        if name in units:
            _check_dimension(path, *units[name], name, si_unit)
        if name in given and not lo <= given[name][1] <= hi:
            key, value = given[name]
            fail(path, key, f"{value:g} {si_unit} is not what a Stockbridge damper has ({lo:g} to {hi:g} {si_unit}); "
                 f"{hint}")
    for i in (1, 2):
        if family == "damper" and f"J_G{i}" in given and f"m{i}" in given:
            r = (given[f"J_G{i}"][1] / given[f"m{i}"][1]) ** 0.5
            if not RADIUS_OF_GYRATION[0] <= r <= RADIUS_OF_GYRATION[1]:
                fail(path, given[f"J_G{i}"][0], f"J_G{i} / m{i} gives a radius of gyration of "
                     f"{1e3 * r:.3g} mm, not a damper mass's ({1e3 * RADIUS_OF_GYRATION[0]:g} to "
                     f"{1e3 * RADIUS_OF_GYRATION[1]:g} mm); {hint}")
