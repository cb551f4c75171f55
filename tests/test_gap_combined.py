"""Diagnosis of systems that carry more than one effect, and of hysteresis loops of shapes the candidate's starts
do not hold: truths drawn at random across the family (a generator independent of the FMUs: the CasADi
reference integrated by CVODES), never at a start value of the candidate. Slow: `pytest -m slow`."""
import dataclasses
import json

import numpy as np
import pytest

from pyfit.gap import campaign, datasets, selection
from pyfit.gap.result import Diagnosis, Verdict
from pyfit.gap import diagnose as dg
from pyfit.gap.effect import Scale, with_derived
from pyfit.gap.effects import candidates

pytestmark = pytest.mark.slow

SEED = 20261125  # the truths of this file: each test draws its own from this seed, whatever ran before it


def _sdof_hysteresis_truths(n: int) -> list[dict]:
    """Bouc-Wen loops of the SDOF family (theory §1.1), drawn across it: the loading branch softening
    (γ + δ > 0) or, for ν below 1.5, mildly hardening (as the benchmark's); the unloading branch's γ − δ from
    0.2 to 2.5 (narrow to wide loops); ν drawn in each third of 1-3 in turn (never the starts' whole values);
    the hysteretic element holding 30-60 % of the stiffness and turning over at 50-500 N (β |z|^ν ≈ α there)."""
    rng, out = np.random.default_rng(SEED), []
    for i in range(n):
        nu = 1.0 + (i % 3 + rng.uniform(0.05, 0.95)) * 2.0 / 3.0  # every sharpness of the transition
        s = rng.uniform(-0.5, 1.5) if nu < 1.5 else rng.uniform(0.1, 1.5)  # γ + δ: hardening only for low ν
        d = rng.uniform(0.2, 2.5)  # γ − δ
        k = 1e5 * rng.uniform(0.4, 0.7)
        z_y = 10.0 ** rng.uniform(1.7, 2.7)
        out.append(_loop(float(k), nu, float(s), float(d), float(z_y)))
    return out


def _loop(k: float, nu: float, s: float, d: float, z_y: float) -> dict:
    """SDOF Bouc-Wen truth: linear spring k [N/m] beside a hysteretic element of 1e5 - k that turns over at
    z_y [N] (β |z|^ν ≈ α there), loading branch γ + δ = s, unloading branch γ − δ = d."""
    return {"k": k, "alpha": 1e5 - k, "beta": (1e5 - k) / z_y ** nu, "gamma": (s + d) / 2, "delta": (s - d) / 2,
            "nu": nu}


def _starts_hold_none_of(truth: dict, effect) -> bool:
    scale = Scale(1e-3, 0.2, 1e5, {"a1": 0.0325, "a2": 0.0325})
    starts = [with_derived(s, effect.derived(scale))
              for s in [{p.name: p.range(scale)[1] for p in effect.params}] + effect.starts(scale)]
    return all(any(abs(s.get(k, np.inf) - v) > 1e-9 for k, v in truth.items() if k in s) for s in starts)


@pytest.mark.parametrize("case", [0, 1, 2])
def test_sdof_hysteresis_of_a_random_shape_is_named(tmp_path, fmu_dir, case, measured):
    truth = _sdof_hysteresis_truths(3)[case]
    assert _starts_hold_none_of(truth, candidates("sdof")["hysteresis"])
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "hysteresis", seed=case, periods=2, truth=truth)
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "hysteresis", (truth, rep.sentence, rep.ranking[:2])
    measured(f"SDOF hysteresis of a random loop shape ({', '.join(f'{k} = {v:.3g}' for k, v in truth.items())}): "
             "held-out shrink [%]", rep.ranking[0].shrink_pct, 90.0, at_least=True)


def test_a_strong_element_with_a_wide_loop_on_long_sweeps_is_named_alone(tmp_path, fmu_dir, measured):
    """Three 35 s sweeps (a test bench's) of an SDOF whose hysteretic element holds 40-60 % of the stiffness and
    turns over far beyond the data's force (1-3 kN: a wide loop, a little hysteretic damping), drawn at random.
    A weak element with a narrow loop has the same first-order nonlinearity (α·β·γ) and is another basin of
    the least squares; refitted from there the loop leaves a misfit a cubic spring absorbs, and the pair is
    named; or the loop alone stays narrow while its pair with a partner of next to nothing holds the wide loop
    (the model so far then takes that loop). Named alone, within 1.2x the noise floor on the held-out file."""
    rng = np.random.default_rng(SEED + 3)
    nu = float(rng.uniform(1.0, 1.4))
    k = 1e5 * float(rng.uniform(0.4, 0.6))
    s, d = float(rng.uniform(-0.5, 0.5)), float(rng.uniform(1.0, 2.5))  # γ + δ, γ - δ
    z_y = float(10.0 ** rng.uniform(3.0, 3.5))
    truth = _loop(k, nu, s, d, z_y)
    assert _starts_hold_none_of(truth, candidates("sdof")["hysteresis"])
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "hysteresis", seed=3, truth=truth,
                                  style=datasets.LabStyle(excitation="sweep"))
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "hysteresis", (truth, rep.sentence, rep.ranking[:3])
    best = rep.ranking[0]
    measured("SDOF wide loop on 35 s sweeps: held-out NRMSE over the noise floor", best.heldout_gap_after
             / rep.gap.noise_floor, 1.2)


def test_a_moderate_element_with_a_very_wide_loop_on_short_sweeps_is_named_alone(tmp_path, fmu_dir, measured):
    """Three 6 s sweeps (the campaign's records) recorded by an accelerometer, of an SDOF whose hysteretic element
    holds 15-30 % of the stiffness and turns over at 150-400 N with ν from 1.4 to 2.0, drawn at random: a loop
    wider than the family's 0.1-width starts. Campaign seed 11 case 23 was one: refitted from those starts the loop
    ended narrow (α a third of the truth) and a softening cubic spring was added ("hysteresis + cubic_stiffness").
    Named alone, with ν within 0.15 of the truth."""
    rng = np.random.default_rng(SEED + 6)
    nu = float(rng.uniform(1.4, 2.0))
    k = 1e5 * float(rng.uniform(0.70, 0.85))
    s, d = float(rng.uniform(0.1, 1.5)), float(rng.uniform(0.2, 2.5))  # γ + δ (softening), γ - δ
    z_y = float(rng.uniform(150.0, 400.0))
    truth = _loop(k, nu, s, d, z_y)
    assert _starts_hold_none_of(truth, candidates("sdof")["hysteresis"])
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "hysteresis", seed=6, truth=truth,
                                  style=datasets.LabStyle(excitation="sweep", outputs=("a",), record_s=6.0))
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "hysteresis", (truth, rep.sentence, rep.ranking[:3])
    measured("SDOF very wide loop on 6 s sweeps: |fitted nu - withheld nu|",
             abs(rep.ranking[0].params["nu"] - nu), 0.15)


def test_a_weak_element_with_a_narrow_loop_is_named_and_its_strength_recovered(tmp_path, fmu_dir, measured):
    """An SDOF whose hysteretic element holds 2-5 % of the stiffness and turns over early (at 5-30 N, a narrow
    loop), drawn at random. On two such campaign cases (seed 7, cases 120 and 144) the refit from the larger shares
    only ended in the strong, wide basin (the same first-order nonlinearity), "not explained"; from the weak
    starts the loop is named, α within 5 %."""
    rng = np.random.default_rng(SEED + 4)
    nu = float(rng.uniform(1.1, 2.0))
    k = 1e5 * float(rng.uniform(0.95, 0.98))
    s, d = float(rng.uniform(0.3, 1.5)), float(rng.uniform(0.5, 2.5))  # γ + δ (softening), γ - δ
    z_y = float(10.0 ** rng.uniform(0.7, 1.5))
    truth = _loop(k, nu, s, d, z_y)
    assert _starts_hold_none_of(truth, candidates("sdof")["hysteresis"])
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "hysteresis", seed=4, truth=truth)
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "hysteresis", (truth, rep.sentence, rep.ranking[:3])
    best = rep.ranking[0]
    measured("SDOF weak narrow loop: fitted alpha relative to the withheld value",
             abs(best.params["alpha"] / truth["alpha"] - 1), 0.05)


def test_sdof_coulomb_friction_and_cubic_stiffness_are_named_together(tmp_path, fmu_dir, measured):
    rng = np.random.default_rng(SEED + 1)
    truth = {"F_c": float(rng.uniform(0.5, 1.5)), "v_s": 1e-3 * float(rng.uniform(0.5, 2.0)),
             "k3": float(rng.uniform(1.5e8, 4e8))}
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "coulomb_friction+cubic_stiffness", periods=2,
                                  truth=truth)
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert set(rep.chosen) == {"coulomb_friction", "cubic_stiffness"}, rep.sentence
    best = rep.ranking[0]
    measured("SDOF with Coulomb friction and cubic stiffness withheld: held-out shrink of the pair [%]",
             best.shrink_pct, 90.0, at_least=True)
    measured("the same: fitted k3 relative to the withheld value", abs(best.params["k3"] / truth["k3"] - 1), 0.05)
    # a combination is refitted from the model it extends and never ends worse than it on the calibration files
    calibration = {r.effect: r.calibration_nrmse for r in rep.ranking}
    for r in rep.ranking:
        if len(r.members) > 1:
            assert r.calibration_nrmse <= max(calibration[m] for m in r.members) * (1 + 1e-12), r.effect


def test_a_weak_loop_beside_a_strong_cubic_spring_is_named_as_both(tmp_path, fmu_dir, measured):
    """A hardening spring beside a hysteretic element holding 2-5 % of the stiffness that turns over at 10-30 N,
    its loop shape drawn at random, under band-limited noise recorded as displacement. A free-shape loop
    refitted alone bends to stand in for the spring (its loop then holds most of the stiffness), and the pair's
    joint descent from the same starts ends there too; the loop refitted first beside the spring's refit held
    fixed finds the weak loop, and the joint refit goes on from it."""
    rng = np.random.default_rng(SEED + 4)
    alpha = 1e5 * float(rng.uniform(0.02, 0.05))
    nu = float(rng.uniform(1.2, 2.2))
    truth = {**_loop(1e5 - alpha, nu, float(rng.uniform(0.1, 1.0)), float(rng.uniform(0.5, 2.5)),
                     float(rng.uniform(10.0, 30.0))), "k3": float(rng.uniform(4e8, 7e8))}
    assert _starts_hold_none_of({k: truth[k] for k in ("gamma", "delta", "nu")}, candidates("sdof")["hysteresis"])
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "cubic_stiffness+hysteresis", seed=56,
                                  truth=truth, style=datasets.LabStyle("noise", ("y",), record_s=8.0))
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert set(rep.chosen) == {"cubic_stiffness", "hysteresis"}, \
        (truth, rep.sentence, [(r.effect, r.heldout_gap_after) for r in rep.ranking[:4]])
    best = rep.ranking[0]
    measured("SDOF with a weak loop beside a strong cubic spring: fitted k3 relative to the withheld value",
             abs(best.params["k3"] / truth["k3"] - 1), 0.1)


def _campaign_case_named(tmp_path, fmu_dir, seed: int, index: int, withheld: str, excitation: str,
                         model: str = "sdof", sized: bool = False):
    """Case `index` of the `model` campaign's draw with `seed` (its withheld effects and excitation checked),
    written and diagnosed as the campaign does (default settings); asserts it is named right; returns the case and
    the report's best model. The case is written at its drawn strength (the search behaviour each test names was
    found there) or, `sized`, scaled to its drawn size over the noise as the campaign writes it (the case returned
    holds the truth as written)."""
    case = campaign.draw(index + 1, seed=seed, model=model)[index]
    assert case.withheld == withheld and case.excitation == excitation
    if not sized:
        case = dataclasses.replace(case, sizes=None)
    outcome = campaign.run_case(campaign.CaseJob(case, str(tmp_path), fmu_dir, campaign.RECORD_S))
    assert outcome["named"] == withheld, outcome["verdict"]
    case = dataclasses.replace(case, truth=outcome["case"]["truth"])
    report = tmp_path / f"case{index:04d}" / "diagnosis" / "report.json"
    return case, Diagnosis.read(report).ranking[0]


def test_a_pair_whose_least_helpful_partner_stands_in_for_its_second_member_is_named(tmp_path, fmu_dir, measured):
    """Coulomb friction and a hardening spring under multisines recorded as displacement (a case of the campaign's
    draw, CasADi reference): beside the friction a free-shape loop stands in for the spring as well as the
    spring does. The least helpful partner's joint refit is the budget control; counted with that partner at
    zero it is the friction alone again, so the pair is named and k3 recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 15, 118, "coulomb_friction+cubic_stiffness", "multisine")
    measured("SDOF with Coulomb friction and a hardening spring, a loop standing in as well: fitted k3 relative to "
             "the withheld value", abs(best.params["k3"] / case.truth["k3"] - 1), 0.1)


def test_a_one_parameter_partner_that_a_loop_outdoes_beside_the_first_member_is_named(tmp_path, fmu_dir, measured):
    """Coulomb friction and quadratic damping under band-limited noise recorded by an accelerometer (a case of the
    campaign's draw, CasADi reference): beside the friction held at its own refit, a free-shape loop absorbs
    more than the quadratic damping, so only the leaner partner's joint refit (selection.leaner_best) finds the
    pair; c2 is recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 16, 194, "coulomb_friction+quadratic_damping", "noise")
    measured("SDOF with Coulomb friction and quadratic damping under noise, a loop absorbing more beside the "
             "friction: fitted c2 relative to the withheld value", abs(best.params["c2"] / case.truth["c2"] - 1),
             0.05)


def test_a_lean_pair_whose_descent_stalls_is_not_lost_to_a_loop_pair(tmp_path, fmu_dir, measured):
    """Coulomb friction and quadratic damping under sweeps recorded as displacement (a case of the campaign's draw,
    CasADi reference): the pair's joint refit stalls (near-ideal friction) above the friction with a free-shape
    loop, which then fit the held-out files better; refitted on before the step is judged, the true pair fits them
    best and is named, with c2 recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 18, 44, "coulomb_friction+quadratic_damping", "sweep")
    # measured 0.09 (its refit on stops there too, above the truth's held-out misfit): room for 1.5x that
    measured("SDOF with Coulomb friction and quadratic damping on sweeps, a loop pair fitting better before the "
             "pair's refit on: fitted c2 relative to the withheld value",
             abs(best.params["c2"] / case.truth["c2"] - 1), 0.15)


def test_a_loop_standing_in_for_a_spring_beyond_its_own_sensitivity_leaves_the_spring_path_its_try(
        tmp_path, fmu_dir, measured):
    """A hardening spring and a weak loop under multisines recorded as displacement (a case of the campaign's draw,
    CasADi reference): the free-shape loop refitted alone takes up the spring's part so fully that it meets the
    absolute criterion and its sensitivity to the spring shows nothing at it; the path from the spring is tried
    all the same, the weak loop is found beside it, the pair named and k3 recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 18, 183, "cubic_stiffness+hysteresis", "multisine")
    # the pair ends at a weaker loop than the truth's (α 1.3e3 against 4.7e3) that fits the held-out files better
    # than the truth does (NRMSE 0.0040 against 0.0049; noise floor 0.0040): spring and loop trade within the
    # noise, so k3 is held to 10 % (measured 6.8 %)
    outcome = json.loads((tmp_path / "case0183" / "outcome.json").read_text())
    assert outcome["named_held_out"] <= outcome["truth_held_out"]
    measured("SDOF with a hardening spring and a loop that stands in for it alone: fitted k3 relative to the "
             "withheld value", abs(best.params["k3"] / case.truth["k3"] - 1), 0.1)


def test_a_damper_loop_standing_in_for_hardening_springs_leaves_the_springs_path_its_try(
        tmp_path, fmu_dir, measured):
    """Hardening cubic springs and a hysteresis loop of a random damper geometry under multisines recorded as the
    masses' displacements (a case of the damper campaign's draw, CasADi reference): the loop refitted alone
    stands in for the springs and ranks first, and the springs' refit ranks third, behind the mass offsets; the
    springs' sensitivity explains most of the nominal residual, so their path is tried after the loop's, finds
    the loop beside them, and the pair is named with the springs' stiffness recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 0, 2, "cubic_stiffness+hysteresis", "multisine", "damper")
    measured("damper with hardening springs and a loop standing in for them: fitted k_cs2 relative to the withheld "
             "value", abs(best.params["k_cs2"] / case.truth["k_cs2"] - 1), 0.1)


def test_a_pair_whose_joint_refit_failed_on_the_loop_path_is_refitted_again_on_the_springs_path(
        tmp_path, fmu_dir, measured):
    """Hardening cubic springs and a loop of a random damper geometry under multisines recorded as clamp force and
    one mass's acceleration (a case of the damper campaign's draw, CasADi reference): the loop refitted alone
    leads and stands in for the springs, and the pair's joint refit on the loop's path adds nothing to it; the
    springs' path refits the pair again from the springs' refit, names it and recovers the springs' stiffness."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 1, 99, "cubic_stiffness+hysteresis", "multisine", "damper")
    # measured 0.003: the springs set the resonance shift the records resolve well above the noise
    measured("damper with hardening springs and a loop whose pair refit on the loop's path added nothing: fitted "
             "k_cs2 relative to the withheld value", abs(best.params["k_cs2"] / case.truth["k_cs2"] - 1), 0.03)


def test_a_loop_beside_a_held_quadratic_damping_is_refitted_from_each_of_its_basins(tmp_path, fmu_dir, measured):
    """A loop and a strong quadratic damping under stepped sines recorded as displacement (a case of the campaign's
    draw, CasADi reference): refitted beside the damping held at its own refit, the loop descends from the best
    start of each of its basins, as its own refit does, and finds the pair's; c2 is recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 18, 153, "hysteresis+quadratic_damping", "stepped_sine")
    measured("SDOF with a loop and a strong quadratic damping on stepped sines: fitted c2 relative to the withheld "
             "value", abs(best.params["c2"] / case.truth["c2"] - 1), 0.05)


def test_a_weak_quadratic_damping_beside_a_strong_cubic_spring_is_named(tmp_path, fmu_dir, measured):
    """A hardening spring that jumps on a sweep and a quadratic damping far below 1 % of its candidate's range
    (the damping force a few % of the viscous one): the pair is named and c2 recovered."""
    rng = np.random.default_rng(SEED + 3)
    truth = {"k3": float(rng.uniform(4e7, 8e7)), "c2": float(rng.uniform(0.4, 1.0))}
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "cubic_stiffness+quadratic_damping", seed=40,
                                  periods=2, truth=truth, style=datasets.LabStyle("sweep", ("a",), record_s=6.0))
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert set(rep.chosen) == {"cubic_stiffness", "quadratic_damping"}, rep.sentence
    measured("SDOF with a strong cubic spring and a weak quadratic damping on sweeps: fitted c2 relative to the "
             "withheld value", abs(rep.ranking[0].params["c2"] / truth["c2"] - 1), 0.1)


def test_the_thesis_damper_with_hysteresis_and_softening_springs_is_named_as_both(tmp_path, fmu_dir, measured):
    """The thesis's damper model: Bouc-Wen hysteresis and softening cubic springs, a loop shape drawn at random
    (not the reference damper's) and the messenger's EI and damping too (not the FMU's start values), clamp
    sweeps recorded as displacement."""
    rng = np.random.default_rng(SEED + 2)
    truth = {"k_bw1": float(rng.uniform(400, 800)), "k_bw2": float(rng.uniform(700, 1200)),
             "a_bw": float(rng.uniform(0.1, 0.6)), "beta": float(rng.uniform(0.3, 1.2)),
             "gamma": float(rng.uniform(-0.2, 0.6)), "nu": float(rng.uniform(1.05, 2.0)),
             "D": float(rng.uniform(1.5e-4, 4e-4)),
             "k_cs1": -float(rng.uniform(2e6, 5e6)), "k_cs2": -float(rng.uniform(5e6, 1.2e7))}
    assert _starts_hold_none_of({k: truth[k] for k in ("a_bw", "beta", "gamma", "nu")}, candidates("damper")["hysteresis"])
    # the messenger's EI and Rayleigh damping drawn too: the nominal calibration starts from the FMU's values
    messenger = {"EI": float(rng.uniform(7.0, 14.0)), "alpha_pd": float(np.exp(rng.uniform(np.log(0.8), np.log(5.0)))),
                 "beta_pd": float(np.exp(rng.uniform(np.log(8e-5), np.log(5e-4))))}
    data = datasets.write_dataset(tmp_path / "data", datasets.DAMPER, "hysteresis+cubic_stiffness",
                                  style=datasets.LabStyle("sweep", motion="x"), truth=truth, base=messenger)
    rep = dg.diagnose("damper", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert set(rep.chosen) == {"hysteresis", "cubic_stiffness"}, rep.sentence
    measured("the thesis's damper (hysteresis + softening cubic springs, random loop shape): held-out shrink [%]",
             rep.ranking[0].shrink_pct, 80.0, at_least=True)
    assert Diagnosis.read(tmp_path / "out" / "report.json").verdict is Verdict.EXPLAINED


def test_a_weak_sharp_loop_softening_on_both_branches_is_named(tmp_path, fmu_dir, measured):
    """A weak hysteretic element (6 % of the stiffness) with a sharp loop (ν = 2.7) that softens on loading and
    unloading, under sweeps recorded by an accelerometer (a case of the campaign's draw, CasADi reference): its
    basin is reached only from a start of that sharpness with that branch shape and a weak share, so it is named
    and α recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 17, 132, "hysteresis", "sweep")
    measured("SDOF with a weak, sharp loop softening on both branches under sweeps: fitted alpha relative to the "
             "withheld value", abs(best.params["alpha"] / case.truth["alpha"] - 1), 0.01)


def test_a_very_weak_loop_is_named(tmp_path, fmu_dir, measured):
    """A very weak hysteretic element (0.2 % of the stiffness, its loop 9 times the noise) under sweeps recorded as
    displacement (a case of the campaign's draw at its drawn size, CasADi reference): refitted from the shares of
    3 % up, the loop ends nearly linear and several times as strong, and fits the held-out files worse than the
    truth; from the weakest share's starts it is named and fits the held-out files as well as the truth does. A
    loop this weak trades its strength against its sharpness within the noise (measured: α 17 % above the truth's
    at ν 1.1 against 1.7), so α is held to within half the truth's."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 18, 163, "hysteresis", "sweep", sized=True)
    assert case.truth["alpha"] < 0.005 * (case.truth["k"] + case.truth["alpha"])
    outcome = json.loads((tmp_path / "case0163" / "outcome.json").read_text())
    measured("SDOF with a very weak loop under sweeps: held-out NRMSE of the named model over the truth's",
             outcome["named_held_out"] / outcome["truth_held_out"], 1.05)  # measured 0.94
    measured("SDOF with a very weak loop under sweeps: fitted alpha relative to the withheld value",
             abs(best.params["alpha"] / case.truth["alpha"] - 1), 0.5)


def test_a_strong_loop_is_named_alone_not_beside_a_stand_in_spring(tmp_path, fmu_dir, measured):
    """The withheld-hysteresis SDOF dataset (the official benchmark's loop, α half the stiffness, hardening on
    loading; CasADi reference) diagnosed with the default settings: the loop's own refit stops short in the slow
    valley where its α and the linear k trade (α 19 % low), and the path that began at the cubic spring ends at
    spring + loop, where the loop holds the effect and the spring a few per cent of its shrink. The backward step
    refits the loop alone from that pair's values (tests each member's removal, not only the last-added's): the
    loop alone is named, at the noise, with α recovered."""
    data = datasets.write_dataset(tmp_path / "data", datasets.SDOF, "hysteresis")
    rep = dg.diagnose("sdof", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert rep.chosen_name == "hysteresis"
    best = rep.ranking[0]
    truth = json.loads((data / "truth.json").read_text())["params"]
    measured("SDOF benchmark loop (default dataset): held-out NRMSE of the loop alone over the noise floor",
             best.heldout_gap_after / rep.gap.noise_floor, 1.05)  # measured 0.99
    measured("SDOF benchmark loop (default dataset): fitted alpha relative to the withheld value",
             abs(best.params["alpha"] / truth["alpha"] - 1), 0.05)  # measured 0.009


def test_a_spring_a_free_shape_loop_matches_within_the_noise_is_named_as_the_spring(tmp_path, fmu_dir, measured):
    """A hardening spring under multisines recorded as displacement (a case of the check campaign's draw at its
    drawn size, CasADi reference): the spring's refit and a free-shape loop's both reach the noise, within ALIKE
    of each other (the loop stiffening as the spring does). No partner is tried; of the single effects the one
    with fewer parameters is named (selection.simpler_or_better, as between path ends), and k3 recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 19, 24, "cubic_stiffness", "multisine", sized=True)
    rep = Diagnosis.read(tmp_path / "case0024" / "diagnosis" / "report.json")
    after = {d.effect: d.heldout_gap_after for d in rep.ranking}
    assert after["hysteresis"] <= (1.0 + selection.ALIKE) * after["cubic_stiffness"]  # the data do not tell them
    md = (tmp_path / "case0024" / "diagnosis" / "report.md").read_text()
    # the report says why the spring is named when the loop's misfit is the lower one (measured: 0.05 % lower)
    why = "cubic_stiffness, with fewer parameters, is named"
    assert (why in md) == (after["hysteresis"] < after["cubic_stiffness"])
    measured("SDOF spring a loop matches within the noise: fitted k3 relative to the withheld value",
             abs(best.params["k3"] / case.truth["k3"] - 1), 0.1)  # measured 0.077



def test_a_pair_whose_stronger_member_alone_lands_just_above_the_noise_is_extended(tmp_path, fmu_dir, measured):
    """Quadratic damping with a weak hardening spring under stepped sines recorded as displacement (a case of the
    campaign's draw at its drawn size, CasADi reference): the damping's refit alone leaves a held-out misfit
    under the nominal's test (noise_factor x the floor should the noise grow) but above the forward selection's
    (extend_factor x it), so the spring is tried beside it; the pair is named and both strengths recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 18, 76, "cubic_stiffness+quadratic_damping",
                                      "stepped_sine", sized=True)
    rep = Diagnosis.read(tmp_path / "case0076" / "diagnosis" / "report.json")
    single = next(d.heldout_gap_after for d in rep.ranking if d.effect == "quadratic_damping")
    cfg, above = dg.DiagnoseConfig(), rep.gap.noise_floor_scaled
    assert selection.significant(single, above, cfg.extend_factor, cfg.combination_min_gap)
    assert not selection.significant(single, above, cfg.noise_factor, cfg.combination_min_gap)
    measured("SDOF pair whose damping alone lands just above the noise: fitted k3 relative to the withheld value",
             abs(best.params["k3"] / case.truth["k3"] - 1), 0.05)  # measured 0.014
    measured("SDOF pair whose damping alone lands just above the noise: fitted c2 relative to the withheld value",
             abs(best.params["c2"] / case.truth["c2"] - 1), 0.05)  # measured 0.0075

def test_an_effect_under_the_noise_threshold_is_told_from_noise_by_its_refit(tmp_path, fmu_dir, measured):
    """A weak quadratic damping under a sweep recorded as displacement (a case of the check campaign's draw,
    CasADi reference): the nominal's held-out misfit is within the noise threshold, but the damping's
    refit (refit_within_noise, the default) removes part of it on the held-out files, where a refit
    of noise alone carries nothing over; the damping is named and c2 recovered."""
    case, best = _campaign_case_named(tmp_path, fmu_dir, 19, 18, "quadratic_damping", "sweep")
    gap = Diagnosis.read(tmp_path / "case0018" / "diagnosis" / "report.json").gap
    assert gap.overall <= selection.noise_level(gap.noise_floor, dg.DiagnoseConfig().noise_factor,
                                                   dg.DiagnoseConfig().min_gap)  # under the nominal's own test
    measured("SDOF with a quadratic damping under the noise threshold: share of the nominal's held-out misfit its "
             "refit removes", gap.detection.cut, dg.DiagnoseConfig().min_detect_cut, at_least=True)
    measured("SDOF with a quadratic damping under the noise threshold: fitted c2 relative to the withheld value",
             abs(best.params["c2"] / case.truth["c2"] - 1), 0.05)


def test_noise_alone_refitted_below_the_noise_threshold_is_no_gap(tmp_path, fmu_dir, measured):
    """A null case of the check campaign's draw (nothing withheld; CasADi reference): within the noise threshold
    every single effect is refitted all the same (refit_within_noise, the default), and the best of them removes
    less of the held-out misfit than min_detect_cut (what a refit fits of the calibration files' noise does not
    carry over to the held-out files): no gap."""
    _campaign_case_named(tmp_path, fmu_dir, 19, 4, "none", "stepped_sine")
    gap = Diagnosis.read(tmp_path / "case0004" / "diagnosis" / "report.json").gap
    assert not gap.detection.detected
    measured("SDOF null case refitted below the noise threshold: share of the held-out misfit the best refit "
             "removes", gap.detection.cut, dg.DiagnoseConfig().min_detect_cut)


@pytest.mark.parametrize("drawn", [True, False], ids=["random loop and springs", "the design damper's"])
def test_a_damper_pair_on_stepped_sines_through_a_hardening_jump_is_named_as_both(tmp_path, fmu_dir, measured, drawn):
    """Hardening cubic springs beside a Bouc-Wen loop, on clamp stepped sines (the clamp's frequency gliding between
    16 dwells at constant velocity amplitude): at the held-out level the response dwells near a resonance where it
    has two steady states. A refit close to the truth can follow the other one there, and misfit a few seconds of
    the held-out file by far more than the noise; the prediction band (parameter sets the calibration files cannot
    tell apart from the fit) then holds one that follows the measured one. Drawn at random, or the design damper's
    loop and springs (datasets.DAMPER's withheld pair, whose fit has followed the other state for two steps, the
    band deciding its verdict)."""
    rng = np.random.default_rng(SEED + 5)
    truth = {"k_bw1": float(rng.uniform(400, 800)), "k_bw2": float(rng.uniform(700, 1200)),
             "a_bw": float(rng.uniform(0.1, 0.6)), "beta": float(rng.uniform(0.3, 1.2)),
             "gamma": float(rng.uniform(-0.2, 0.6)), "nu": float(rng.uniform(1.05, 2.0)),
             "D": float(rng.uniform(1.5e-4, 4e-4)),
             "k_cs1": float(rng.uniform(6e8, 1e9)), "k_cs2": float(rng.uniform(1.8e9, 3e9))} if drawn else None
    data = datasets.write_dataset(tmp_path / "data", datasets.DAMPER, "hysteresis+cubic_stiffness",
                                  style=datasets.LabStyle("stepped_sine", ("x1", "x2"), "x"), truth=truth)
    rep = dg.diagnose("damper", data, tmp_path / "out", dg.DiagnoseConfig(), fmu_dir, workers=2, progress=False)
    assert set(rep.chosen) == {"hysteresis", "cubic_stiffness"}, rep.sentence
    best = rep.ranking[0]
    truth = json.loads((data / "truth.json").read_text())["params"]
    for name in ("k_cs1", "k_cs2"):
        measured(f"stepped sines through a jump ({'drawn' if drawn else 'design'}): {name}'s relative error",
                 abs(best.params[name] / truth[name] - 1), 0.03)
    if best.heldout_gap_after > rep.explained_below:  # the fit follows the other steady state somewhere
        assert best.explains_in_band and best.prediction_band["heldout_nrmse"] <= rep.explained_below
        assert rep.confined_misfit["nrmse_rest"] <= rep.explained_below
