"""Unit strings as a factor to coherent SI and a dimension: the Modelica unit grammar the FMUs declare
('N.m2', 'kg.m2', 'N.s2/m2', '1/s') and the forms people write in a file ('N·m²', 'kg*mm^2', 'N s^2/m^2',
'g.cm2', 'lbf', 'in', and the newton run into the next symbol as catalogues do: 'Nm2', 'Ns/m').

A unit is a product of factors, each a symbol with an optional SI prefix and an optional integer exponent,
then optionally '/' and the factors it divides by (in brackets, or one factor per '/'). A dimension is the
exponents of (kg, m, s, A); the radian counts as dimensionless, as SI defines it. 'g' is the gram here (a
nominal parameter is never an acceleration; measurement files read 'g' as standard gravity:
pyfit.io.data.TO_SI).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

Dimension = tuple[int, int, int, int]  # exponents of kg, m, s, A
SI_BASE = ("kg", "m", "s", "A")

G0 = 9.80665  # standard gravity [m/s2], exact by definition
INCH, FOOT, POUND = 0.0254, 0.3048, 0.45359237  # [m], [m], [kg]: exact by the 1959 international agreement
_M, _L, _T, _I = (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, 0, 0, 1)
_NONE: Dimension = (0, 0, 0, 0)


def _times(*parts: tuple[Dimension, int]) -> Dimension:
    return tuple(sum(d[i] * n for d, n in parts) for i in range(4))


_FORCE = _times((_M, 1), (_L, 1), (_T, -2))
PREFIXED = {  # symbol -> (factor to coherent SI, dimension); these take an SI prefix
    "m": (1.0, _L), "g": (1e-3, _M), "s": (1.0, _T), "A": (1.0, _I), "N": (1.0, _FORCE), "Hz": (1.0, _times((_T, -1))),
    "Pa": (1.0, _times((_FORCE, 1), (_L, -2))), "J": (1.0, _times((_FORCE, 1), (_L, 1))),
    "W": (1.0, _times((_FORCE, 1), (_L, 1), (_T, -1))), "V": (1.0, _times((_M, 1), (_L, 2), (_T, -3), (_I, -1))),
    "rad": (1.0, _NONE)}
UNPREFIXED = {  # symbols that take no prefix
    "1": (1.0, _NONE), "min": (60.0, _T), "h": (3600.0, _T), "deg": (math.pi / 180, _NONE),
    "in": (INCH, _L), "ft": (FOOT, _L), "lb": (POUND, _M), "lbf": (POUND * G0, _FORCE)}
PREFIXES = {"da": 1e1, "Y": 1e24, "Z": 1e21, "E": 1e18, "P": 1e15, "T": 1e12, "G": 1e9, "M": 1e6, "k": 1e3,
            "h": 1e2, "d": 1e-1, "c": 1e-2, "m": 1e-3, "u": 1e-6, "n": 1e-9, "p": 1e-12, "f": 1e-15, "a": 1e-18,
            "z": 1e-21, "y": 1e-24}
DIMENSION_NAMES = {_L: "a length", _M: "a mass", _T: "a time", _FORCE: "a force", _NONE: "dimensionless"}
_FACTOR = re.compile(r"^([A-Za-z]+|1)(-?\d+)?$")
_WRITTEN = (("²", "2"), ("³", "3"), ("⁴", "4"), ("⁻", "-"), ("¹", "1"), ("µ", "u"), ("μ", "u"), ("·", "."),
            ("⋅", "."))  # as people write a unit -> the Modelica grammar (then '^' and '**' before an exponent go)


@dataclass(frozen=True)
class Unit:
    """A parsed unit: its text, the factor that takes a value in it to coherent SI, and its dimension."""

    text: str
    factor: float
    dimension: Dimension

    def describe(self) -> str:
        """Its dimension as coherent SI in the Modelica grammar, with a name where it has a common one:
        'a length (m)', 'kg.m2', 'N.s2/m2' (as kg/m)."""
        up = ".".join(f"{s}{n if n != 1 else ''}" for s, n in zip(SI_BASE, self.dimension) if n > 0) or "1"
        down = ".".join(f"{s}{-n if n != -1 else ''}" for s, n in zip(SI_BASE, self.dimension) if n < 0)
        si = f"{up}/({down})" if "." in down else f"{up}/{down}" if down else up
        name = DIMENSION_NAMES.get(self.dimension)
        return f"{name} ({si})" if name else si


def _symbol(sym: str) -> tuple[float, Dimension]:
    if sym in UNPREFIXED:
        return UNPREFIXED[sym]
    if sym in PREFIXED:
        return PREFIXED[sym]
    for p in sorted(PREFIXES, key=len, reverse=True):
        if sym.startswith(p) and sym[len(p):] in PREFIXED:
            f, d = PREFIXED[sym[len(p):]]
            return PREFIXES[p] * f, d
    raise ValueError(f"unknown unit symbol '{sym}'")


def _product(text: str) -> tuple[float, Dimension]:
    if not text.strip("."):
        raise ValueError("a '/' with nothing on one side")
    factor, dim = 1.0, _NONE
    for part in filter(None, text.split(".")):
        m = _FACTOR.match(part)
        if not m:
            raise ValueError(f"'{part}' is not a unit symbol with an integer exponent")
        f, d = _symbol(m.group(1))
        n = int(m.group(2) or 1)
        factor, dim = factor * f ** n, _times((dim, 1), (d, n))
    return factor, dim


def parse_unit(text: str) -> Unit:
    """A unit string as a Unit; ValueError naming what does not parse."""
    s = text.strip().strip("[]").strip()
    for a, b in _WRITTEN:
        s = s.replace(a, b)
    s = re.sub(r"(\^|\*\*)(?=-?\d)", "", s).replace("*", ".")
    s = re.sub(r"N(?=[sm])", "N.", s)  # 'Ns/m', 'Nm', 'Nm2' as catalogues write N·s/m, N·m, N·m² (no prefix is 'N')
    s = re.sub(r"\s+", ".", s)
    if not s:
        raise ValueError("empty unit")
    head, *divisors = s.split("/")
    factor, dim = _product(head)
    for div in divisors:
        f, d = _product(div.strip("()"))
        factor, dim = factor / f, _times((dim, 1), (d, -1))
    return Unit(text.strip(), factor, dim)


NUMBER = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"  # a decimal number as a file writes it
QUANTITY = re.compile(rf"^\s*({NUMBER})\s*(.*?)\s*$")


def parse_quantity(text: str) -> tuple[float, Unit | None]:
    """'150 mm' -> (0.15, Unit('mm', ...)): the value in coherent SI and the unit it was written in (None for a
    bare number, taken as SI); ValueError naming what does not parse."""
    m = QUANTITY.match(text)
    if not m:
        raise ValueError("not a number followed by a unit")
    if not m.group(2):
        return float(m.group(1)), None
    unit = parse_unit(m.group(2))
    return float(m.group(1)) * unit.factor, unit
