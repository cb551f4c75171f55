"""Span design check: conductor bending stiffness, Poffenberger–Swart against a direct solution of the beam
with tension, safe border line, energy balance with several dampers, placement against a brute-force grid,
the SPAN.toml reader and the design_check command."""
import json
import math
import pathlib
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from pyfit.design import conductor as cd
from pyfit.design import energy_balance as eb
from pyfit.design import fatigue, placement
from pyfit.runtime.damper_power import DamperPowerTable, damper_power_table
from pyfit.design.wind import WindPower
from pyfit.io.schema import ConfigError
from pyfit.design.span_config import load_span_design

ROOT = pathlib.Path(__file__).resolve().parents[1]
DRAKE = cd.DRAKE
TENSION = 0.2 * DRAKE.rts


def test_drake_stranding_gives_its_catalogue_diameter_and_stiffness_bounds(measured):
    """Outer diameter 28.1 mm (ASTM B232: 1.108 in = 28.14 mm); EI bounds by summing each wire at its actual
    angular position (parallel-axis theorem wire by wire) against the layer formula n·A·r²/2."""
    measured("Drake outer diameter from its stranding vs the catalogue 28.14 mm: |Δ| [m]",
             abs(DRAKE.diameter - 28.14e-3), 0.05e-3)
    ei_min = ei_max = 0.0
    radius = 0.0
    for k, layer in enumerate((cd.Layer(1, 3.45e-3, cd.STEEL_E, "steel"), cd.Layer(6, 3.45e-3, cd.STEEL_E, "steel"),
                               cd.Layer(10, 4.44e-3, cd.ALUMINIUM_E, "aluminium"),
                               cd.Layer(16, 4.44e-3, cd.ALUMINIUM_E, "aluminium"))):
        d = layer.wire_diameter
        r = 0.0 if k == 0 else radius + d / 2
        radius = d / 2 if k == 0 else radius + d
        angles = 2 * np.pi * np.arange(layer.n) / layer.n + 0.3 * k  # any orientation of the ring
        i_own = np.pi * d ** 4 / 64
        ei_min += layer.n * layer.youngs_modulus * i_own
        ei_max += layer.youngs_modulus * np.sum(i_own + np.pi * d ** 2 / 4 * (r * np.sin(angles)) ** 2)
    assert DRAKE.ei_min == pytest.approx(ei_min, rel=1e-12)
    assert DRAKE.ei_max == pytest.approx(ei_max, rel=1e-12)
    assert DRAKE.aluminium_layers == 2 and 30 < DRAKE.ei_max / DRAKE.ei_min < 40


@pytest.mark.parametrize("ei", [DRAKE.ei_min, DRAKE.ei_max])
def test_poffenberger_swart_against_the_beam_with_tension_solved_directly(ei, measured):
    """EI y'''' − T y'' = 0 on [0, 40/p], clamped at 0, leaving with the standing wave's slope θ and no
    curvature, solved by scipy's collocation BVP solver: Y_b = 2 y(89 mm) and σ_a = E_a d_a y''(0) / 2."""
    Y, f = 0.3 * DRAKE.diameter, 20.0
    theta = float(fatigue.clamp_slope(Y, f, TENSION, DRAKE.mass_per_length))
    p = math.sqrt(TENSION / ei)
    length = 40 / p

    def rhs(x, y):
        return np.vstack([y[1], y[2], y[3], (TENSION / ei) * y[2]])

    def bc(ya, yb):
        return np.array([ya[0], ya[1], yb[1] - theta, yb[2]])

    x = np.linspace(0, length, 4000)
    guess = np.vstack([theta * (x - (1 - np.exp(-p * x)) / p), theta * (1 - np.exp(-p * x)),
                       theta * p * np.exp(-p * x), -theta * p ** 2 * np.exp(-p * x)])
    sol = solve_bvp(rhs, bc, x, guess, tol=1e-10, max_nodes=200000)
    assert sol.success
    yb_direct = 2 * sol.sol(fatigue.X_B)[0]
    stress_direct = DRAKE.outer_youngs_modulus * DRAKE.outer_wire_diameter * sol.sol(0.0)[2] / 2
    yb = float(fatigue.bending_amplitude(Y, f, TENSION, DRAKE.mass_per_length, ei))
    stress = float(fatigue.bending_stress(Y, f, DRAKE, TENSION, ei))
    measured(f"Poffenberger–Swart Y_b at 89 mm (EI = {ei:.1f} N·m²) vs the beam with tension solved directly: "
             "relative error", abs(yb / yb_direct - 1), 1e-6)
    measured(f"Poffenberger–Swart stress K·Y_b (EI = {ei:.1f} N·m²) vs E_a d_a y''(0)/2 of the direct solution: "
             "relative error", abs(stress / stress_direct - 1), 1e-6)


def test_safe_border_line_and_its_inverse():
    """The published CIGRE coefficients (EPRI Orange Book §3.3) and the inverse on both branches."""
    assert fatigue.safe_border_line(1e6, 2) == pytest.approx(450e6 * 1e6 ** -0.2, rel=1e-12)
    assert fatigue.safe_border_line(1e8, 2) == pytest.approx(263e6 * 1e8 ** -0.17, rel=1e-12)
    assert fatigue.safe_border_line(1e7, 1) == pytest.approx(730e6 * 1e7 ** -0.2, rel=1e-12)
    assert fatigue.endurance_stress(2) / 1e6 == pytest.approx(263 * 5e8 ** -0.17, rel=1e-12)  # 8.73 MPa
    for n in (1e5, 3e6, 1e8, 5e9):
        for layers in (1, 2):
            assert fatigue.cycles_to_failure(fatigue.safe_border_line(n, layers), layers) == pytest.approx(n, rel=1e-9)
    assert fatigue.cycles_to_failure(0.0, 2) == math.inf


def test_yearly_cycles_follow_the_weibull_climate():
    """A flat stress σ below every knee over the band: cycles per year = ∫ St·V/D dP(V) over the range
    (worst Strouhal: the upper one), damage = cycles / N(σ)."""
    climate = fatigue.WindClimate(2.0, 4.0, (1.0, 7.0), (0.185, 0.2), 0.5)
    f = np.geomspace(*climate.band(DRAKE.diameter), 50)
    sigma = 5e6
    damage, cycles = fatigue.yearly_damage(f, np.full_like(f, sigma), DRAKE.diameter, climate, 2, bins=4000)
    v = np.linspace(1.0, 7.0, 200001)
    pdf = (2.0 / 4.0) * (v / 4.0) * np.exp(-(v / 4.0) ** 2)
    expected = 0.5 * fatigue.SECONDS_PER_YEAR * np.trapezoid(0.2 * v / DRAKE.diameter * pdf, v)
    assert cycles == pytest.approx(expected, rel=1e-5)
    assert damage == pytest.approx(cycles / fatigue.cycles_to_failure(sigma, 2), rel=1e-12)


def test_two_dampers_add_their_power_with_their_phase_on_the_wave():
    """Without the dampers' reaction, two dashpots c at x1, x2 give the amplitude of one dashpot at x1 with
    c·(sin²kx1 + sin²kx2)/sin²kx1: each is driven by the standing wave at its own position."""
    span = eb.Conductor(DRAKE.diameter, DRAKE.mass_per_length, TENSION, 300.0, 0.0,
                        (cd.SELF_DAMPING_LAWS["noiseux1991"], cd.self_damping_constant(DRAKE)))
    f, c, x1, x2 = 25.0, 40.0, 0.6, 1.7
    k = 2 * np.pi / float(span.wavelength(f))
    dash = lambda c_: (lambda a: np.full(np.shape(a), c_ + 0j))  # noqa: E731
    two = eb.steady_amplitude(f, span, [(dash(c), x1), (dash(c), x2)], reaction=False)
    one = eb.steady_amplitude(f, span, [(dash(c * (np.sin(k * x1) ** 2 + np.sin(k * x2) ** 2) / np.sin(k * x1) ** 2), x1)],
                              reaction=False)
    assert two == pytest.approx(one, rel=1e-9)
    assert two < eb.steady_amplitude(f, span, [(dash(c), x1)], reaction=False) < eb.steady_amplitude(f, span)


def test_the_dampers_reaction_vanishes_for_a_weak_damper_and_matters_for_a_strong_one():
    """The string solved with the dampers' forces: a weak dashpot (Z ≪ √(T·m) = 213 N·s/m) moves with the
    undisturbed wave, Y·|sin kx|; a strong one (Z = √(T·m)) holds its point still relative to that."""
    span = eb.Conductor(DRAKE.diameter, DRAKE.mass_per_length, TENSION, 300.0, 0.0)
    f, x1, x2 = 20.0, 0.8, 1.9
    k = 2 * np.pi / float(span.wavelength(f))
    Y = np.array([1e-3, 5e-3])
    weak = eb.clamp_amplitudes(Y, f, span, [(lambda a: np.full(np.shape(a), 1e-3 + 0j), x1),
                                            (lambda a: np.full(np.shape(a), 2e-3 + 0j), x2)])
    assert weak[0] == pytest.approx(Y * abs(np.sin(k * x1)), rel=1e-5)
    assert weak[1] == pytest.approx(Y * abs(np.sin(k * x2)), rel=1e-5)
    z_c = np.sqrt(TENSION * DRAKE.mass_per_length)
    strong = eb.clamp_amplitudes(Y, f, span, [(lambda a: np.full(np.shape(a), z_c + 0j), x1)])[0]
    assert np.all(strong < 0.9 * Y * abs(np.sin(k * x1)))


@pytest.mark.parametrize("name", list(cd.SELF_DAMPING_LAWS))
def test_self_damping_is_the_power_law_its_exponents_say(name):
    """P/L = k Y^l f^m / T^n: at random (f, Y, T) in the aeolian range, scaling one variable by λ scales the power by
    λ^l, λ^m or λ^-n (log-log slopes measured on the function, not re-typed), and it is linear in k. A law whose
    code mixed up the exponents or the units of T (kN) would fail."""
    law = cd.SELF_DAMPING_LAWS[name]
    rng = np.random.default_rng(7)
    for _ in range(20):
        f, Y, T, lam, k = rng.uniform(5, 50), rng.uniform(1e-4, 3e-3), rng.uniform(1e4, 8e4), rng.uniform(1.1, 3), 1.7
        p = lambda f, Y, T, k=k: cd.self_damping_power_per_length(law, k, f, Y, T)  # noqa: E731
        assert np.log(p(f, lam * Y, T) / p(f, Y, T)) / np.log(lam) == pytest.approx(law.l, rel=1e-12)
        assert np.log(p(lam * f, Y, T) / p(f, Y, T)) / np.log(lam) == pytest.approx(law.m, rel=1e-12)
        assert np.log(p(f, Y, lam * T) / p(f, Y, T)) / np.log(lam) == pytest.approx(-law.n, rel=1e-12)
        assert p(f, Y, T, k=2 * k) == pytest.approx(2 * p(f, Y, T), rel=1e-14)
        # T enters in kN: at 1000 N, Y = 1 m, f = 1 Hz the power per length is k itself
        assert cd.self_damping_power_per_length(law, k, 1.0, 1.0, 1000.0) == pytest.approx(k, rel=1e-14)
    # the published laws differ: a table that repeated one law under every name would not
    assert len({(w.l, w.m, w.n) for w in cd.SELF_DAMPING_LAWS.values()}) == len(cd.SELF_DAMPING_LAWS)


@pytest.fixture(scope="module")
def drake_table(fmu_dir):
    """The design damper without its softening cubic springs (k_cs = 0: every run stays stable up to 30 mm,
    so that every configuration resolves) over a coarse band grid (7 frequencies × 7 clamp amplitudes)."""
    freqs = np.geomspace(6.6, 49.8, 7)
    return damper_power_table(fmu_dir / "DamperElement.fmu", freqs, np.geomspace(1e-5, 3e-2, 7),
                                 {"k_cs1": 0.0, "k_cs2": 0.0}, progress=False)


def test_placement_is_at_least_as_good_as_a_brute_force_grid(drake_table, measured):
    """300 m ACSR Drake at 20 % RTS with the design damper (linear springs): the optimiser's best 1 and 2
    dampers in 0.5–3 m against every configuration of 1–2 dampers on a 0.5 m grid."""
    span = eb.Conductor(DRAKE.diameter, DRAKE.mass_per_length, TENSION, 300.0, 0.0,
                        (cd.SELF_DAMPING_LAWS["noiseux1991"], cd.self_damping_constant(DRAKE)))
    coarse = placement.position_grid((0.5, 3.0), 0.5)
    for n in (1, 2):
        best = placement.optimise(span, DRAKE, drake_table, n, (0.5, 3.0), step=0.25)
        brute = placement.grid_search(span, DRAKE, drake_table, n, coarse)
        assert len(brute) == math.comb(6, n) and all(math.isfinite(c.use) for c in brute)
        measured(f"placement of {n} damper(s): optimiser's worst-case fatigue use minus the best of a 0.5 m "
                 "brute-force grid (≤ 0)", best.use - brute[0].use, 0.0)
    bare = placement.evaluate(span, DRAKE, drake_table, ())
    assert bare.use > placement.grid_search(span, DRAKE, drake_table, 1, coarse)[0].use


def test_span_config_errors_name_the_key(tmp_path):
    cases = {
        "[conductor]\ntype = 'dove'\n[span]\nlength = 300\ntension_rts = 0.2\n": "[conductor.type] unknown conductor",
        "[conductor]\ntype = 'drake'\n[span]\nlength = 300\n": "give exactly one of tension",
        "[conductor]\ntype = 'drake'\n[span]\nlength = 300\ntension = 2e4\n[self_damping]\nlaw = 'x'\n":
            "[self_damping.law] unknown law",
        "[conductor]\ntype = 'drake'\n[span]\nlength = -3\ntension = 2e4\n": "[span.length] must be > 0",
        "[conductor]\ntype = 'drake'\n[span]\nlength = 300\ntension = 2e4\n[wind]\nstrouhal = [0.2, 0.1]\n":
            "[wind.strouhal] inverted",
        "[conductor]\ntype = 'drake'\n[span]\nlength = 300\ntension = 2e4\n[wind]\ncurve = 'rawlins'\n":
            "[wind.curve] unknown wind power curve 'rawlins'",
    }
    for text, expected in cases.items():
        path = tmp_path / "span.toml"
        path.write_text(text)
        with pytest.raises(ConfigError, match=expected.replace("[", r"\[").replace("]", r"\]")):
            load_span_design(path)
    design = load_span_design(ROOT / "configs" / "span_drake_300m.toml")
    assert design.tension == pytest.approx(0.2 * DRAKE.rts) and design.self_damping[0].l == 2.44
    assert design.wind.curve == "cigre" and design.wind.turbulence == 0.0
    path.write_text("[conductor]\ntype = 'drake'\n[span]\nlength = 300\ntension = 2e4\n[wind]\n"
                    "curve = 'brika1995'\nturbulence = 0.05\n")
    assert load_span_design(path).wind == WindPower("brika1995", 0.05)


def test_design_check_command_writes_the_report(fmu_dir, tmp_path):
    span = tmp_path / "span.toml"
    # a quick version of the example; the damper without its softening springs stays stable at every clamp
    # amplitude of the table, so that every configuration resolves
    small = {"n_amplitudes = 14": "n_amplitudes = 3\nparameters = { k_cs1 = 0.0, k_cs2 = 0.0 }",
             "n_frequencies = 20": "n_frequencies = 2", "max_dampers = 2": "max_dampers = 1", "step = 0.25": "step = 0.5"}
    text = (ROOT / "configs" / "span_drake_300m.toml").read_text()
    for old, new in small.items():
        assert old in text
        text = text.replace(old, new)
    span.write_text(text)
    run = subprocess.run([sys.executable, str(ROOT / "scripts" / "design_check.py"), str(span), "--fmus", str(fmu_dir),
                          "--out", str(tmp_path / "out"), "--workers", "1"], capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    md = (tmp_path / "out" / "design_check.md").read_text()
    res = json.loads((tmp_path / "out" / "design_check.json").read_text())
    # the verdict from the figures: CIGRE use = max stress / endurance stress, IEEE use = strain / 150 µε
    cigre = res["max_stress_pa"] / res["endurance_stress_pa"]
    ieee = res["max_strain_pp"] / 150e-6
    assert res["cigre_use"] == pytest.approx(cigre, rel=1e-12) and res["ieee_use"] == pytest.approx(ieee, rel=1e-12)
    verdict = "PASSES" if max(cigre, ieee) <= 1 else "FAILS"
    assert md.startswith("# Span design check: ACSR Drake")
    assert f"**The span {verdict} with {len(res['recommended_positions_m'])} damper(s)" in md
    assert f"a margin of {1 - max(cigre, ieee):.0%}" in md
    for name in ("design_amplitude.png", "design_stress.png", "design_positions.png", "design_check.json"):
        assert (tmp_path / "out" / name).is_file()
    bad = tmp_path / "bad.toml"
    bad.write_text("[span]\nlength = 1\n")
    run = subprocess.run([sys.executable, str(ROOT / "scripts" / "design_check.py"), str(bad)], capture_output=True,
                         text=True, timeout=60)
    assert run.returncode == 1 and "[conductor] missing section" in run.stderr


def _write_impedance_test(folder, rows, header="f,v0,Z,phi,comment", units=("Hz", "mm/s", "N.s/m", "deg")):
    csv = folder / "damper_test.csv"
    csv.write_text("# IEC 61897 characteristic test, bench export\n" + header + "\n"
                   + "\n".join(",".join(f"{x:.9g}" for x in r) + ",ok" for r in rows) + "\n")
    (folder / "damper_test.toml").write_text(
        'kind = "damper_impedance"\n[columns]\n'
        f'frequency = {{ name = "f", unit = "{units[0]}" }}\nvelocity = {{ name = "v0", unit = "{units[1]}" }}\n'
        f'impedance = {{ name = "Z", unit = "{units[2]}" }}\nphase = {{ name = "phi", unit = "{units[3]}" }}\n')
    return csv


def test_measured_impedance_file_replaces_the_damper_model(tmp_path):
    """An IEC 61897-style file (constant clamp-velocity levels, mm/s, degrees, a comment line, an extra column)
    of a dashpot c with a mass m (Z = c + iωm): the table read from it gives Z at its amplitudes and the same
    energy balance as the dashpot-and-mass written directly."""
    c, m = 35.0, 0.4
    freqs, levels = np.linspace(6.0, 50.0, 12), [50.0, 100.0, 600.0]  # Hz, mm/s
    rows = []
    for f in freqs:
        z = c + 1j * 2 * np.pi * f * m
        rows += [(f, v, abs(z), np.degrees(np.angle(z))) for v in levels]
    from pyfit.io.impedance import read_impedance
    test = read_impedance(_write_impedance_test(tmp_path, rows))
    table = DamperPowerTable.from_test(test)
    assert table.amplitudes.shape == (12, 3)
    assert table.amplitudes[3, 1] == pytest.approx(0.1 / (2 * np.pi * freqs[3]), rel=1e-12)
    assert table.impedance_at(3, 6e-4) == pytest.approx(c + 1j * 2 * np.pi * freqs[3] * m, rel=1e-8)
    span = eb.Conductor(DRAKE.diameter, DRAKE.mass_per_length, TENSION, 300.0, 2e-4)
    i = 5
    measured_y = eb.steady_amplitude(freqs[i], span, [(lambda a: table.impedance_at(i, a), 1.2)])
    direct_y = eb.steady_amplitude(freqs[i], span, [(lambda a: np.full(np.shape(a), c + 2j * np.pi * freqs[i] * m), 1.2)])
    assert measured_y == pytest.approx(direct_y, rel=1e-7)


def test_impedance_file_errors_name_the_problem(tmp_path):
    from pyfit.io.data import MeasurementError
    from pyfit.io.impedance import read_impedance
    csv = _write_impedance_test(tmp_path, [(10.0, 50.0, 40.0, 30.0)], units=("Hz", "m/s2", "N.s/m", "deg"))
    with pytest.raises(MeasurementError, match=r"\[columns.velocity.unit\] unit 'm/s2'; allowed: a unit of m/s, "
                                               r"e\.g\. m/s, mm/s, in/s"):
        read_impedance(csv)
    # a velocity in any unit of one reads (50 km/h = 50 / 3.6 m/s)
    csv = _write_impedance_test(tmp_path, [(10.0, 50.0, 40.0, 30.0)], units=("Hz", "km/h", "N.s/m", "deg"))
    assert read_impedance(csv).amplitudes[0, 0] == pytest.approx(50.0 / 3.6 / (2 * np.pi * 10.0), rel=1e-14)
    csv = _write_impedance_test(tmp_path, [(10.0, 50.0, 40.0, 30.0), (10.0, 100.0, 41.0, 31.0), (20.0, 50.0, 40.0, 30.0)])
    with pytest.raises(MeasurementError, match=r"\[frequency\] levels per frequency differ"):
        read_impedance(csv)
    csv = _write_impedance_test(tmp_path, [(10.0, 50.0, 40.0, 30.0)], header="freq,v0,Z,phi,comment")
    with pytest.raises(MeasurementError, match="no column 'f'"):
        read_impedance(csv)


def test_design_check_takes_a_measured_impedance_instead_of_the_damper_fmu(tmp_path):
    """A damper known only by its characteristic test (here a dashpot with a mass, Z = c + iωm, written as an
    impedance test file): the design check uses the test's frequencies inside the aeolian band and runs no FMU;
    a test that misses the band is refused by name."""
    from pyfit.design.design_check import run_design_check, write_report
    from pyfit.io.impedance import write_impedance

    freqs = np.array([4.0, 10.0, 20.0, 40.0, 80.0])  # Hz; the band of Drake at 1-7 m/s is 6.6-49.8 Hz
    amps = np.repeat(np.geomspace(1e-4, 3e-2, 4)[None, :], len(freqs), axis=0)
    write_impedance(tmp_path / "test.csv", freqs, amps, (60.0 + 2j * np.pi * freqs[:, None] * 0.5) * np.ones(amps.shape))
    text = (ROOT / "configs" / "span_drake_300m.toml").read_text()
    text = text.replace("[damper]\n", '[damper]\nimpedance_file = "test.csv"\n').replace("max_dampers = 2", "max_dampers = 1")
    (tmp_path / "span.toml").write_text(text)
    result = run_design_check(load_span_design(tmp_path / "span.toml"), None, progress=False)
    assert list(result.table.frequencies) == [10.0, 20.0, 40.0]
    assert "measured impedance `test.csv`" in write_report(result, tmp_path / "out").read_text()
    write_impedance(tmp_path / "test.csv", freqs[[0, 4]], amps[:2], np.full((2, 4), 60.0 + 0j))
    with pytest.raises(ConfigError, match="fewer than two test frequencies inside the aeolian band"):
        run_design_check(load_span_design(tmp_path / "span.toml"), None, progress=False)
    (tmp_path / "span.toml").write_text(text.replace("[damper]\n", "[damper]\nparameters = { k_bw1 = 400.0 }\n"))
    with pytest.raises(ConfigError, match=r"\[damper.impedance_file\] a measured impedance replaces the damper FMU"):
        load_span_design(tmp_path / "span.toml")
