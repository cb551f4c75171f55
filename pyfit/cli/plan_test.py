"""stockbridge plan-test: the test that would separate a diagnosis's close leaders, and its drive file."""
from __future__ import annotations

import pathlib
import sys

EXAMPLE = """example:
  stockbridge diagnose --model sdof --data my_sweeps --out results/diagnose
  stockbridge plan-test --from results/diagnose --out results/next_test   # plan.md, next_test.csv + .toml

With the --nominal and --config the diagnosis ran with."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge plan-test`."""
    ap.add_argument("--from", dest="diagnosed", required=True, help="a diagnosis's output folder (its report.json)")
    ap.add_argument("--nominal", help="the TOML describing the system, as given to the diagnosis")
    ap.add_argument("--config", help="the TOML with the [diagnose] table the diagnosis ran with")
    ap.add_argument("--fmus", default="fmus", help="FMU folder (built there if missing)")
    ap.add_argument("--out", default="results/next_test", help="where plan.md and the drive file go")


def run(args, ap) -> int:
    """Propose the test and write it."""
    from pyfit.gap.diagnose import load_config
    from pyfit.gap.proposal import plan_test, write_plan
    from pyfit.io.schema import ConfigError

    try:
        cfg = load_config(args.config) if args.config else None
        proposal, (report, records, system) = plan_test(args.diagnosed, cfg, args.fmus, args.nominal)
    except (ConfigError, ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    md = write_plan(proposal, report, records, system, pathlib.Path(args.out))
    print(md.read_text())
    return 0
