"""stockbridge crosscheck: every FMU against the independent CasADi reference."""
from __future__ import annotations

import pathlib
import sys

EXAMPLE = """examples:
  stockbridge crosscheck                          # every example with a reference model
  stockbridge crosscheck StockbridgeDamper --out results/crosscheck

Writes crosscheck.json, crosscheck.md, overlay plots and <Model>_ref.csv/.opt; exits 1 if a check fails."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge crosscheck`."""
    ap.add_argument("names", nargs="*", help="FMUs to check (default: every example with a reference model)")
    ap.add_argument("--fmus", default="fmus", help="folder with the FMUs")
    ap.add_argument("--out", default="results/crosscheck", help="output folder")
    ap.add_argument("--samples", type=int, default=10, help="sampled states for the RHS and Jacobian levels")


def run(args, ap) -> int:
    """Run the cross-check levels and print one line per model and level."""
    from pyfit.reference import crosscheck
    from pyfit.reference.models import NAMES

    try:
        results = crosscheck.run(pathlib.Path(args.fmus), pathlib.Path(args.out), args.names or list(NAMES),
                                 args.samples)
    except (FileNotFoundError, KeyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    failed = [r for r in results if not r.passed]
    for r in results:
        print(f"{'ok  ' if r.passed else 'FAIL'} {r.model:18s} {r.level}")
    print(f"{len(results) - len(failed)} checks passed, {len(failed)} failed; report: {args.out}/crosscheck.md")
    return 1 if failed else 0
