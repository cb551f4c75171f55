"""stockbridge fit: every config x seed, in parallel, resumable."""
from __future__ import annotations

import pathlib
import sys

from pyfit.catalog import CONFIGS
from pyfit.cli import count

DEFAULT = CONFIGS / "quickstart.toml"
EXAMPLE = """examples:
  stockbridge fit                                   # the bundled quick study (SDOF Bouc-Wen, about a minute)
  stockbridge fit my_study.toml --repeats 3 --out results/my_study
  stockbridge fit study.toml --scheduler tcp://10.0.0.5:8786    # on a Dask cluster

A rerun with the same --out skips the runs that have a result.json. Writes <out>/<config>/seed_<k>/result.json
with figures, and <out>/summary.md."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge fit`."""
    ap.add_argument("configs", nargs="*", help=f"fit study files (default: the bundled {DEFAULT.name})")
    ap.add_argument("--repeats", type=count, default=1, help="seeds per config")
    ap.add_argument("--workers", type=count, help="local worker processes (default: one per core)")
    ap.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    ap.add_argument("--out", default="results/fit", help="output folder")
    ap.add_argument("--fmus", default="fmus", help="folder with the FMUs (built if missing)")
    ap.add_argument("--nominal", help="TOML describing your system ([nominal] fixed and free parameters)")


def run(args, ap) -> int:
    """Fit every study, print one line per run and the summary's path."""
    from pyfit.fit.batch import describe_run, fit_batch
    from pyfit.io.nominal import load_nominal
    from pyfit.io.schema import ConfigError

    configs = [pathlib.Path(c) for c in (args.configs or [DEFAULT])]
    try:
        results = fit_batch(configs, args.repeats, pathlib.Path(args.out), pathlib.Path(args.fmus), args.workers,
                            args.scheduler, nominal=load_nominal(args.nominal) if args.nominal else None)
    except (ConfigError, OSError) as exc:  # OSError: a file not found, a scheduler not answering
        print(f"error: {exc}", file=sys.stderr)
        return 2
    failed = [r for r in results if "error" in r]
    for r in results:
        print(describe_run(r), file=sys.stderr if "error" in r else sys.stdout)
    print(f"{len(results) - len(failed)} of {len(results)} fits done; summary: {args.out}/summary.md")
    return 1 if failed else 0
