"""One process, 1000 consecutive runs of one FMU (instantiate once, reset between runs): resident memory
after the first 100 runs and at the end, and the growth in between.

    python bench/fmu_soak.py [--runs 1000] [--model StockbridgeDamper]
"""
import argparse
import os
import pathlib
import tempfile
import time


from pyfit.build import EXAMPLES, build_fmu
from pyfit.runtime.fmu import FmuRunner
from pyfit.report.generated import BenchReport


def rss_mib() -> float:
    with open(f"/proc/{os.getpid()}/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--model", default="SDOFBoucWen", choices=sorted(EXAMPLES))
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        runner = FmuRunner(str(build_fmu(EXAMPLES[args.model], pathlib.Path(tmp), args.model).fmu))
        outputs = [v.name for v in runner.model_description.modelVariables if v.causality == "output"][:2]
        t0 = time.perf_counter()
        rss100 = None
        for i in range(args.runs):
            r = runner.simulate(0.2, 1e-3, outputs, {"exc_type": 1, "exc_f_start": 5.0 + i % 11})
            if not r.ok:
                raise SystemExit(f"run {i} failed: {r.message}")
            if i == 99:
                rss100 = rss_mib()
        rss_end = rss_mib()
        runner.close()
    growth = (rss_end - rss100) / rss100 * 100
    BenchReport("fmu_soak", pathlib.Path(__file__).resolve().parents[1]).line(f"{args.runs} runs of {args.model} in one process: {time.perf_counter() - t0:.1f} s, no crash; "
          f"RSS after 100 runs {rss100:.1f} MiB, after {args.runs} {rss_end:.1f} MiB, growth {growth:+.2f} % "
          f"")


if __name__ == "__main__":
    main()
