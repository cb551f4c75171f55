"""The rules that pick among candidate models on the held-out files (pyfit.gap.selection): the shrink, the score,
and when a model with more effects earns them, with the misfits of a campaign case (a hardening spring with
quadratic damping withheld, floor 0.0021: a single hysteresis loop 0.0207, the true pair 0.0054)."""
import pytest

from pyfit.gap import selection
from pyfit.gap.diagnose import DiagnoseConfig


def test_shrink_and_score():
    assert selection.shrink_pct(0.31, 0.0207, 0.0021) == pytest.approx(100 * (0.31 - 0.0207) / (0.31 - 0.0021))
    assert selection.shrink_pct(0.001, 0.0005, 0.002) == 0.0  # no gap above the reference: nothing to shrink
    # a pair pays 5 points for its second strength parameter: here the single loop scores a hair higher
    single = selection.score(0.3129, 0.0207, 0.0021, 1)
    pair = selection.score(0.3129, 0.0054, 0.0021, 2)
    assert single > pair and single - pair < 1.0


def test_a_model_explains_only_with_both_the_shrink_and_the_absolute_criterion():
    """selection.explains, the report's test and the campaign's for the truth: half the gap removed (the default
    min_shrink_pct) and the held-out misfit within the absolute criterion, each necessary."""
    below = selection.explained_below(0.005, 3.0, 0.02)  # 0.025
    assert selection.explains(50.0, 0.025, below, 50.0)
    assert not selection.explains(49.9, 0.010, below, 50.0)  # too little of the gap removed
    assert not selection.explains(99.0, 0.0251, below, 50.0)  # above the absolute criterion


def test_a_larger_model_is_kept_only_when_it_removes_half_the_misfit_left_above_the_floor():
    floor, cut = 0.0021, 0.5
    # the pair leaves 0.0033 above the floor, the single loop 0.0186: the pair is kept, in either order
    assert selection.adds_enough(0.0207, 0.0054, floor, cut)
    assert selection.simpler_or_better((1, 0.0207), (2, 0.0054), floor, cut) == 1
    assert selection.simpler_or_better((2, 0.0054), (1, 0.0207), floor, cut) == 0
    # a pair that removes less than half of it is not: the simpler model stays
    assert not selection.adds_enough(0.0207, 0.0120, floor, cut)
    assert selection.simpler_or_better((1, 0.0207), (2, 0.0120), floor, cut) == 0
    # exactly half is enough; of two as large, the lower misfit
    assert selection.adds_enough(0.0207, floor + 0.5 * (0.0207 - floor), floor, cut)
    assert selection.simpler_or_better((2, 0.0060), (2, 0.0054), floor, cut) == 1
    # a smaller model that leaves nothing above the floor cannot be improved on (the larger's lower misfit is noise)
    assert not selection.adds_enough(0.0050, 0.0045, 0.0052, cut)
    assert selection.simpler_or_better((1, 0.0050), (2, 0.0045), 0.0052, cut) == 0


def test_of_two_pairs_both_within_the_noise_the_one_with_fewer_parameters_is_kept():
    """A campaign case (cubic spring with quadratic damping withheld, floor should the noise grow 0.0049): the true
    pair (2 parameters) and a loop with quadratic damping (5) both leave 0.0052, within 1.2x that floor; the
    leaner one is kept whichever misfits a hair less. Above the noise the lower misfit still decides."""
    noise = selection.noise_level(0.0049, 1.2, 0.0)
    assert noise == pytest.approx(0.00588)
    assert selection.simpler_or_better((2, 0.00521), (2, 0.00518), 0.0049, 0.5, parameters=(2, 5), noise=noise) == 0
    assert selection.simpler_or_better((2, 0.00518), (2, 0.00521), 0.0049, 0.5, parameters=(5, 2), noise=noise) == 1
    assert selection.simpler_or_better((2, 0.0080), (2, 0.0070), 0.0049, 0.5, parameters=(2, 5), noise=noise) == 1


def test_of_two_single_effects_within_the_noise_a_linear_change_wins_on_its_misfit_alone():
    """SDOF check campaign case 24 (stockbridge diagnose --campaign 100 --campaign-seed 19; a hardening spring
    withheld, multisines; misfits as ratios to the floor should the noise grow): the spring (1 parameter) leaves
    0.9954 and a free-shape loop (4) 0.9949: the spring is kept. Damper campaign case 72 (seed 1, a loop withheld):
    of the loop (5) at 1.050 and the mass offsets (2, a change of the linear system that within the noise can take
    up the sensor chain's linear difference) at 1.059, the lower misfit decides."""
    noise = selection.noise_level(1.0, 1.2, 0.0)
    assert selection.simpler_or_better((1, 0.9949), (1, 0.9954), 1.0, 0.5, parameters=(4, 1), noise=noise) == 1
    assert selection.simpler_or_better((1, 1.050), (1, 1.059), 1.0, 0.5, parameters=(5, 2), noise=noise) == 1
    assert selection.simpler_or_better((1, 1.050), (1, 1.059), 1.0, 0.5, parameters=(5, 2), noise=noise,
                                       linear=True) == 0


def test_of_two_pairs_within_the_noise_but_far_apart_the_lower_misfit_is_kept():
    """Damper campaign case 4 (stockbridge diagnose --campaign 100 --model damper; Coulomb friction with a weak loop
    withheld; floor should the noise grow 0.0133, so both pairs lie under its 1.2x): the true pair (9 parameters)
    leaves 0.00648 on the held-out files, friction with a mass eccentricity (5) 0.00785, 21 % more. On the same
    files that difference is the data telling the models apart, so the lower misfit is kept in either order;
    within ALIKE (3 %) of it the leaner one still is."""
    noise = selection.noise_level(0.0133, 1.2, 0.0)
    assert max(0.00648, 0.00785) <= noise
    assert selection.simpler_or_better((2, 0.00648), (2, 0.00785), 0.0133, 0.5, parameters=(9, 5), noise=noise) == 0
    assert selection.simpler_or_better((2, 0.00785), (2, 0.00648), 0.0133, 0.5, parameters=(5, 9), noise=noise) == 1
    alike = 0.00648 * (1.0 + selection.ALIKE)
    assert selection.simpler_or_better((2, 0.00648), (2, alike), 0.0133, 0.5, parameters=(9, 5), noise=noise) == 1
    assert selection.simpler_or_better((2, 0.00648), (2, 1.001 * alike), 0.0133, 0.5, parameters=(9, 5),
                                       noise=noise) == 0


def test_a_model_is_extended_only_while_its_misfit_is_a_significant_gap():
    """The forward selection goes on by the nominal's test (noise_factor 1.2, min_gap 0.005): a single effect that
    leaves 2.5x a floor of 0.0019 (less than min_gap above it) is not extended; one that leaves 2.9x a floor of
    0.005 (0.0094 above it) is; a misfit 0.008 above a floor of 0.05 is within 1.2x the floor (campaign cases)."""
    assert not selection.significant(0.0047, 0.0019, 1.2, 0.005)
    assert selection.significant(0.0144, 0.005, 1.2, 0.005)
    assert not selection.significant(0.058, 0.05, 1.2, 0.005)
    assert selection.significant(0.0611, 0.05, 1.2, 0.005)


def test_a_pair_must_beat_what_refitting_on_alone_buys_the_model_it_extends():
    """Held-out misfits of two campaign cases (stockbridge diagnose --campaign 200 --campaign-seed 5). Case 154,
    hysteresis alone withheld (floor 0.0084): the loop leaves 0.0127 and every partner added to it 0.0101-0.0106,
    so the gain is the loop's own parameters refitted on, not the partner. Case 180, hysteresis with quadratic
    damping withheld (floor 0.0066): the loop leaves 0.0111, the true pair 0.0073, the partner that helps least
    0.0108."""
    floor, cut = 0.0084, 0.5
    control = selection.budget_control(0.0106, 4)
    assert control == 0.0106
    assert selection.adds_enough(0.0127, 0.0101, floor, cut)  # against the loop alone the pair would pass ...
    assert selection.simpler_or_better((1, 0.0127), (2, 0.0101), floor, cut, control) == 0  # ... not the control
    floor = 0.0066
    control = selection.budget_control(0.0108, 4)
    assert selection.simpler_or_better((1, 0.0111), (2, 0.0073), floor, cut, control) == 1
    # fewer than CONTROL_SIBLINGS partners tried: no control (one or two partners may all genuinely help)
    assert selection.budget_control(0.0106, 2) == float("inf")
    assert selection.simpler_or_better((1, 0.0127), (2, 0.0101), 0.0084, cut,
                                       selection.budget_control(0.0106, 2)) == 1


def test_the_best_leaner_partner_beside_a_model_is_refitted_jointly_too():
    """Calibration misfits of the refits beside a cubic spring held at its own refit (0.05688), case 75 of the SDOF
    check campaign (`stockbridge diagnose --campaign 100 --campaign-seed 19`; a cubic spring with quadratic damping
    withheld): the free-shape loop (five parameters with the spring's one) leaves 0.00824, the true partner (two)
    0.01595, a delay 0.05667, a friction 0.05688. The loop leads; the quadratic damping cuts 84 % of what the loop
    cuts and also gets the joint refit. Beside a loop every one-parameter partner is as lean: no other."""
    order = ["cubic + loop", "cubic + quadratic", "cubic + delay", "cubic + friction"]
    sizes = {"cubic + loop": 5, "cubic + quadratic": 2, "cubic + delay": 2, "cubic + friction": 3}
    misfit = {"cubic + loop": 0.00824, "cubic + quadratic": 0.01595, "cubic + delay": 0.05667,
              "cubic + friction": 0.05688}
    cuts = {n: 0.05688 - v for n, v in misfit.items()}
    assert selection.leaner_best(order, sizes, cuts) == ["cubic + quadratic"]
    assert selection.leaner_best(order[1:], sizes, cuts) == []
    assert selection.leaner_best([], {}, {}) == []


def test_a_leaner_partner_that_cuts_little_beside_a_model_is_not_refitted_jointly():
    """The diagnosis-time bench's pair (the design damper's cubic springs with its loop withheld): beside the
    springs held at their refit (0.1323), friction (five parameters) leaves 0.0908, the loop (nine) 0.1033, mass
    offsets (four) 0.1294, a delay (three) 0.1320. The offsets cut 7 % of what the friction cuts, the delay under
    1 %: neither is the leaner partner a joint refit is spent on (LEANER_MIN_SHARE, a quarter). At a share of 5 %
    the offsets would be."""
    order = ["cubic + friction", "cubic + loop", "cubic + offsets", "cubic + delay"]
    sizes = {"cubic + friction": 5, "cubic + loop": 9, "cubic + offsets": 4, "cubic + delay": 3}
    cuts = {n: 0.1323 - v for n, v in zip(order, (0.0908, 0.1033, 0.1294, 0.1320))}
    assert selection.leaner_best(order, sizes, cuts) == []
    assert selection.leaner_best(order, sizes, cuts, min_share=0.05) == ["cubic + offsets"]


def test_a_rough_loop_behind_a_leaner_partner_beside_a_model_is_refitted_jointly_too():
    """Calibration misfits of the refits beside the design damper's cubic springs held at their own refit, the
    diagnosis-time bench's pair (cubic springs with hysteresis withheld): friction (three parameters) leaves
    0.0908, the true partner, a loop without basins refitted from its one best start (seven), 0.1033, mass
    offsets (two) 0.1294, a delay (one) 0.1320. The loop is the best richer one among the rough; none beside a
    loop, and none among partners refitted from each basin."""
    order = ["cubic + friction", "cubic + loop", "cubic + offsets", "cubic + delay"]
    sizes = {"cubic + friction": 5, "cubic + loop": 9, "cubic + offsets": 4, "cubic + delay": 3}
    assert selection.richer_best(order, sizes, {"cubic + loop"}) == ["cubic + loop"]
    assert selection.richer_best(order[1:], sizes, {"cubic + loop"}) == []
    assert selection.richer_best(order, sizes, set()) == []
    assert selection.richer_best([], {}, set()) == []


def test_a_lean_pair_that_a_loop_pair_outdoes_is_refitted_on_before_the_step_is_judged():
    """Held-out misfits of one step's joint refits from the friction's refit, campaign seed 18 case 44 (Coulomb
    friction and quadratic damping withheld, sweeps read as displacement): friction with a free-shape loop leaves
    0.0125, with the true quadratic damping 0.0218 (its descent stalled), with a delay 0.0350 (the control). The
    quadratic pair is the rival refitted on; never the control (then the next lean pair is), and none when the
    loop pair is not better or when no pair holds a loop."""
    after = {"c + loop": 0.0125, "c + quadratic": 0.0218, "c + delay": 0.0350}
    joint = list(after)
    assert selection.lean_rival(joint, {"c + loop"}, after, "c + delay") == "c + quadratic"
    assert selection.lean_rival(joint, {"c + loop"}, after, "c + quadratic") == "c + delay"
    assert selection.lean_rival(joint[:2], {"c + loop"}, after, "c + quadratic") is None
    assert selection.lean_rival(joint, {"c + loop"}, {**after, "c + loop": 0.0300}, "c + delay") is None
    assert selection.lean_rival(joint, set(), after, "c + delay") is None
    assert selection.lean_rival(["c + loop"], {"c + loop"}, after, None) is None


def test_a_model_that_explains_the_data_with_nothing_a_candidate_explains_left_is_not_extended():
    """The screening repeated at the model so far (fractions of its calibration residual), with numbers of the
    diagnoses that found them. Lab sweeps of the family's hysteresis (accelerometer files, floor estimate 0.0036):
    the loop leaves 0.0091, above 1.2x the floor but within the absolute criterion (0.0236), and the best other
    candidate explains 0.13 % of what is left: nothing to add. Campaign seed 6, case 5 (Coulomb friction with
    quadratic damping withheld; absolute criterion 0.0243): friction alone leaves 0.0171 and the best candidate
    explains 0.99 % of its residual; the selection goes on (and names the pair). Case 28 (the same pair): the
    partner explains 0.28 %, but friction alone leaves 0.0447, above the criterion (0.0245): it goes on."""
    assert selection.explained_below(0.0036, 3.0, 0.02) == pytest.approx(0.0236)
    assert selection.nothing_to_add(0.0091, 0.0236, [0.0008, 0.0013, 0.0004, 0.0008], 0.005)
    assert not selection.nothing_to_add(0.0171, 0.0243, [0.0099, 0.0003, 0.0009, 0.0002], 0.005)
    assert not selection.nothing_to_add(0.0447, 0.0245, [0.0016, 0.0019, 0.0028, 0.0005], 0.005)
    assert selection.nothing_to_add(0.0091, 0.0236, [], 0.005)  # no other candidate: nothing can be added


def test_a_refit_finds_a_gap_below_the_noise_threshold_only_when_it_carries_over_to_the_held_out_files():
    """The held-out misfits of two check-campaign cases under the nominal's noise threshold, refitted with every
    single effect (refit_within_noise): a weak quadratic damping's refit takes 0.00889 to 0.00554
    (its linear values alone 0.0264), a null case's best refit 0.005084 to 0.005083 (its linear values alone
    0.005082: what it removes is the linear re-adjustment's, not the effect's)."""
    cut = DiagnoseConfig().min_detect_cut
    assert selection.detected_by_refit(min(0.00889, 0.0264), 0.00554, cut)
    assert not selection.detected_by_refit(min(0.005084, 0.005082), 0.005083, cut)
    # a damper null case whose hysteresis refit takes 0.005339 to 0.005199 (2.6 %: a free-shape loop takes up a
    # little of what the FMU and the reference simulator differ by) is no gap either
    assert not selection.detected_by_refit(0.005339, 0.005199, cut)
    edge = (1.0 - cut) * 0.01
    assert selection.detected_by_refit(0.01, edge, cut) and not selection.detected_by_refit(0.01, 1.001 * edge, cut)
    assert not selection.detected_by_refit(0.0, 0.0, cut)  # no misfit: nothing to find


def test_a_pairs_shares_of_the_shrink_do_not_depend_on_which_member_was_found_first():
    # damper campaign case 24: cubic springs alone worsen the held-out sweep (shrink -31.5 %), the loop alone
    # barely moves it (0.2 %), the pair removes 99.3 %. Each member's share is what it adds averaged over both
    # orders: springs (-31.5 + (99.3 - 0.2)) / 2, loop (0.2 + (99.3 + 31.5)) / 2
    shrink = {frozenset(["cubic_stiffness"]): -31.5, frozenset(["hysteresis"]): 0.2,
              frozenset(["cubic_stiffness", "hysteresis"]): 99.3}
    shares = selection.member_shares(["cubic_stiffness", "hysteresis"], shrink.get)
    assert shares == pytest.approx({"cubic_stiffness": 33.8, "hysteresis": 65.5}, abs=1e-9)
    assert selection.member_shares(["hysteresis", "cubic_stiffness"], shrink.get) == pytest.approx(shares)
    # three members, every sub-model refitted: the shares sum to the whole, and two members that add the same to
    # every model get the same share
    three = {frozenset(s): v for s, v in [("a", 10.0), ("b", 10.0), ("c", 40.0), ("ab", 30.0), ("ac", 60.0),
                                          ("bc", 60.0), ("abc", 90.0)]}
    shares = selection.member_shares(list("abc"), three.get)
    assert sum(shares.values()) == pytest.approx(90.0) and shares["a"] == pytest.approx(shares["b"])
    assert shares["c"] == pytest.approx((40.0 + 50.0 + 50.0 + 60.0 + 40.0 + 60.0) / 6)
    # a sub-model not refitted: each member what it adds to the ones before it, in the order given
    partial = {frozenset("ab"): 80.0, frozenset("a"): 50.0}
    assert selection.member_shares(list("ab"), partial.get) == pytest.approx({"a": 50.0, "b": 30.0})


def test_a_linear_change_that_removes_little_of_the_gap_starts_no_path_of_its_own():
    """The design damper's cubic springs withheld, lab-style accelerometer sweeps (held-out 0.8538, floor 0.0015): the
    springs' refit removes 99.7 % of the gap; the second-best single effect, a sensor delay (a change of the linear
    system), leaves 0.8451: 1.0 %. A path from it would add the springs and refit the first path's partners beside
    them again. A nonlinear effect below the first starts a path however little it removes alone (a weak loop whose
    partner is the first path's spring); a linear change that removes most of the gap does too."""
    cut = DiagnoseConfig().min_shrink_pct
    delay = selection.shrink_pct(0.8538, 0.8451, 0.0015)
    assert delay == pytest.approx(1.02, abs=0.01)
    assert not selection.worth_a_path(delay, True, cut)
    assert selection.worth_a_path(delay, False, cut)
    assert selection.worth_a_path(selection.shrink_pct(0.8538, 0.0040, 0.0015), True, cut)
    assert not selection.worth_a_path(cut - 0.1, True, cut) and selection.worth_a_path(cut, True, cut)
