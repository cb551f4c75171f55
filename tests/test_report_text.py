"""The diagnosis report's text (pyfit.gap.report): how a candidate's listed starts are written in report.md."""
from pyfit.gap.report import LISTED_IN_FULL, starts_text
from pyfit.gap.systems import SDOF_EFFECTS, Scale


def test_a_few_starts_are_written_one_by_one():
    starts = [{"k3": 2.0e8}, {"k3": -2.0e8}]
    assert starts_text(starts) == "k3 = 2e+08; k3 = -2e+08"


def test_many_starts_are_summarised_by_parameter():
    """The SDOF loop's starts (more than LISTED_IN_FULL): ν's three values, the four hysteretic shares of
    k = 1e5 N/m, γ's range from the widest loop's to the largest listed γ, and where the full list is."""
    scale = Scale(1e-3, 0.2, 1e5, {})
    starts = SDOF_EFFECTS["hysteresis"].starts(scale)
    assert len(starts) > LISTED_IN_FULL
    text = starts_text(starts)
    assert "nu in {1, 2, 3}" in text
    assert "alpha in {3000, 10000, 30000, 60000}" in text
    assert "gamma from 0.0025 to 1.5 (" in text
    assert text.endswith("(each start in report.json, `listed_starts`)")
