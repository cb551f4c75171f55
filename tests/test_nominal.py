"""The nominal model a user describes: reading, errors, and what the diagnosis builds from it."""
import numpy as np
import pytest

from pyfit.gap.systems import make_system
from pyfit.io.nominal import load_nominal
from pyfit.io.schema import ConfigError

DESCRIBED = """
[nominal]
family = "damper"
[nominal.fixed]          # a symmetric damper, not the design one
m1 = 1.0
m2 = 1.0
L1 = 0.15
L2 = 0.15
J_G1 = 2.0e-3
J_G2 = 2.0e-3
a1 = 0.02
a2 = 0.02
[nominal.free]
EI = { start = 12.0, lower = 4.0, upper = 36.0 }
alpha_pd = { start = 1.5 }
"""
FMU_DEFAULTS = {"EI": 10.0, "alpha_pd": 2.0, "beta_pd": 2e-4, "L1": 0.17, "L2": 0.12, "a1": 0.0325, "a2": 0.0325,
                "m1": 0.8, "m2": 0.6}


def test_described_damper_sets_the_nominal_and_the_effect_ranges(tmp_path):
    f = tmp_path / "my_damper.toml"
    f.write_text(DESCRIBED)
    nom = load_nominal(f)
    system = make_system("damper", FMU_DEFAULTS, nom)
    assert system.linear == ("EI", "alpha_pd")
    assert system.nominal_fixed["m1"] == 1.0 and system.nominal_fixed["a1"] == 0.02
    assert "a1" not in {k for k, v in system.nominal_fixed.items() if k.startswith("k_")}
    assert system.start([]) == {"EI": 12.0, "alpha_pd": 1.5}
    b = system.bounds(system.start([]))
    assert b["EI"] == (4.0, 36.0) and b["alpha_pd"] == pytest.approx((0.15, 15.0))  # the default rule: x0.1 .. x10
    # the tip stiffness of arm 1 from the described EI and L1: 3 EI / L1^3
    sc = system.scale([np.array([1e-4, -1e-4])], 500.0, {"EI": 12.0, "alpha_pd": 1.5})
    assert sc.k == pytest.approx(3 * 12.0 / 0.15**3, rel=1e-12)
    # mass eccentricity is a deviation from the described offsets, not a switch from zero
    lo, start, hi = system.effects["mass_eccentricity"].params[0].range(sc)
    assert (lo, start, hi) == pytest.approx((-0.01, 0.02, 0.05))


def test_default_nominal_damper_keeps_the_design_eccentric_masses():
    system = make_system("damper", FMU_DEFAULTS, None)
    assert "a1" not in system.nominal_fixed  # the FMU's own 32.5 mm stays
    sc = system.scale([np.array([1e-4, -1e-4])], 500.0, {"EI": 10.0})
    assert system.effects["mass_eccentricity"].params[1].range(sc)[1] == 0.0325


@pytest.mark.parametrize("text,match", [
    ('[nominal]\nfamily = "beam"\n', r"\[nominal.family\] unknown family 'beam'; allowed: sdof, damper"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nm1 = "heavy"\n', r"\[nominal.fixed.m1\] must be a number"),
    ('[nominal]\nfamily = "damper"\n[nominal.free]\nEI = { start = 50.0, lower = 1.0, upper = 30.0 }\n',
     r"\[nominal.free.EI.start\] 50.0 outside \[1.0, 30.0\]"),
    ('[nominal]\nfamily = "damper"\n[nominal.free]\nEI = { lower = 1.0 }\n', r"\[nominal.free.EI\] give both lower and upper"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nEI = 10.0\n[nominal.free]\nEI = { start = 10.0 }\n',
     r"\[nominal.free.EI\] is also in \[nominal.fixed\]"),
    ('[model]\nfamily = "damper"\n', r"\[model\] unknown section; allowed: nominal"),
])
def test_bad_nominal_files_name_file_and_key(tmp_path, text, match):
    f = tmp_path / "n.toml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=match):
        load_nominal(f)


def test_unknown_parameter_names_the_valid_ones(tmp_path):
    f = tmp_path / "n.toml"
    f.write_text('[nominal]\nfamily = "damper"\n[nominal.fixed]\nmass1 = 1.0\n')
    with pytest.raises(ConfigError, match=r"n.toml: \[nominal.fixed.mass1\] not a parameter of the model; allowed: EI, L1"):
        load_nominal(f).check_names({"EI", "L1"})
