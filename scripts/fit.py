"""Batch fitting: every config x repeat, in parallel, resumable.

    python scripts/fit.py [CONFIG.toml ...] [--repeats N] [--workers N] [--scheduler ADDRESS] [--out DIR]

Without a config it runs the small default study configs/quickstart.toml. A rerun with the same --out
skips the runs that have a result.json. Writes <out>/<config>/seed_<k>/result.json and figures, and
<out>/summary.md.
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.io.nominal import load_nominal  # noqa: E402
from pyfit.io.schema import ConfigError  # noqa: E402
from pyfit.fit.batch import describe_run, fit_batch  # noqa: E402

DEFAULT = pathlib.Path(__file__).resolve().parents[1] / "configs" / "quickstart.toml"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("configs", nargs="*", help=f"fit study files (default: {DEFAULT.name})")
    ap.add_argument("--repeats", type=int, default=1, help="seeds per config")
    ap.add_argument("--workers", type=int, help="local worker processes (default: one per core)")
    ap.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    ap.add_argument("--out", default="results/fit", help="output folder")
    ap.add_argument("--fmus", default="fmus", help="folder with the FMUs (built if missing)")
    ap.add_argument("--nominal", help="TOML describing your system ([nominal] fixed and free parameters)")
    args = ap.parse_args()
    configs = [pathlib.Path(c) for c in (args.configs or [DEFAULT])]
    try:
        results = fit_batch(configs, args.repeats, pathlib.Path(args.out), pathlib.Path(args.fmus), args.workers,
                            args.scheduler, nominal=load_nominal(args.nominal) if args.nominal else None)
    except (ConfigError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    failed = [r for r in results if "error" in r]
    for r in results:
        print(describe_run(r), file=sys.stderr if "error" in r else sys.stdout)
    print(f"{len(results) - len(failed)} of {len(results)} fits done; summary: {args.out}/summary.md")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
