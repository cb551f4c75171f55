"""A campaign case's follow-up (pyfit.gap.follow_up) on cases the data left undecided: two cases of the 200-case
calibration campaign (seed 18, drawn at random across the family; the truths integrated by the CasADi reference,
independent of the FMUs) whose first report is not decisive — a cubic spring the diagnosis did not detect, and a
hysteresis loop it named a cubic spring — are diagnosed again with the test their report proposes recorded on the
truth, and named right. Slow: `pytest -m slow`."""
import json

import pytest

from pyfit.gap import campaign
from pyfit.gap.diagnose import DiagnoseConfig

pytestmark = pytest.mark.slow

SEED = 18  # the calibration campaign's draw


@pytest.mark.parametrize("index", [38, 57])
def test_a_case_the_data_left_undecided_is_named_after_one_follow_up(tmp_path, fmu_dir, index, measured):
    case = campaign.draw(index + 1, SEED)[index]
    outcome = campaign.run_case(campaign.CaseJob(case, str(tmp_path), str(fmu_dir), campaign.RECORD_S,
                                                 DiagnoseConfig(), follow_up=True))
    follow = outcome["follow_up"]
    assert outcome["named"] != case.withheld and follow is not None, outcome["named"]
    assert follow["named"] == case.withheld, (follow, outcome["verdict"])
    folder = tmp_path / f"case{index:04d}"
    assert (folder / "follow_up" / "data" / "follow_up_test.csv").is_file()
    assert json.loads((folder / "outcome.json").read_text())["follow_up"] == follow
    measured(f"campaign seed 18 case {index} ({case.withheld} withheld, first named {outcome['named']}): the proposed "
             f"test's predicted separation [x noise] ({follow['test']})", follow["separation"], 1.0, at_least=True)
