"""What starting a local process pool costs with the workers forked from a server that imported the task's
module (pyfit.runtime.batch.map_tasks) against one whose workers import it each, measured in one run.

Each measurement runs in a fresh interpreter (a process's forkserver reads its preload list when it starts):
two workers map a function of pyfit.gap.diagnose over four items, three pools in a row.

    python bench/pool_start.py [--repeats 3]
"""
import argparse
import pathlib
import subprocess
import sys

from pyfit.report.generated import BenchReport

ROOT = pathlib.Path(__file__).resolve().parents[1]
POOLS = """
import concurrent.futures as cf, multiprocessing, time
from pyfit.gap.search import stem as _stem
from pyfit.runtime.batch import map_tasks
items = ["a + b", "c", "d + e", "f"]
t0 = time.perf_counter()
for _ in range(3):
    if PRELOADED:
        map_tasks(_stem, items, workers=2, progress=False)
    else:
        with cf.ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("forkserver")) as pool:
            list(pool.map(_stem, items))
print(time.perf_counter() - t0)
"""


def _seconds(preloaded: bool) -> float:
    out = subprocess.run([sys.executable, "-c", f"PRELOADED = {preloaded}\n" + POOLS], capture_output=True, text=True,
                         check=True)
    return float(out.stdout.split()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    each = {flag: min(_seconds(flag) for _ in range(args.repeats)) for flag in (False, True)}
    BenchReport("pool_start", ROOT).line(
        f"three 2-worker pools mapping a pyfit.gap.diagnose function: {each[True]:.2f} s with the module preloaded "
        f"in the server, {each[False]:.2f} s with each worker importing it ({each[False] / each[True]:.1f} x); "
        f"fastest of {args.repeats}")


if __name__ == "__main__":
    main()
