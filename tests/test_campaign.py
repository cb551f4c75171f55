"""The validation campaign (pyfit.gap.campaign): its draw and its summary; the short campaign itself (20 random
cases written by the CasADi reference and diagnosed on a Dask LocalCluster) is in the slow tier."""
import dataclasses
import json
import pathlib
import time

import numpy as np
import pytest

from pyfit.gap import campaign, confidence, datasets, sizing
from pyfit.gap import diagnose as dg
from pyfit.report import generated
from pyfit.gap.effect import Scale, with_derived
from pyfit.gap.effects import DAMPER_LOOP_STARTS, SDOF_LOOP_STARTS, candidates

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_the_draw_is_reproducible_and_spans_nulls_singles_and_pairs():
    a, b = campaign.draw(200, seed=3), campaign.draw(200, seed=3)
    assert a == b
    kinds = [0 if c.withheld == "none" else len(c.withheld.split("+")) for c in a]
    # shares 0.2 / 0.6 / 0.2: binomial standard deviation of a count of 200 is at most 7
    assert abs(kinds.count(0) - 40) < 4 * 7 and abs(kinds.count(1) - 120) < 4 * 7 and abs(kinds.count(2) - 40) < 4 * 7
    assert {c.excitation for c in a} == {"multisine", "sweep", "stepped_sine", "noise"}
    assert {c.outputs for c in a} == {("y",), ("a",)}
    # each withheld effect's size over the noise drawn log-uniformly over 0.5-20 x: the share below 1.25 x within
    # four binomial standard deviations of log(2.5) / log(40)
    sizes = [v for c in a if c.sizes for v in c.sizes.values()]
    assert all(set(c.sizes or ()) == set(c.withheld.split("+")) - {"none"} for c in a)
    assert all(campaign.sizing.SIZE_RANGE[0] <= v <= campaign.sizing.SIZE_RANGE[1] for v in sizes)
    share = np.log(1.25 / 0.5) / np.log(20 / 0.5)
    assert abs(sum(v < 1.25 for v in sizes) - share * len(sizes)) < 4 * np.sqrt(share * (1 - share) * len(sizes))
    # loop sharpness across the family, none at a start's ν (the candidate starts at whole values)
    nus = [c.truth["nu"] for c in a if "nu" in c.truth]
    assert min(nus) < 1.2 and max(nus) > 2.8 and all(1.0 <= nu <= 3.0 for nu in nus)
    assert all(abs(nu - s["nu"]) > 1e-6 for nu in nus for s in SDOF_LOOP_STARTS)


def test_drawn_dampers_span_the_catalogue_and_their_band_holds_two_resonances():
    """Damper cases: geometry within the catalogue ranges, the test band around the two lowest resonances of the
    reference model, every sensor set and clamp motion, no stepped sine unless asked for (its dwells need longer
    records than a campaign's), loop shapes away from the candidate's starts."""
    from pyfit.reference.models import damper_modes_hz

    cases = campaign.draw(60, seed=5, model="damper")
    assert cases == campaign.draw(60, seed=5, model="damper") and {c.model for c in cases} == {"damper"}
    for c in cases:
        g = c.base
        assert all(0.5 <= g[f"m{i}"] <= 4.0 and 0.1 <= g[f"L{i}"] <= 0.3 and 0.0 <= g[f"a{i}"] <= 0.05 for i in (1, 2))
        f = damper_modes_hz(g)
        assert c.band_hz[0] < f[0] < f[1] < c.band_hz[1] and 4.0 <= f[0] and f[1] <= 60.0
    assert {c.outputs for c in cases} == set(campaign.DAMPER_OUTPUTS)
    assert {c.motion for c in cases} == set(campaign.DAMPER_MOTIONS)
    assert {c.excitation for c in cases} == set(datasets.CLAMP_EXCITATIONS)
    starts = DAMPER_LOOP_STARTS  # the candidate's default start and its other shape starts
    loops = [c.truth for c in cases if "a_bw" in c.truth]
    assert loops and all(all(abs(lp["a_bw"] - s["a_bw"]) > 1e-6 and abs(lp["nu"] - s["nu"]) > 1e-6 for s in starts)
                         for lp in loops)

def test_a_campaign_under_one_excitation_draws_the_same_cases_under_it(tmp_path):
    """`--excitation` replaces each drawn case's excitation and nothing else (the cases a mixed campaign of the
    same seed draws, e.g. a damper's under a clamp stepped sine); its command line and headline say so; an
    excitation the family has not, a record too short for it, or a calibration from one excitation only, is refused
    by name."""
    mixed = campaign.draw(30, seed=2, model="damper")
    stepped = campaign.draw(30, seed=2, model="damper", excitation="stepped_sine")
    assert {c.excitation for c in stepped} == {"stepped_sine"} and "stepped_sine" not in {c.excitation for c in mixed}
    assert [dataclasses.replace(c, excitation="stepped_sine") for c in mixed] == stepped
    line = campaign.command(20, 0, "damper", excitation="stepped_sine", record_s=35.0)
    assert line == "stockbridge diagnose --campaign 20 --campaign-seed 0 --model damper --excitation stepped_sine " \
                   "--record-s 35"
    head = campaign.markdown({**campaign.summarise([]), "cases": 0, "seed": 0, "record_s": 35.0, "where": "here",
                              "wall_s": 60.0, "command": line, "excitation": "stepped_sine"}).splitlines()[0]
    assert "every case's excitation: stepped sine, records 35 s" in head
    with pytest.raises(ValueError, match="'impedance' unknown for --model damper; allowed: multisine, sweep, noise"):
        campaign.draw(3, model="damper", excitation="impedance")
    with pytest.raises(ValueError, match="--calibrate takes a campaign of every excitation"):
        campaign.run(3, tmp_path, excitation="sweep", calibrate=True)
    # a record too short for the excitation: refused before anything is written (16 dwells of a 3 s record would
    # be shorter than the 0.2 s glide into each)
    with pytest.raises(ValueError, match=r"--record-s\) 3 s: a stepped_sine record must be longer than 3.2 s"):
        campaign.run(3, tmp_path / "short", model="damper", excitation="stepped_sine", record_s=3.0)
    assert not (tmp_path / "short").exists()



@pytest.mark.parametrize("config, model", [(None, "sdof"), ("diagnose_nominal_threshold.toml", "sdof"),
                                           (None, "damper")])
def test_a_campaign_read_back_states_every_report_with_the_calibration_it_reads(tmp_path, config, model):
    """Outcomes stored by an earlier run hold the confidence that run's calibration gave; the summary states every
    report's with the calibration the package carries now for the campaign's family and settings (the SDOF's
    defaults; the nominal's threshold alone, a calibration of its own; the damper's defaults, another family's),
    as a report diagnosed in this run states it."""
    from dataclasses import asdict

    from pyfit.gap.diagnose import DiagnoseConfig, load_config

    path = None if config is None else str(ROOT / "configs" / config)
    package = confidence.load(confidence.settings_of(asdict(load_config(path) if path else DiagnoseConfig())), model)
    assert package is not None and package["model"] == model
    for c in campaign.draw(3, seed=0, model=model):
        named = c.withheld
        (tmp_path / f"case{c.index:04d}").mkdir()
        (tmp_path / f"case{c.index:04d}" / "outcome.json").write_text(json.dumps(
            {"named": named, "withheld": c.withheld, "enr": 20.0, "top_shrink_pct": None if named == "none" else 99.0,
             "verdict": "no significant gap" if named == "none" else f"gap explained by {named}", "stated": 0.01,
             "data_s": 1.0, "diagnose_s": 2.0, "case": asdict(c)}))
    campaign.run(3, tmp_path, seed=0, workers=1, progress=False, config=path, model=model)
    stored = json.loads((tmp_path / "summary.json").read_text())
    assert stored["resumed"] == 3 and stored["stated_from"]["source"] == package["source"]
    for o in stored["outcomes"]:
        chosen = None if o["named"] == "none" else o["named"]
        assert o["stated"] == confidence.stated(o["verdict"], chosen, o["top_shrink_pct"], package)["rate"] != 0.01


def test_a_folder_holding_another_campaign_s_cases_is_refused_not_read_as_this_one_s(tmp_path):
    """A finished case is read, not diagnosed again, so an outcome of another draw (another --campaign-seed,
    --model or --excitation given the same --out) would be summarised as this run's case: refused by name."""
    from dataclasses import asdict

    case = campaign.draw(1, seed=0)[0]
    (tmp_path / "case0000").mkdir()
    stored = tmp_path / "case0000" / "outcome.json"
    stored.write_text(json.dumps({"named": "none", "withheld": case.withheld, "case": asdict(case)}))
    other = campaign.draw(1, seed=1)[0]
    with pytest.raises(ValueError, match=r"case0000/outcome.json: a case of another campaign \(.*noise seed "
                                         rf"{case.seed}.*this run draws .*noise seed {other.seed}"):
        campaign.run(1, tmp_path, seed=1, progress=False)
    assert not (tmp_path / "summary.json").exists()


def test_no_drawn_loop_sits_at_a_start_of_the_candidate():
    scale = Scale(1e-3, 0.2, 1e5, {})
    effect = candidates("sdof")["hysteresis"]
    starts = [with_derived(s, effect.derived(scale))
              for s in [{p.name: p.range(scale)[1] for p in effect.params}] + effect.starts(scale)]
    loops = [c.truth for c in campaign.draw(200, seed=4) if "gamma" in c.truth]
    for loop in loops:
        assert all(abs(loop["gamma"] - s["gamma"]) > 1e-6 or abs(loop["delta"] - s["delta"]) > 1e-6 for s in starts)


def test_the_summary_counts_what_was_named_against_what_was_withheld():
    outcomes = [{"withheld": "hysteresis", "named": "hysteresis", "enr": 30.0, "top_shrink_pct": 99.0},
                {"withheld": "hysteresis", "named": "cubic_stiffness", "enr": 3.0, "top_shrink_pct": 60.0},
                {"withheld": "cubic_stiffness", "named": "none", "enr": 1.0, "top_shrink_pct": None},
                {"withheld": "none", "named": "none", "enr": 0.9, "top_shrink_pct": None},
                {"withheld": "none", "named": "coulomb_friction", "enr": 1.5, "top_shrink_pct": 55.0}]
    for o in outcomes:
        o.update(data_s=1.0, diagnose_s=2.0, stated=0.9 if o["top_shrink_pct"] else None,
                 verdict=f"gap explained by {o['named']}" if o["top_shrink_pct"] else "no significant gap")
    s = campaign.summarise(outcomes)
    assert s["confusion"]["hysteresis"] == {"coulomb_friction": 0, "cubic_stiffness": 1, "hysteresis": 1, "none": 0}
    assert s["top1"] == pytest.approx(1 / 3) and s["false_alarms"] == 1 and s["null_cases"] == 2
    assert [b["cases"] for b in s["by_enr"]] == [1, 1, 0, 0, 1]
    assert [(b["named"], b["right"]) for b in s["by_shrink"]] == [(0, 0), (2, 0), (0, 0), (1, 1)]
    assert s["no_gap"] == {"verdicts": 2, "right": 1}  # 'no significant gap' twice, once with nothing withheld
    assert [(c["reports"], c["right"]) for c in s["check"]] == [(0, 0), (0, 0), (3, 1), (0, 0)]


def test_the_summary_splits_singles_from_pairs_and_counts_a_pair_named_as_one_member():
    pairs = [("cubic_stiffness+hysteresis", "cubic_stiffness+hysteresis"), ("cubic_stiffness+hysteresis", "hysteresis"),
             ("coulomb_friction+hysteresis", "none"), ("hysteresis", "hysteresis"), ("hysteresis", "none")]
    outcomes = [{"withheld": w, "named": n, "enr": 10.0, "top_shrink_pct": None, "stated": None, "data_s": 1.0,
                 "diagnose_s": 1.0, "verdict": ""} for w, n in pairs]
    s = campaign.summarise(outcomes)
    assert s["by_size"] == [{"kind": "single effects", "cases": 2, "hits": 1, "one_member": 1},
                            {"kind": "pairs", "cases": 3, "hits": 1, "one_member": 1}]
    text = campaign.markdown({**s, "cases": 5, "seed": 0, "record_s": 6.0, "where": "here", "wall_s": 60.0,
                              "command": "c"})
    assert "| pairs | 3 | 33 % | 1 |" in text


def test_the_headline_states_the_size_range_the_summary_was_drawn_at(tmp_path):
    """The README's campaign line reads the sizes the effects were drawn at from the summary (sizing.SIZE_RANGE),
    not from a copy of its own."""
    outcomes = [{"withheld": w, "named": n, "enr": 10.0, "top_shrink_pct": None, "stated": None, "data_s": 1.0,
                 "diagnose_s": 1.0, "verdict": ""} for w, n in [("hysteresis", "hysteresis"), ("none", "none")]]
    text = campaign.markdown({**campaign.summarise(outcomes), "cases": 2, "seed": 0, "record_s": 6.0,
                              "where": "here", "wall_s": 60.0, "command": "c"})
    (tmp_path / "campaign.md").write_text(text, encoding="utf-8")
    lo, hi = sizing.SIZE_RANGE
    line = generated._campaign_headline(tmp_path)
    assert f"each at {lo:g}–{hi:g} × the sensor noise" in line and "in 100 %" in line
    # the damper campaign's line, from its own summary, points to its own page
    (tmp_path / "campaign_damper.md").write_text(text, encoding="utf-8")
    damper = generated._campaign_headline(tmp_path, "campaign_damper.md", "Damper campaign", "catalogue dampers",
                                          "geometry drawn", "damper-campaigns.md", first=False)
    assert damper.startswith("- **Damper campaign**: on 1 random catalogue dampers")
    assert "(../validation/damper-campaigns.md)" in damper


def test_the_summary_times_nulls_singles_and_pairs_apart():
    spent = [("none", 10.0, 5.0), ("none", 20.0, 10.0), ("hysteresis", 40.0, 20.0),
             ("cubic_stiffness+hysteresis", 100.0, 50.0), ("coulomb_friction+hysteresis", 300.0, 60.0),
             ("cubic_stiffness+quadratic_damping", 200.0, 40.0)]
    outcomes = [{"withheld": w, "named": "none", "enr": 10.0, "top_shrink_pct": None, "stated": None,
                 "data_s": d, "diagnose_s": t, "verdict": ""} for w, t, d in spent]
    s = campaign.summarise(outcomes)
    assert s["times"] == [{"kind": "null cases", "cases": 2, "median_s": 22.5, "longest_s": 30.0,
                           "diagnose_median_s": 15.0, "diagnose_longest_s": 20.0},
                          {"kind": "single effects", "cases": 1, "median_s": 60.0, "longest_s": 60.0,
                           "diagnose_median_s": 40.0, "diagnose_longest_s": 40.0},
                          {"kind": "pairs", "cases": 3, "median_s": 240.0, "longest_s": 360.0,
                           "diagnose_median_s": 200.0, "diagnose_longest_s": 300.0}]
    text = campaign.markdown({**s, "cases": 6, "seed": 0, "record_s": 6.0, "where": "here", "wall_s": 60.0,
                              "command": "c"})
    assert "| null cases | 2 | 22 | 30 | 15 | 20 |" in text and "| pairs | 3 | 240 | 360 | 200 | 300 |" in text
    assert "Left out" not in text


def test_the_time_per_case_leaves_out_cases_diagnosed_again_from_stored_fits():
    """A case whose outcome was removed to diagnose it again reads its stored fits: its time is not a diagnosis's
    from scratch, so neither the median nor the table holds it."""
    spent = [("hysteresis", 40.0, False), ("hysteresis", 4.0, True), ("cubic_stiffness", 60.0, False)]
    outcomes = [{"withheld": w, "named": "none", "enr": 10.0, "top_shrink_pct": None, "stated": None,
                 "data_s": 0.0, "diagnose_s": t, "verdict": "", "fits_reused": r} for w, t, r in spent]
    s = campaign.summarise(outcomes)
    assert s["fits_reused"] == 1 and s["median_case_s"] == 50.0
    assert s["times"][1] == {"kind": "single effects", "cases": 2, "median_s": 50.0, "longest_s": 60.0,
                             "diagnose_median_s": 50.0, "diagnose_longest_s": 60.0}
    text = campaign.markdown({**s, "cases": 3, "seed": 0, "record_s": 6.0, "where": "here", "wall_s": 60.0,
                              "command": "c"})
    assert "median 50 s per case diagnosed from scratch" in text
    assert "Left out: the 1 case diagnosed again from the fits an earlier run stored" in text


def test_the_summary_bins_cases_by_their_weakest_withheld_effect():
    drawn = [("cubic_stiffness+hysteresis", "hysteresis", {"cubic_stiffness": 1.5, "hysteresis": 40.0}),
             ("cubic_stiffness+hysteresis", "cubic_stiffness+hysteresis", {"cubic_stiffness": 12.0, "hysteresis": 8.0}),
             ("hysteresis", "hysteresis", {"hysteresis": 3.0}), ("hysteresis", "none", {"hysteresis": 1.2}),
             ("none", "none", {})]
    outcomes = [{"withheld": w, "named": n, "member_to_noise": m, "enr": 10.0, "top_shrink_pct": None,
                 "stated": None, "data_s": 1.0, "diagnose_s": 1.0, "verdict": ""} for w, n, m in drawn]
    s = campaign.summarise(outcomes)
    rows = {confidence.range_label(*b["size"]): b for b in s["by_weakest"]}
    assert rows["< 2"]["single"] == {"cases": 1, "hits": 0, "one_member": 0}
    assert rows["< 2"]["pair"] == {"cases": 1, "hits": 0, "one_member": 1}  # its weaker member sets the bin
    assert rows["2–5"]["single"]["hits"] == 1 and rows["5–10"]["pair"]["hits"] == 1
    assert sum(b["single"]["cases"] + b["pair"]["cases"] for b in s["by_weakest"]) == 4  # nulls left out
    text = campaign.markdown({**s, "cases": 5, "seed": 0, "record_s": 6.0, "where": "here", "wall_s": 60.0,
                              "command": "c"})
    assert "| < 2 | 1 | 0 % | 1 | 0 % | 1 |" in text and "| 5–10 | 0 | — | 1 | 100 % | 0 |" in text


def test_the_summary_tells_misses_the_data_cannot_decide_from_misses_of_the_search():
    # (withheld, named, verdict, named model's held-out NRMSE, the truth's held-out NRMSE, explanation threshold)
    drawn = [("hysteresis", "hysteresis", "gap explained by hysteresis", 0.010, 0.010, 0.012),
             ("cubic_stiffness+hysteresis", "hysteresis+quadratic_damping", "gap explained by", 0.0058, 0.0060, 0.012),
             ("hysteresis", "none", "gap not explained by the candidate effects", 0.044, 0.011, 0.012),  # search
             ("cubic_stiffness+hysteresis", "hysteresis", "gap explained by", 0.0105, 0.0078, 0.0050),  # truth above
             ("coulomb_friction", "none", "no significant gap", 0.0074, 0.0057, 0.012),  # below the detection limit
             ("none", "none", "no significant gap", 0.005, 0.006, 0.012),
             ("none", "none", "no significant gap", 0.004, 0.006, 0.012),
             ("none", "quadratic_damping", "gap explained by", 0.004, 0.009, 0.012)]  # a false alarm: not a null's
    outcomes = [{"withheld": w, "named": n, "verdict": v, "named_held_out": a, "truth_held_out": t,
                 "explained_below": e, "enr": 10.0, "top_shrink_pct": None, "stated": None, "data_s": 1.0,
                 "diagnose_s": 1.0} for w, n, v, a, t, e in drawn]
    # the truth fits better than 'none' but removes a tenth of the gap: the report's test would not name it either
    outcomes.append({**outcomes[2], "withheld": "quadratic_damping", "named_held_out": 0.0053, "truth_held_out": 0.005,
                     "truth_shrink_pct": 10.0, "min_shrink_pct": 50.0})
    s = campaign.summarise(outcomes)
    assert s["misses"] == {"judged": 5, "undetected": 1, "undecided": 1, "unnamed": 2, "search": 1,
                           "handicap": pytest.approx(1.35)}  # median of 1.2 and 1.5
    assert s["top1"] == pytest.approx(1 / 6) and s["top1_decided"] == pytest.approx(1 / 2) and s["decided"] == 2
    text = campaign.markdown({**s, "cases": 9, "seed": 0, "record_s": 6.0, "where": "here", "wall_s": 60.0,
                              "command": "c"})
    assert "(the data do not favour the truth) | 1 |" in text
    assert "on the 2 cases detected and decided by the data: 50 %." in text
    assert "misfit above the explanation threshold) | 2 |" in text
    assert "(a miss of the search or of the selection) | 1 |" in text
    assert "1.35 × the calibrated nominal's" in text
    # resumed into a folder whose earlier runs took 90 min: this run's 6 min and theirs bound a full run
    text = campaign.markdown({**s, "cases": 9, "seed": 0, "record_s": 6.0, "where": "here", "wall_s": 360.0,
                              "resumed": 5, "earlier_wall_s": 5400.0, "command": "c"})
    assert ("wall 6.0 min for the 4 cases this run diagnosed (5 read from an earlier run, whose runs took 90.0 min: "
            "a full run takes at most 96.0 min)") in text


def test_the_summary_tabulates_the_follow_ups_verdicts_before_and_after():
    """A campaign run with --follow-up: top-1 and false alarms before and after one follow-up test, the misses for
    want of evidence (undetected, undecided) named right after it, the tests' mean length; a case without a
    proposal keeps its verdict."""
    def outcome(withheld, named, verdict, named_held, truth_held, after=None, test_s=20.0):
        follow = {"named": after, "verdict": "gap explained", "test_s": test_s} if after else None
        return {"withheld": withheld, "named": named, "verdict": verdict, "named_held_out": named_held,
                "truth_held_out": truth_held, "explained_below": 0.012, "enr": 5.0, "top_shrink_pct": None,
                "stated": None, "data_s": 1.0, "diagnose_s": 1.0, "follow_up": follow}
    outcomes = [outcome("cubic_stiffness", "none", "no significant gap", 0.007, 0.006, "cubic_stiffness", 10.0),
                outcome("hysteresis", "cubic_stiffness", "gap explained", 0.005, 0.006, "hysteresis", 30.0),
                outcome("coulomb_friction", "none", "no significant gap", 0.007, 0.006, "none", 20.0),  # not found
                outcome("quadratic_damping", "quadratic_damping", "gap explained", 0.005, 0.005),  # decisive
                outcome("none", "none", "no significant gap", 0.005, 0.006, "quadratic_damping", 40.0),  # an alarm
                {**outcome("hysteresis", "none", "no significant gap", 0.007, 0.006), "follow_up": {"error": "X"}}]
    s = campaign.summarise(outcomes)["follow_up"]
    # a follow-up that failed keeps its case's first verdict (and counts as a miss for want of evidence not followed)
    assert s == {"cases": 6, "proposed": 4, "effect_cases": 5, "top1_before": 1, "top1_after": 3, "wanting": 4,
                 "wanting_proposed": 3, "wanting_right_after": 2, "null_cases": 1, "false_alarms_before": 0,
                 "false_alarms_after": 1, "failed": 1, "mean_test_s": 25.0}
    text = campaign.markdown({**campaign.summarise(outcomes), "cases": 6, "seed": 0, "record_s": 6.0,
                              "where": "here", "wall_s": 60.0, "command": "c"})
    assert "| named right (cases with a withheld effect) | 1 of 5 (20 %) | 3 of 5 (60 %) |" in text
    assert "named right | 0 of 4 | 2 of 4 (50 %) (3 proposed a test) |" in text
    assert "Tests proposed and run: 4 of 6 cases (follow-ups that failed: 1); mean test length 25 s." in text
    without = [{k: v for k, v in o.items() if k != "follow_up"} for o in outcomes]  # a campaign without them
    assert campaign.summarise(without)["follow_up"] is None


def test_a_resumed_or_extended_campaign_states_the_earlier_runs_wall_time():
    """campaign.wall_of_runs: a run that read cases from an earlier run states that run's wall time beside its own
    when the earlier run covered the same cases or exactly the ones read (a campaign of 20 cases extended to 40 of
    the same draw), and its own alone when the earlier summary is of another set of cases."""
    this = {"wall_s": 600.0, "resumed": 20, "where": "here"}
    extended = campaign.wall_of_runs(this, 40, {"cases": 20, "wall_s": 2400.0, "resumed": 0, "where": "there"})
    assert extended == {**this, "earlier_wall_s": 2400.0}
    # a rerun of 40 whose earlier run (of 40, itself resumed from a run of 20) lost 20 outcomes: both runs before
    rerun = campaign.wall_of_runs(this, 40, {"cases": 40, "wall_s": 900.0, "earlier_wall_s": 2400.0})
    assert rerun["earlier_wall_s"] == 3300.0 and rerun["wall_s"] == 600.0
    # every case read: the earlier run's own statement
    assert campaign.wall_of_runs({**this, "resumed": 40}, 40, {"cases": 40, "wall_s": 900.0, "resumed": 20,
                                                                "where": "there", "earlier_wall_s": 2400.0}) == {
        "wall_s": 900.0, "resumed": 20, "where": "there", "earlier_wall_s": 2400.0}
    # an earlier summary of 30 cases, 20 of them read now: its wall time is not theirs
    assert campaign.wall_of_runs(this, 40, {"cases": 30, "wall_s": 2400.0}) == this
    assert campaign.wall_of_runs(this, 40, None) == this


def test_the_truth_s_own_test_is_the_report_s(tmp_path):
    """campaign.truth_test: the truth's held-out shrink of the gap against the report's reference (the truth's own
    misfit when lower: the report takes the least of every model's)."""
    cfg = dg.DiagnoseConfig()
    assert campaign.truth_test(0.0053, 0.0048, 0.0050, cfg) == {"truth_shrink_pct": pytest.approx(60.0),
                                                                 "min_shrink_pct": cfg.min_shrink_pct}
    assert campaign.truth_test(0.0053, 0.0048, 0.0040, cfg)["truth_shrink_pct"] == pytest.approx(100.0)


@pytest.mark.slow
def test_a_short_campaign_on_a_local_dask_cluster(tmp_path, fmu_dir, measured):
    summary = campaign.run(20, tmp_path, fmu_dir, seed=0, workers=2, progress=False)
    # effects drawn from half the noise to twenty times it: many of them the data cannot decide, so the guard is on
    # the cases they do (the 200-case campaign's: 88 % of 94, docs/validation/campaigns.md; 3 binomial standard deviations
    # below it for the ten or so of 20 cases)
    measured("short campaign (20 random SDOF cases): top-1 accuracy on the cases detected and decided by the data",
             summary["top1_decided"], 0.55, at_least=True)
    measured("short campaign: false alarms on the null cases", summary["false_alarms"], 0)
    assert summary["errors"] == 0
    (tmp_path / "case0003" / "outcome.json").unlink()  # as if interrupted before its end
    t0 = time.perf_counter()
    again = campaign.run(20, tmp_path, fmu_dir, seed=0, workers=2, progress=False)  # resumes: one case redone
    assert time.perf_counter() - t0 < 0.5 * summary["wall_s"]
    assert summary["resumed"] == 0 and again["resumed"] == 19 and again["wall_s"] < 0.5 * summary["wall_s"]
    assert again["earlier_wall_s"] == summary["wall_s"]  # a full run's wall time at most the two runs'
    # the redone case read the fits its first run stored: its time is left out of the time per case
    assert summary["fits_reused"] == 0 and again["fits_reused"] == 1
    assert sum(t["cases"] for t in again["times"]) == 19 == sum(t["cases"] for t in summary["times"]) - 1
    assert "Left out: the 1 case diagnosed again from the fits" in (tmp_path / "summary.md").read_text()
    assert (f"(19 read from an earlier run, whose runs took {summary['wall_s'] / 60:.1f} min: a full run takes at "
            f"most {(summary['wall_s'] + again['wall_s']) / 60:.1f} min)") in (tmp_path / "summary.md").read_text()
    whole = campaign.run(20, tmp_path, fmu_dir, seed=0, workers=2, progress=False)  # every case stored: summarised
    assert whole["wall_s"] == again["wall_s"] and whole["resumed"] == 19  # with the wall time of their run
    misses = summary["misses"]  # every effect case's miss judged against its truth
    assert misses["judged"] == round(summary["effect_cases"] * (1 - summary["top1"]))
    # the calibrated nominal of a null case has the truth's structure: the truth at its true parameters fits the
    # held-out files no better (measured 1.1-1.5 x on the 200-case campaign's nulls)
    measured("short campaign: truth's held-out misfit over the calibrated nominal's on the nulls (median)",
             misses["handicap"], 2.0)
    assert misses["handicap"] >= 0.95
    assert json.loads((tmp_path / "summary.json").read_text())["cases"] == 20
    assert np.isfinite(summary["median_case_s"])
