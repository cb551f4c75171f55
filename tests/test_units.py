"""Unit strings (pyfit.io.units): the Modelica grammar the FMUs declare and the forms people write, against the
definitions written out (SI prefixes; 1 in = 25.4 mm, 1 lb = 0.45359237 kg, g0 = 9.80665 m/s², exact)."""
import math

import numpy as np
import pytest
from fmpy import read_model_description
from hypothesis import given, settings
from hypothesis import strategies as st

from pyfit.io.units import PREFIXED, PREFIXES, parse_quantity, parse_unit

KG, M, S = (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0)


@pytest.mark.parametrize("text, factor, dimension", [
    ("N.m2", 1.0, (1, 3, -2, 0)),            # the FMUs' EI
    ("N·m²", 1.0, (1, 3, -2, 0)),
    ("Nm2", 1.0, (1, 3, -2, 0)),             # as catalogues write them, without a separator
    ("kNs/m", 1e3, (1, 0, -1, 0)),
    ("Nmm", 1e-3, (1, 2, -2, 0)),
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


def test_an_impedance_test_in_a_catalogue_s_units_reads_as_its_si_twin(tmp_path):
    """A damper impedance test written in in/s, kHz, lbf·s/in and rad reads to the numbers of the same test in
    Hz, m and N·s/m (definitions written out: 1 in = 0.0254 m, 1 lbf = 0.45359237 kg × 9.80665 m/s²); a unit of
    another quantity is refused naming the file, the key and the quantity's SI unit, a phase in neither deg nor
    rad naming those."""
    from pyfit.io.data import MeasurementError
    from pyfit.io.impedance import read_impedance, write_impedance

    f, a = [8.0, 21.0], [[1e-4, 3e-4], [2e-5, 6e-5]]
    z = np.array([[120 * np.exp(0.4j), 118 * np.exp(0.5j)], [40 * np.exp(-0.3j), 41 * np.exp(-0.2j)]])
    si = read_impedance(write_impedance(tmp_path / "si.csv", f, a, z))
    lbf_s_per_in = 0.45359237 * 9.80665 / 0.0254
    rows = [(fi / 1e3, 2 * np.pi * fi * aij / 0.0254, abs(zij) / lbf_s_per_in, np.angle(zij))
            for fi, ai, zi in zip(f, a, z) for aij, zij in zip(ai, zi)]
    np.savetxt(tmp_path / "us.csv", rows, delimiter=",", header="f_khz,v_ips,z,phi", comments="", fmt="%.17g")
    sidecar = ('kind = "damper_impedance"\n[columns]\nfrequency = { name = "f_khz", unit = "kHz" }\n'
               'velocity = { name = "v_ips", unit = "in/s" }\nimpedance = { name = "z", unit = "lbf·s/in" }\n'
               'phase = { name = "phi", unit = "rad" }\n')
    (tmp_path / "us.toml").write_text(sidecar)
    us = read_impedance(tmp_path / "us.csv")
    np.testing.assert_allclose(us.frequencies, si.frequencies, rtol=1e-14)
    # the SI file holds 9 significant digits (write_impedance's format); the other 17
    np.testing.assert_allclose(us.amplitudes, si.amplitudes, rtol=1e-8)
    np.testing.assert_allclose(us.impedance, si.impedance, rtol=1e-8)
    (tmp_path / "us.toml").write_text(sidecar.replace("lbf·s/in", "N/m"))
    with pytest.raises(MeasurementError, match=r"us\.toml: \[columns\.impedance\.unit\] unit 'N/m'; allowed: a "
                                               r"unit of kg/s, e\.g\. N\.s/m"):
        read_impedance(tmp_path / "us.csv")
    (tmp_path / "us.toml").write_text(sidecar.replace('"rad"', '"1"'))  # dimensionless, but which angle?
    with pytest.raises(MeasurementError, match=r"\[columns\.phase\.unit\] unit '1'; allowed: deg, rad"):
        read_impedance(tmp_path / "us.csv")
