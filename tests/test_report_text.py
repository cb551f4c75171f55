"""The diagnosis report's text (pyfit.gap.report): how a candidate's listed starts are written in report.md, and
what a gap no candidate explains is told with."""
from pyfit.gap.diagnose import DiagnoseConfig
from pyfit.gap.report import LISTED_IN_FULL, POOR_LINEAR_NRMSE, not_explained_lines, starts_text
from pyfit.gap.systems import FAMILY, SDOF_EFFECTS, Scale


def test_a_few_starts_are_written_one_by_one():
    starts = [{"k3": 2.0e8}, {"k3": -2.0e8}]
    assert starts_text(starts) == "k3 = 2e+08; k3 = -2e+08"


def test_many_starts_are_summarised_by_parameter():
    """The SDOF loop's starts (more than LISTED_IN_FULL): ν's three values, the five hysteretic shares of
    k = 1e5 N/m, γ's range from the widest loop's to the largest listed γ, and where the full list is."""
    scale = Scale(1e-3, 0.2, 1e5, {})
    starts = SDOF_EFFECTS["hysteresis"].starts(scale)
    assert len(starts) > LISTED_IN_FULL
    text = starts_text(starts)
    assert "nu in {1, 2, 3}" in text
    assert "alpha in {300, 3000, 10000, 30000, 60000}" in text
    assert "gamma from 0.0025 to 1.5 (" in text
    assert text.endswith("(each start in report.json, `listed_starts`)")


def _unexplained(best_calibration_nrmse: float, shrinks: dict) -> list[str]:
    ranking = [{"effect": n, "shrink_pct": v, "heldout_gap_after": 0.5} for n, v in shrinks.items()]
    gap = {"noise_floor": 0.01, "worst_band_hz": (4.7, 6.1)}
    return not_explained_lines(ranking[0], ranking, gap, (best_calibration_nrmse, "level1"), 0.05, DiagnoseConfig(),
                               FAMILY["sdof"].outside)


def test_a_nominal_that_misfits_every_file_and_refits_that_remove_little_are_said_first():
    """Both conditions: the linear nominal misfits even its best calibration file beyond POOR_LINEAR_NRMSE and no
    refit removes the required shrink (DiagnoseConfig.min_shrink_pct): the first line says so, with the numbers,
    and what to try; either condition alone leaves the usual three lines."""
    required = DiagnoseConfig().min_shrink_pct
    lines = _unexplained(0.702, {"sensor_delay": 12.1, "hysteresis": 0.2})
    assert len(lines) == 4
    assert "(level1) at NRMSE 0.702" in lines[0] and "more than 12.1 %" in lines[0] and "Record a level" in lines[0]
    assert lines[1].startswith("best candidate sensor_delay")
    assert len(_unexplained(POOR_LINEAR_NRMSE * 0.99, {"sensor_delay": 12.1})) == 3
    assert len(_unexplained(0.702, {"cubic_stiffness": required + 1.0})) == 3


def test_the_effects_outside_the_candidates_named_are_the_family_s():
    """The hint of an unexplained gap names effects common in that family and how to add one of them: an SDOF
    joint's micro-slip, not the damper's messenger."""
    where = _unexplained(0.1, {"hysteresis": 60.0})[-1]
    assert "4.7-6.1 Hz" in where and "a bolted joint's micro-slip" in where and "messenger" not in where
    assert "--candidates FILE.toml" in where
    assert "messenger's frequency-dependent loss" in FAMILY["damper"].outside
