"""stockbridge design-check: dampers needed on a span, where, and the fatigue margin."""
from __future__ import annotations

import pathlib
import sys

EXAMPLE = """examples:
  stockbridge design-check configs/span_drake_300m.toml --out results/design_check

SPAN.toml describes the conductor, span, self-damping law, wind climate, damper (FMU parameters, e.g. a fit's
result, or a measured impedance test) and the placement range (docs: user guide, design check). Writes
design_check.md, design_check.json, damper_power.csv and figures into --out."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge design-check`."""
    ap.add_argument("span", help="SPAN.toml")
    ap.add_argument("--out", default="results/design_check", help="report folder")
    ap.add_argument("--fmus", default="fmus", help="FMU folder (DamperElement built if missing)")
    ap.add_argument("--workers", type=int, default=None, help="parallel damper runs (default: all cores)")


def run(args, ap) -> int:
    """Run the check and print the report."""
    from pyfit.design.design_check import run_design_check, write_report
    from pyfit.design.span_config import load_span_design
    from pyfit.io.schema import ConfigError
    from pyfit.runtime.examples import ensure_fmu

    try:
        design = load_span_design(args.span)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    result = run_design_check(design, ensure_fmu("DamperElement", pathlib.Path(args.fmus)), args.workers)
    print(write_report(result, args.out).read_text())
    return 0
