"""stockbridge sweep: a sweep study from a TOML file."""
from __future__ import annotations

import pathlib
import sys

from pyfit.cli import count

EXAMPLE = """examples:
  stockbridge sweep configs/seed_fig4_4_sweep.toml --out results/sweep
  stockbridge sweep study.toml --scheduler tcp://10.0.0.5:8786"""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge sweep`."""
    ap.add_argument("config")
    ap.add_argument("--out", help="output folder (default: results/<config stem>)")
    ap.add_argument("--workers", type=count, help="local worker processes (default: one per core)")
    ap.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://10.0.0.5:8786")
    ap.add_argument("--fmus", default="fmus", help="folder with the FMUs (built if missing)")
    ap.add_argument("--nominal", help="TOML describing your system ([nominal] fixed and free parameters)")


def run(args, ap) -> int:
    """Run the study; one line per failed run."""
    from pyfit.io.nominal import load_nominal
    from pyfit.io.sweep_config import ConfigError, load_sweep
    from pyfit.runtime.examples import ensure_fmu
    from pyfit.runtime.sweep import fmu_interface, run_study

    fmus = pathlib.Path(args.fmus)
    try:
        cfg = load_sweep(args.config, lambda m: fmu_interface(ensure_fmu(m, fmus)),
                         load_nominal(args.nominal) if args.nominal else None)
        out = pathlib.Path(args.out or f"results/{cfg.path.stem}")
        rows = run_study(cfg, fmus, out, args.workers, args.scheduler)
    except (ConfigError, ValueError, ConnectionError) as exc:  # ConnectionError: a scheduler not answering
        print(f"error: {exc}", file=sys.stderr)
        return 2
    failed = [r for r in rows if not r["ok"]]
    for r in failed:
        print(f"run {r['label']} failed: {r['message']}", file=sys.stderr)
    print(f"{len(rows) - len(failed)} of {len(rows)} runs done; results in {out}")
    return 1 if failed else 0
