"""Speed-up of a batch of SDOF runs on 2 worker processes over 1, measured in one run.

    python bench/batch_speedup.py [--runs 96]
"""
import argparse
import pathlib
import tempfile
import time


from pyfit.runtime.batch import RunSpec, run_batch
from pyfit.build import EXAMPLES, build_fmu
from pyfit.report.generated import BenchReport


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=96)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fmu = str(build_fmu(EXAMPLES["SDOFBoucWen"], pathlib.Path(tmp), "SDOFBoucWen").fmu)
        specs = [RunSpec(fmu, 20.0, 1e-3, ("y", "z"), {"exc_rate": 3.0, "exc_amplitude": 20.0 + i}, tolerance=1e-9)
                 for i in range(args.runs)]
        times = {}
        for workers in (1, 2):
            run_batch(specs[:2], workers=workers, progress=False)  # warm-up (process start, extraction)
            t0 = time.perf_counter()
            res = run_batch(specs, workers=workers, progress=False)
            times[workers] = time.perf_counter() - t0
            assert all(r.ok for r in res)
    speedup = times[1] / times[2]
    BenchReport("batch_speedup", pathlib.Path(__file__).resolve().parents[1]).line(f"{args.runs} SDOF runs (20 s sweeps): 1 worker {times[1]:.2f} s, 2 workers {times[2]:.2f} s, "
          f"speed-up {speedup:.2f}x")


if __name__ == "__main__":
    main()
