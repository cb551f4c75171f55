"""Wall time of a full gap diagnosis on 2 workers (3 levels, every candidate effect refitted, default
budgets), hysteresis withheld: the SDOF (4 candidates, goal 10 minutes) and the damper (5 candidates,
goal 30 minutes), measured in one run.

    python bench/diagnose_time.py [--only sdof|damper]
"""
import argparse
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.gap.datasets import FAMILIES, write_dataset  # noqa: E402
from pyfit.gap.diagnose import diagnose  # noqa: E402
from pyfit.report.readme import BenchReport  # noqa: E402

GOAL_S = {"sdof": 600.0, "damper": 1800.0}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", choices=list(GOAL_S))
    ap.add_argument("--fmus", default="fmus")
    args = ap.parse_args()
    report = BenchReport("diagnose_time", pathlib.Path(__file__).resolve().parents[1])
    for model in [args.only] if args.only else list(GOAL_S):
        with tempfile.TemporaryDirectory() as tmp:
            data = write_dataset(pathlib.Path(tmp) / "data", FAMILIES[model], "hysteresis")
            t0 = time.perf_counter()
            rep = diagnose(model, data, pathlib.Path(tmp) / "out", fmu_dir=args.fmus, workers=2, progress=False)
            wall = time.perf_counter() - t0
        report.line(f"{model} diagnosis (hysteresis withheld, 3 levels, {len(rep['ranking'])} candidates refitted): "
              f"{wall:.0f} s; goal {GOAL_S[model]:.0f} s; ratio {wall / GOAL_S[model]:.2f} "
              f"(verdict: {rep['verdict']})")


if __name__ == "__main__":
    main()
