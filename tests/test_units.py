"""Unit strings (pyfit.io.units): the Modelica grammar the FMUs declare and the forms people write, against the
definitions written out (SI prefixes; 1 in = 25.4 mm, 1 lb = 0.45359237 kg, g0 = 9.80665 m/s², exact)."""
import math

import pytest
from fmpy import read_model_description
from hypothesis import given, settings
from hypothesis import strategies as st

from pyfit.io.units import PREFIXED, PREFIXES, parse_quantity, parse_unit

KG, M, S = (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0)


@pytest.mark.parametrize("text, factor, dimension", [
    ("N.m2", 1.0, (1, 3, -2, 0)),            # the FMUs' EI
    ("N·m²", 1.0, (1, 3, -2, 0)),
    ("N*mm^2", 1e-6, (1, 3, -2, 0)),
    ("kg.m2", 1.0, (1, 2, 0, 0)),
    ("g·cm²", 1e-3 * 1e-4, (1, 2, 0, 0)),
    ("kg mm**2", 1e-6, (1, 2, 0, 0)),
    ("N.s2/m2", 1.0, (1, -1, 0, 0)),         # the quadratic damping coefficient
    ("N s^2/m^2", 1.0, (1, -1, 0, 0)),
    ("N/m3", 1.0, (1, -2, -2, 0)),
    ("kN/mm", 1e6, (1, 0, -2, 0)),
    ("N / mm", 1e3, (1, 0, -2, 0)),
    ("kg/(m.s)", 1.0, (1, -1, -1, 0)),
    ("1/s", 1.0, (0, 0, -1, 0)),
    ("s⁻¹", 1.0, (0, 0, -1, 0)),
    ("1/min", 1 / 60, (0, 0, -1, 0)),
    ("µm", 1e-6, M),
    ("in", 0.0254, M),
    ("ft", 0.3048, M),
    ("lb", 0.45359237, KG),
    ("lbf", 0.45359237 * 9.80665, (1, 1, -2, 0)),
    ("daN", 10.0, (1, 1, -2, 0)),
    ("deg", math.pi / 180, (0, 0, 0, 0)),
    ("mV", 1e-3, (1, 2, -3, -1)),
    ("[mm]", 1e-3, M),
])
def test_units_read_to_their_definitions(text, factor, dimension):
    u = parse_unit(text)
    assert u.factor == pytest.approx(factor, rel=1e-14) and u.dimension == dimension


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(sorted(PREFIXES)), st.sampled_from(["m", "g", "s", "N"]), st.integers(-3, 3).filter(bool),
       st.sampled_from(["", "^", "**"]))
def test_a_prefixed_symbol_to_a_power_is_the_prefix_times_the_symbol_to_that_power(prefix, symbol, n, power):
    u = parse_unit(f"{prefix}{symbol}{power}{n}")
    base_factor, base_dim = PREFIXED[symbol]
    assert u.factor == pytest.approx((PREFIXES[prefix] * base_factor) ** n, rel=1e-12)
    assert u.dimension == tuple(n * d for d in base_dim)


def test_every_unit_the_fmus_declare_reads(fmu_dir):
    """The diagnosis checks a nominal file's units against the FMU's: every declared unit must parse, and all but
    the sweep rate's octaves per minute be coherent SI (factor 1: the FMU's numbers are SI)."""
    seen = {v.unit for path in sorted(fmu_dir.glob("*.fmu")) for v in read_model_description(str(path)).modelVariables
            if v.unit}
    assert {"N.m2", "kg.m2", "N.s2/m2", "N/m3", "1/s"} <= seen
    assert {u for u in seen if parse_unit(u).factor != 1.0} == {"1/min"}


@pytest.mark.parametrize("text, value, unit", [("150 mm", 0.15, "mm"), ("2.5e-3", 2.5e-3, None),
                                               (" -3E2 N/m3 ", -300.0, "N/m3"), (".5 kg", 0.5, "kg"),
                                               ("6 in", 0.1524, "in")])
def test_quantities_read_as_si(text, value, unit):
    v, u = parse_quantity(text)
    assert v == pytest.approx(value, rel=1e-14) and (u.text if u else None) == unit


@pytest.mark.parametrize("text, match", [("heavy", "not a number followed by a unit"),
                                         ("1.2 kilo", "unknown unit symbol 'kilo'"),
                                         ("150 m/", "a '/' with nothing on one side"),
                                         ("2 m^x", "not a unit symbol with an integer exponent")])
def test_bad_quantities_say_what_does_not_read(text, match):
    with pytest.raises(ValueError, match=match):
        parse_quantity(text)
