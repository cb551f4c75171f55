"""Wall time of the Bouc-Wen benchmark fit (configs/boucwen_benchmark.toml, one seed, as `scripts/fit.py` runs
it on this machine's cores), per stage, measured in one run, with the validation result it must keep.
Goals: <= 60 s and <= -127 dB RMS error on the official multisine.

    python bench/fit_time.py [--seed 0]
"""
import argparse
import pathlib
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]

from pyfit.fit.batch import fit_batch
from pyfit.report.generated import BenchReport

CONFIG = ROOT / "configs" / "boucwen_benchmark.toml"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--fmus", default=str(ROOT / "fmus"))
    args = ap.parse_args()
    report = BenchReport("fit_time", ROOT)
    with tempfile.TemporaryDirectory() as tmp:
        (r,) = fit_batch([CONFIG], 1, pathlib.Path(tmp), pathlib.Path(args.fmus), progress=False, first_seed=args.seed)
    if "error" in r:
        raise SystemExit(f"the fit failed: {r['error']}")
    stages = ", ".join(f"{k} {v:.1f} s" for k, v in r["stage_s"].items())
    db = r["benchmark_rms_db"]["multisine"]
    report.line(f"Bouc-Wen benchmark fit ({CONFIG.name}, seed {args.seed}, {r['true_evaluations']} FMU runs): "
                f"{r['wall_s']:.1f} s ({stages}); official multisine RMS error {db:.1f} dB")


if __name__ == "__main__":
    main()
