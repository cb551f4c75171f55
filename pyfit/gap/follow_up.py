"""A campaign case's follow-up: where its report is not decisive, the test the report proposes (pyfit.gap.proposal)
recorded on the case's truth (the same independent simulator and sensor chain: datasets.write_test), added to the
dataset, and the dataset diagnosed again. What the campaign tabulates of it: the verdicts before and after and
the test's length."""
from __future__ import annotations

import dataclasses
import pathlib
import shutil

from pyfit.gap import datasets
from pyfit.gap.diagnose import diagnose
from pyfit.gap.proposal import plan_test, write_plan
from pyfit.gap.result import Diagnosis

FOLLOW_UP_SEED = 7919  # added to a case's noise seed for the follow-up record's noise (another record, other noise)
TEST_NAME = "follow_up_test"


def run(folder: pathlib.Path, case, data: pathlib.Path, cfg, fmu_dir, described) -> dict | None:
    """The follow-up of the case diagnosed in folder/diagnosis from `data` (None when its report names no next
    test): the proposed test, its length [s] and predicted separation, and the verdict of the dataset with it,
    diagnosed in folder/follow_up/diagnosis; {"error": ...} when the follow-up fails (the first diagnosis stands)."""
    if Diagnosis.read(folder / "diagnosis" / "report.json").next_test is None:
        return None
    try:
        return _recorded_and_diagnosed(folder, case, data, cfg, fmu_dir, described)
    except Exception as exc:  # a follow-up that breaks is part of the case's outcome, not its end
        return {"error": f"{type(exc).__name__}: {exc}"}


def _recorded_and_diagnosed(folder, case, data, cfg, fmu_dir, described) -> dict:
    """The proposed test (plan_test: its signal) recorded on the truth into a copy of the dataset, diagnosed."""
    pr, (d, records, system) = plan_test(folder / "diagnosis", cfg, fmu_dir, described)
    write_plan(pr, d, records, system, folder / "diagnosis")
    more = folder / "follow_up" / "data"
    if more.exists():
        shutil.rmtree(more)
    shutil.copytree(data, more)
    family = datasets.FAMILIES[case.model]
    if case.band_hz:
        family = dataclasses.replace(family, band_hz=tuple(case.band_hz))
    clamp = bool(system.motion_inputs)
    datasets.write_test(more, family, pr.test.signal(clamp), pr.test.duration_s,
                        "stepped_sine" if pr.test.kind == "stepped sine" else "sweep", pr.test.level, TEST_NAME,
                        case.seed + FOLLOW_UP_SEED)
    after = diagnose(case.model, more, folder / "follow_up" / "diagnosis", cfg, fmu_dir, workers=1, progress=False,
                     nominal=described)
    return {"test": pr.test.sentence(), "test_s": pr.test.duration_s, "separation": pr.separation,
            "between": list(pr.between), "named": "+".join(sorted(after.chosen)) or "none",
            "verdict": after.verdict.value}


def summary(outcomes: list[dict], miss_cause) -> dict | None:
    """What the follow-ups of a campaign's outcomes did (None when the campaign ran none): how many cases proposed
    a test, top-1 over the effect cases and false alarms on the nulls before and after one follow-up, the cases
    missed for want of evidence (`miss_cause`: 'undetected' or 'undecided', campaign.split_misses) named right
    after it, and the proposed tests' mean length [s]."""
    ran = [o for o in outcomes if "follow_up" in o]
    if not ran:
        return None
    proposed = [o for o in ran if o["follow_up"] and "named" in o["follow_up"]]
    effects = [o for o in ran if o["withheld"] != "none"]
    nulls = [o for o in ran if o["withheld"] == "none"]

    def after(o):
        return (o.get("follow_up") or {}).get("named", o["named"])

    wanting = [o for o in effects if o["named"] != o["withheld"] and o.get("truth_held_out") is not None
               and miss_cause(o) in ("undetected", "undecided")]
    return {"cases": len(ran), "proposed": len(proposed), "effect_cases": len(effects),
            "top1_before": sum(o["named"] == o["withheld"] for o in effects),
            "top1_after": sum(after(o) == o["withheld"] for o in effects),
            "wanting": len(wanting), "wanting_proposed": sum(o in proposed for o in wanting),
            "wanting_right_after": sum(after(o) == o["withheld"] for o in wanting),
            "null_cases": len(nulls), "false_alarms_before": sum(o["named"] != "none" for o in nulls),
            "false_alarms_after": sum(after(o) != "none" for o in nulls),
            "failed": sum(bool(o["follow_up"]) and "error" in o["follow_up"] for o in ran),
            "mean_test_s": (sum(o["follow_up"]["test_s"] for o in proposed) / len(proposed)) if proposed else None}


def lines(s: dict | None) -> list[str]:
    """The follow-ups' table in a campaign summary ([] without follow-ups)."""
    if not s:
        return []

    def share(part, whole):
        return f"{part} of {whole}" + (f" ({100 * part / whole:.0f} %)" if whole else "")

    mean = "—" if s["mean_test_s"] is None else f"{s['mean_test_s']:.0f} s"
    return ["", "**One follow-up test**: each report that is not decisive proposes a test (pyfit.gap.proposal); it "
            "is recorded on the case's truth and the dataset with it diagnosed again", "",
            "| | before | after one follow-up |", "|---|---|---|",
            f"| named right (cases with a withheld effect) | {share(s['top1_before'], s['effect_cases'])} | "
            f"{share(s['top1_after'], s['effect_cases'])} |",
            f"| missed for want of evidence (undetected or undecided), named right | 0 of {s['wanting']} | "
            f"{share(s['wanting_right_after'], s['wanting'])} ({s['wanting_proposed']} proposed a test) |",
            f"| false alarms (null cases) | {share(s['false_alarms_before'], s['null_cases'])} | "
            f"{share(s['false_alarms_after'], s['null_cases'])} |",
            "", f"Tests proposed and run: {s['proposed']} of {s['cases']} cases (follow-ups that failed: "
            f"{s['failed']}); mean test length {mean}."]
