"""The nominal model a user describes: reading, errors, and what the diagnosis builds from it."""
import pathlib

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
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nm1 = "heavy"\n',
     r"\[nominal.fixed.m1\] 'heavy': not a number followed by a unit; allowed: a number in SI units, or a string"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nm1 = "1.2 kilo"\n',
     r"\[nominal.fixed.m1\] '1.2 kilo': unknown unit"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nm1 = true\n', r"\[nominal.fixed.m1\] must be a number \(SI\) or"),
    # a unit slip: millimetres, grams, kg·mm² written as SI numbers, and a unit of another quantity
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nL1 = 150\n',
     r"\[nominal.fixed.L1\] 150 m is not what a Stockbridge damper has \(0.01 to 3 m\); the file's numbers are SI"),
    ('[nominal]\nfamily = "damper"\n[nominal.free]\nEI = { start = 1.2e7 }\n',
     r"\[nominal.free.EI.start\] 1.2e\+07 N.m2 is not what a Stockbridge damper has"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nm1 = 1200\n', r"\[nominal.fixed.m1\] 1200 kg is not what"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nm1 = 1.0\nJ_G1 = 2.0\n',
     r"\[nominal.fixed.J_G1\] J_G1 / m1 gives a radius of gyration of 1.41e\+03 mm, not a damper mass's "
     r"\(3 to 500 mm\)"),
    ('[nominal]\nfamily = "damper"\n[nominal.fixed]\nL1 = "150 g"\n',
     r"\[nominal.fixed.L1\] 'g' is a mass \(kg\), but L1 is in m; allowed: a number in m or a value in a unit "
     r"of a length"),
    ('[nominal]\nfamily = "damper"\n[nominal.free]\nEI = { start = "12 N.m2", lower = "4 N.m", upper = 40.0 }\n',
     r"\[nominal.free.EI.lower\] 'N.m' is kg.m2/s2, but nominal.free.EI.start is in 'N.m2'"),
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


def test_values_written_with_units_read_to_the_si_numbers_of_the_same_damper(tmp_path):
    """The described damper above in the units of a drawing (g, cm, mm, in, kg·mm², N·mm²): the same SI numbers
    as written out by the definitions (1 in = 25.4 mm exact)."""
    f = tmp_path / "drawing.toml"
    f.write_text("""
[nominal]
family = "damper"
[nominal.fixed]
m1 = "1000 g"
m2 = "1 kg"
L1 = "15 cm"
L2 = "5.905511811023622 in"
J_G1 = "2000 kg·mm²"
J_G2 = "2e-3 kg.m2"
a1 = "20 mm"
a2 = 0.02
[nominal.free]
EI = { start = "12 N·m²", lower = "4e6 N*mm^2", upper = 36.0 }
alpha_pd = { start = "1.5 1/s" }
""")
    (tmp_path / "si.toml").write_text(DESCRIBED)
    drawn, si = load_nominal(f), load_nominal(tmp_path / "si.toml")
    assert drawn.fixed.keys() == si.fixed.keys() and drawn.free.keys() == si.free.keys()
    for name, value in si.fixed.items():
        assert drawn.fixed[name] == pytest.approx(value, rel=1e-14), name
    assert drawn.free["EI"].lower == pytest.approx(4.0, rel=1e-14) and drawn.free["EI"].start == 12.0
    assert drawn.free["alpha_pd"].start == 1.5
    assert drawn.units["L1"][0] == "nominal.fixed.L1" and drawn.units["L1"][1].text == "cm"


def test_unknown_parameter_names_the_valid_ones(tmp_path, fmu_dir):
    from pyfit.runtime.fmu import FmuRunner

    f = tmp_path / "n.toml"
    f.write_text('[nominal]\nfamily = "damper"\n[nominal.fixed]\nmass1 = 1.0\n')
    with pytest.raises(ConfigError, match=r"n.toml: \[nominal.fixed.mass1\] not a parameter of the model; "
                                          r"allowed: A, D, EI, "):
        load_nominal(f).check_against(FmuRunner(str(fmu_dir / "StockbridgeDamper.fmu")).parameters())


@pytest.mark.parametrize("fmu, text, match", [
    ("SDOFBoucWen", '[nominal]\nfamily = "sdof"\n[nominal.fixed]\nk = "5e4 N"\n',
     r"\[nominal.fixed.k\] 'N' is a force \(kg.m/s2\), but k is in N/m; allowed: a number in N/m or a value in a unit "
     r"of kg/s2"),
    ("SDOFBoucWen", '[nominal]\nfamily = "sdof"\n[nominal.fixed]\nbeta = "1000 1/m"\n',
     r"\[nominal.fixed.beta\] '1/m' is 1/m, but beta is in no declared unit; allowed: a number"),
    ("SDOFBoucWen", '[nominal]\nfamily = "sdof"\n[nominal.free]\nm = { start = -2.0 }\n',
     r"\[nominal.free.m\] -2 is outside the model's range; allowed: 0.0 to inf kg"),
    ("StockbridgeDamper", '[nominal]\nfamily = "damper"\n[nominal.free]\nalpha_pd = { start = 1.0, lower = -1.0, '
     'upper = 5.0 }\n', r"\[nominal.free.alpha_pd\] -1 is outside the model's range; allowed: 0.0 to inf 1/s"),
])
def test_a_nominal_is_checked_against_the_units_and_ranges_the_fmu_declares(tmp_path, fmu_dir, fmu, text, match):
    from pyfit.runtime.fmu import FmuRunner

    f = tmp_path / "n.toml"
    f.write_text(text)
    with pytest.raises(ConfigError, match=match):
        load_nominal(f).check_against(FmuRunner(str(fmu_dir / f"{fmu}.fmu")).parameters())


def test_frf_peaks_of_a_linear_sdof_sweep_give_its_natural_frequency_and_damping(measured):
    """Independent truth: the analytic SDOF (m 2 kg, c 10 N·s/m, k 1e5 N/m: f_n 35.59 Hz, zeta 1.12 %) driven
    by a 5-80 Hz force sweep (scipy lsim), displacement and acceleration outputs, with 0.5 % noise."""
    import scipy.signal

    from pyfit.analysis.excitation import Excitation
    from pyfit.analysis.modal import frf_peaks

    m, c, k, fs = 2.0, 10.0, 1e5, 500.0
    f_n, zeta = np.sqrt(k / m) / (2 * np.pi), c / (2 * np.sqrt(k * m))
    t = np.arange(0, 35.0, 1 / fs)
    u = Excitation(2, 10.0, 5.0, 80.0, 75.0 / 34.0, t_ramp=1.0)(t)
    sys_ = scipy.signal.StateSpace([[0, 1], [-k / m, -c / m]], [[0], [1 / m]], [[1, 0], [-k / m, -c / m]],
                                   [[0], [1 / m]])
    _, y, _ = scipy.signal.lsim(sys_, u, t)
    rng = np.random.default_rng(0)
    for col, order, what in ((0, 0, "displacement"), (1, 2, "acceleration")):
        out = y[:, col] + 0.005 * np.std(y[:, col]) * rng.standard_normal(len(t))
        for segment_s, how in ((8.0, "8 s Welch segments"), (None, "whole record")):
            peaks = frf_peaks(u, out, fs, (5.0, 80.0), order, segment_s)
            main = min(peaks, key=lambda p: abs(p.f_n - f_n))
            # a line is 0.125 Hz (Welch) or 1/35 Hz: 3.5e-3 and 8e-4 of f_n; the parabola refines it
            measured(f"FRF peak of a linear SDOF force sweep ({what} output, {how}): |f_peak / f_n - 1|",
                     abs(main.f_n / f_n - 1), 1e-3)
            measured(f"FRF peak of a linear SDOF force sweep ({what} output, {how}): |zeta_half-power / zeta - 1|",
                     abs(main.zeta / zeta - 1), 0.1)


def test_damper_modal_start_puts_the_lowest_resonance_on_the_measured_peak(fmu_dir, measured):
    """A symmetric damper (configs/symmetric_damper.toml) whose true EI (6 N·m²) is half the described start
    (12 N·m²), a 5-20 Hz
    constant-velocity clamp sweep over 15 s made by the CasADi reference (CVODES): the started model's lowest
    resonance (linearised FMU) against the measured peak, and the started EI against the truth."""
    from pyfit.analysis.excitation import Excitation, motion_with_derivatives
    from pyfit.analysis.modal import frf_peaks
    from pyfit.gap import datasets
    from pyfit.gap.diagnose import fmu_defaults
    from pyfit.gap.simulate import Record
    from pyfit.reference.synthetic import SyntheticSpec, simulate_truth
    from pyfit.runtime.fmu import FmuRunner
    from pyfit.runtime.linearize import linear_modes

    symmetric = load_nominal(pathlib.Path(__file__).parents[1] / "configs" / "symmetric_damper.toml")
    sweep = Excitation(4, 0.005, 5.0, 20.0, 15.0 / 14.0, t_ramp=1.0)
    truth = {**datasets.DAMPER.linear, **symmetric.fixed, "EI": 6.0}
    t, y, _ = simulate_truth(SyntheticSpec("StockbridgeDamper", sweep, 15.0, 500.0, ["x1", "x2"], truth))
    motion = motion_with_derivatives(sweep, t, ("x", "v", "a"))
    rec = Record("sweep", "5 mm/s", 0.005, 500.0, {"x_base": motion["x"], "v_base": motion["v"],
                                                     "a_base": motion["a"]}, {"x1": y["x1"], "x2": y["x2"]}, 0)
    fmu = str(fmu_dir / "StockbridgeDamper.fmu")
    system = make_system("damper", fmu_defaults(FmuRunner(fmu)), symmetric)
    starts = system.data_starts([rec], lambda p: linear_modes(fmu, p))
    assert system.start([rec])["EI"] == 12.0  # the user's start; the data's starts come beside it
    peak = frf_peaks(rec.compared("x_base"), rec.outputs["x1"], rec.fs, (5.0, 20.0), segment_s=None)[0]
    f_start = linear_modes(fmu, {**system.nominal_fixed, **starts[0]})[0].f_n
    measured("damper modal start: lowest resonance of the started model vs the measured peak, relative",
             abs(f_start / peak.f_n - 1), 1e-6)
    # the whole-record FRF's peak lies within a quarter of a line (1/15 Hz) of the resonance: 2 x 0.2 % in EI
    measured("damper modal start from a 15 s clamp sweep: EI vs the truth (6 N·m², start 12), relative",
             abs(starts[0]["EI"] / 6.0 - 1), 0.005)


def test_damper_modal_starts_pair_every_resonance_with_every_peak(fmu_dir, measured):
    """A heavy catalogue damper (masses 3.1 / 3.4 kg, messenger EI 57 N·m²; a case of an earlier campaign draw)
    described without its EI: at the FMU's start EI (10 N·m²) the model's two lowest resonances (2.4, 3.3 Hz)
    lie below a 2.8-17 Hz clamp sweep and its third (23 Hz) in it, so putting the in-band resonance on the
    measured peaks (5.6, 7.8 Hz) makes EI 50 times too small. Among the starts, the lowest resonance on the
    lowest peak recovers EI (CasADi reference, 15 s sweep) and, driven by the sweep, fits it best."""
    from pyfit.analysis.excitation import Excitation, motion_with_derivatives
    from pyfit.gap import datasets
    from pyfit.gap.attribute import stacked_residuals
    from pyfit.gap.diagnose import fmu_defaults
    from pyfit.gap.simulate import Record
    from pyfit.io.nominal import NominalModel
    from pyfit.reference.synthetic import SyntheticSpec, simulate_truth
    from pyfit.runtime.fmu import FmuRunner
    from pyfit.runtime.linearize import linear_modes

    geometry = {"m1": 3.105, "L1": 0.2704, "a1": 0.00695, "J_G1": 8.113e-3, "m2": 3.374, "L2": 0.2964,
                "a2": 0.0422, "J_G2": 6.158e-3}
    sweep = Excitation(4, 0.005, 2.83, 17.1, 15.0 / 14.0, t_ramp=1.0)
    truth = {**datasets.DAMPER.linear, **geometry, "EI": 57.0, "alpha_pd": 1.3, "beta_pd": 3e-4}
    t, y, _ = simulate_truth(SyntheticSpec("StockbridgeDamper", sweep, 15.0, 500.0, ["acc_x1", "F_clamp"], truth))
    motion = motion_with_derivatives(sweep, t, ("x", "v", "a"))
    rec = Record("sweep", "5 mm/s", 0.005, 500.0, {"x_base": motion["x"], "v_base": motion["v"],
                                                     "a_base": motion["a"]},
                 {k: y[k] for k in ("acc_x1", "F_clamp")}, 0)
    fmu = str(fmu_dir / "StockbridgeDamper.fmu")
    runner = FmuRunner(fmu)
    system = make_system("damper", fmu_defaults(runner), NominalModel("damper", geometry))
    start = system.start([rec])
    assert [round(m.f_n) for m in linear_modes(fmu, {**system.nominal_fixed, **start})][:3] == [2, 3, 23]
    starts = system.data_starts([rec], lambda p: linear_modes(fmu, p))
    measured("damper modal starts, the in-band resonance not the lowest: the first start's EI vs the truth "
             "(57 N·m², FMU start 10), relative", abs(starts[0]["EI"] / 57.0 - 1), 0.01)
    costs = [float(np.sum(stacked_residuals(runner, [rec], {**system.nominal_fixed, **s}, 2, 2) ** 2)) for s in starts]
    assert int(np.argmin(costs)) == 0, [(round(s["EI"], 2), round(c, 4)) for s, c in zip(starts, costs)]
    # a nominal calibrated on records with a strong effect can end with its damping far off (an earlier campaign
    # case: beta_pd 55 x the truth): the effect refits' starts take only its resonances to name the peaks, and
    # their damping from the start values, scaled to the measured peak's half-power width
    calibrated = {"EI": 1.05 * 57.0, "alpha_pd": 50 * 1.3, "beta_pd": 50 * 3e-4}
    around = system.data_starts([rec], lambda p: linear_modes(fmu, p), calibrated)
    true_linear = {k: truth[k] for k in start}
    zeta = [linear_modes(fmu, {**system.nominal_fixed, **p})[0].zeta for p in (around[0], true_linear)]
    measured("damper modal starts around a calibrated nominal with 50 x the damping: the first start's EI vs the "
             "truth, relative", abs(around[0]["EI"] / 57.0 - 1), 0.01)
    measured("damper modal starts around a calibrated nominal with 50 x the damping: the first start's lowest "
             "damping ratio vs the truth's, relative", abs(zeta[0] / zeta[1] - 1), 0.25)


def test_a_joint_refit_holds_each_seed_it_starts_from():
    """A member's refit started from the lowest level's linear system can end far from the calibrated nominal
    (campaign damper case 4: a friction refit with beta_pd 480 x the nominal's, whose rule bounds span a factor
    10 either way). A joint refit seeded from it must be able to start there: its bounds widen to hold the seed's
    linear values (clipped into the nominal's, the seed is another model, worse than the member alone), and stay
    the nominal's when every seed lies inside them."""
    from pyfit.gap.attribute import Fit, UnitScaling, effect_task
    from pyfit.gap.effect import Scale, combine

    system = make_system("damper", FMU_DEFAULTS)
    nominal = Fit("nominal", {**FMU_DEFAULTS, "EI": 10.3, "alpha_pd": 3.7, "beta_pd": 9.8e-7}, ["EI"], 0, 0.2, 1, 1.0)
    scale = Scale(3e-4, 0.02, 3 * 10.3 / 0.17 ** 3, nominal.params)
    pair = combine([system.effects["coulomb_friction"], system.effects["hysteresis"]])
    member = {**nominal.params, "EI": 10.29, "alpha_pd": 1.44, "beta_pd": 4.7e-4, "F_c1": 0.038, "F_c2": 0.058,
              "v_s": 1e-3}
    task = effect_task(system, pair, "x.fmu", [], nominal, scale, 10, 1, seeds=(member,))
    unit = UnitScaling(list(task.start), task.bounds, task.log_scaled)
    held = unit.values(unit.scaled({**task.start, **task.alternatives[-1]}))
    assert all(held[n] == pytest.approx(member[n], rel=1e-9) for n in ("EI", "alpha_pd", "beta_pd", "F_c1"))
    alone = effect_task(system, pair, "x.fmu", [], nominal, scale, 10, 1)
    assert alone.bounds["beta_pd"][1] < member["beta_pd"] / 40  # the nominal's bounds did not hold it
    inside = {**member, "alpha_pd": 2.0, "beta_pd": 2e-6}
    assert effect_task(system, pair, "x.fmu", [], nominal, scale, 10, 1, seeds=(inside,)).bounds == alone.bounds
