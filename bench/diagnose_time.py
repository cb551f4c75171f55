"""Wall time of a full SDOF gap diagnosis (3 levels, 4 candidate effects, default budgets) on 2 workers,
against the goal of 10 minutes, measured in one run. The damper diagnosis is not built yet (issue #5).

    python bench/diagnose_time.py [--effect hysteresis]
"""
import argparse
import pathlib
import sys
import tempfile
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.gap.datasets import SDOF_WITHHELD, write_sdof_dataset  # noqa: E402
from pyfit.gap.diagnose import diagnose  # noqa: E402

GOAL_S = 600.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--effect", default="hysteresis", choices=list(SDOF_WITHHELD))
    ap.add_argument("--fmus", default="fmus")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        data = write_sdof_dataset(pathlib.Path(tmp) / "data", args.effect)
        t0 = time.perf_counter()
        rep = diagnose("sdof", data, pathlib.Path(tmp) / "out", fmu_dir=args.fmus, workers=2, progress=False)
        wall = time.perf_counter() - t0
    print(f"SDOF diagnosis ({args.effect} withheld, 3 levels, {len(rep['ranking'])} candidates refitted): "
          f"{wall:.0f} s; goal {GOAL_S:.0f} s; ratio {wall / GOAL_S:.2f} (verdict: {rep['verdict']})")
    print("damper diagnosis: not built yet (issue #5)")


if __name__ == "__main__":
    main()
