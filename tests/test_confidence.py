"""The confidence a report states: Wilson intervals against their definition solved numerically, the campaign's
calibration table, the bin a report falls in, and the check of stated confidence against the hit rate."""
import json

import numpy as np
import pytest
import scipy.optimize

from pyfit.gap import confidence


@pytest.mark.parametrize("right, of", [(7, 10), (0, 5), (5, 5), (13, 40)])
def test_wilson_interval_solves_its_defining_equation(right, of):
    # the Wilson interval holds the p with |p_hat - p| <= z sqrt(p (1 - p) / n): its ends are the roots
    z, p_hat = 1.96, right / of
    gap = lambda p: (p_hat - p) ** 2 - z * z * p * (1 - p) / of  # noqa: E731
    low, high = confidence.wilson(right, of)
    expected_low = 0.0 if right == 0 else scipy.optimize.brentq(gap, 1e-12, p_hat - 1e-9, xtol=1e-14)
    expected_high = 1.0 if right == of else scipy.optimize.brentq(gap, p_hat + 1e-9, 1 - 1e-12, xtol=1e-14)
    assert low == pytest.approx(expected_low, abs=1e-9) and high == pytest.approx(expected_high, abs=1e-9)
    # the stated rate is the interval's centre where neither end is clipped at 0 or 1
    if 0 < right < of:
        assert confidence.wilson_centre(right, of) == pytest.approx((low + high) / 2, abs=1e-12)


def _outcome(withheld, named, shrink, verdict=None, stated=None):
    verdict = verdict or ("no significant gap" if named == "none" else f"gap explained by {named}")
    return {"withheld": withheld, "named": named, "top_shrink_pct": shrink, "verdict": verdict, "stated": stated}


OUTCOMES = ([_outcome("hysteresis", "hysteresis", 99.0)] * 7 + [_outcome("cubic_stiffness", "hysteresis", 97.0)] * 3
            + [_outcome("coulomb_friction", "quadratic_damping", 85.0)]
            + [_outcome("none", "none", None)] * 4 + [_outcome("coulomb_friction", "none", None)]
            + [_outcome("cubic_stiffness", "none", 60.0, "gap not explained by the candidate effects")])


def test_calibration_counts_each_shrink_bin_and_the_quiet_verdicts():
    cal = confidence.calibration_of(OUTCOMES, "stockbridge diagnose --campaign 17 --campaign-seed 4", 4)
    rows = {confidence.shrink_label(k): (r["named"], r["right"]) for k, r in enumerate(cal["by_shrink"])}
    assert rows == {"< 50": (0, 0), "50–80": (0, 0), "80–95": (1, 0), "≥ 95": (10, 7)}
    assert cal["no_gap"] == {"verdicts": 5, "right": 4} and cal["cases"] == 17


def test_a_report_states_the_hit_rate_of_its_bin_and_none_without_one():
    cal = confidence.calibration_of(OUTCOMES, "stockbridge diagnose --campaign 17 --campaign-seed 4", 4)
    named = confidence.stated("gap explained by hysteresis", "hysteresis", 96.5, cal)
    # the Wilson centre (7 + 1.96²/2) / (10 + 1.96²): a bin of ten reports states less than its raw 70 %
    assert named["rate"] == pytest.approx(8.9208 / 13.8416, abs=1e-6) and (named["right"], named["of"]) == (7, 10)
    assert (named["low"], named["high"]) == pytest.approx(confidence.wilson(7, 10))
    assert "7 of the 10 reports" in confidence.Confidence(**named).sentence()
    quiet = confidence.stated("no significant gap", None, None, cal)
    assert quiet["rate"] == pytest.approx((4 + 1.9208) / (5 + 3.8416), abs=1e-6)
    one = confidence.calibration_of([_outcome("hysteresis", "cubic_stiffness", 70.0)], "one case", 0)
    assert 0.2 < confidence.stated("gap explained by cubic_stiffness", "cubic_stiffness", 70.0, one)["rate"] < 0.5
    assert confidence.stated("gap explained by cubic_stiffness", "cubic_stiffness", 70.0, cal) is None  # no case
    assert confidence.stated("gap not explained by the candidate effects", None, 60.0, cal) is None
    assert confidence.stated("no significant gap", None, None, None) is None


def test_the_check_compares_stated_confidence_with_what_happened():
    outcomes = ([_outcome("hysteresis", "hysteresis", 99.0, stated=0.9)] * 3
                + [_outcome("cubic_stiffness", "hysteresis", 99.0, stated=0.9)]
                + [_outcome("none", "none", None, stated=0.6)] * 2 + [_outcome("cubic_stiffness", "none", None)])
    rows = confidence.check(outcomes)
    assert [r["reports"] for r in rows] == [0, 2, 4, 0]
    assert rows[2]["right"] == 3 and rows[2]["mean_stated"] == pytest.approx(0.9)
    assert rows[1]["right"] == 2 and rows[0]["mean_stated"] is None


def test_a_calibration_is_read_for_the_settings_it_was_made_with_only(tmp_path):
    path = tmp_path / "calibration.json"
    default, other = {"refit_within_noise": False, "min_gap": 0.005}, {"refit_within_noise": True, "min_gap": 0.005}
    confidence.write(confidence.calibration_of(OUTCOMES, "default settings", 4, default), path)
    confidence.write(confidence.calibration_of(OUTCOMES[:3], "other settings", 4, other), path)
    confidence.write(confidence.calibration_of(OUTCOMES[:5], "other settings, again", 4, other), path)  # replaces
    confidence.write(confidence.calibration_of(OUTCOMES[:7], "damper cases", 4, default, model="damper"), path)
    assert confidence.load(default, path=path)["cases"] == 17
    again = confidence.load(other, path=path)
    assert (again["source"], again["cases"]) == ("other settings, again", 5)
    # a calibration is of one system family: a damper's does not replace, nor stand for, the SDOF's
    assert confidence.load(default, "damper", path)["cases"] == 7 and confidence.load(other, "damper", path) is None
    assert confidence.load({"refit_within_noise": True, "min_gap": 0.01}, path=path) is None
    assert confidence.load({"refit_within_noise": True}, path=path) is None  # a setting it was not made with
    # where the files are (which are calibrated on, the bands) is no setting of the rule
    assert confidence.settings_of({"min_gap": 0.005, "calibration": ["a"], "bands_hz": None}) == {"min_gap": 0.005}
    # a setting added since: the calibrations made without it can no longer be read, and go
    confidence.write(confidence.calibration_of(OUTCOMES[:9], "a setting added", 4, {**other, "extend_factor": 1.1}),
                     path)
    assert [c["source"] for c in json.loads(path.read_text())["calibrations"]] == ["a setting added"]


def test_the_package_carries_a_calibration_of_the_default_settings_from_a_campaign():
    from dataclasses import asdict

    from pyfit.gap.diagnose import DiagnoseConfig

    cal = confidence.load(confidence.settings_of(asdict(DiagnoseConfig())))
    assert cal is not None and cal["source"].startswith("stockbridge diagnose --campaign ")
    assert sum(r["named"] for r in cal["by_shrink"]) + cal["no_gap"]["verdicts"] <= cal["cases"]
    assert np.all([0 <= r["right"] <= r["named"] for r in cal["by_shrink"]])
