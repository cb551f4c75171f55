"""Span design check: dampers needed, where, and the fatigue margin at the suspension clamp.

    python scripts/design_check.py SPAN.toml [--out results/design_check] [--fmus fmus] [--workers N]

SPAN.toml describes the conductor, span, self-damping law, wind climate, damper (FMU parameters, e.g. a fit's
result) and the placement range (format: pyfit/io/span_config.py; example: configs/span_drake_300m.toml).
Writes design_check.md, design_check.json, damper_power.csv and figures into --out.
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.design.design_check import run_design_check, write_report  # noqa: E402
from pyfit.io.schema import ConfigError  # noqa: E402
from pyfit.io.span_config import load_span_design  # noqa: E402
from pyfit.runtime.examples import ensure_fmu  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("span", help="SPAN.toml")
    ap.add_argument("--out", default="results/design_check", help="report folder")
    ap.add_argument("--fmus", default="fmus", help="FMU folder (DamperElement built if missing)")
    ap.add_argument("--workers", type=int, default=None, help="parallel damper runs (default: all cores)")
    args = ap.parse_args()
    try:
        design = load_span_design(args.span)
    except ConfigError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    result = run_design_check(design, ensure_fmu("DamperElement", pathlib.Path(args.fmus)), args.workers)
    print(write_report(result, args.out).read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
