"""Cross-check every FMU against the independent CasADi reference (RHS, Jacobian, trajectories).

    python scripts/crosscheck.py [--fmus fmus] [--out results/crosscheck] [NAME ...]

Writes crosscheck.json, crosscheck.md, overlay plots and <Model>_ref.csv/.opt; exits 1 if a check fails.
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.reference import crosscheck  # noqa: E402
from pyfit.reference.models import NAMES  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help="FMUs to check (default: every example with a reference model)")
    ap.add_argument("--fmus", default="fmus", help="folder with the FMUs")
    ap.add_argument("--out", default="results/crosscheck", help="output folder")
    ap.add_argument("--samples", type=int, default=10, help="sampled states for the RHS and Jacobian levels")
    args = ap.parse_args()
    try:
        results = crosscheck.run(pathlib.Path(args.fmus), pathlib.Path(args.out), args.names or list(NAMES),
                                 args.samples)
    except (FileNotFoundError, KeyError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    failed = [r for r in results if not r.passed]
    for r in results:
        print(f"{'ok  ' if r.passed else 'FAIL'} {r.model:18s} {r.level}")
    print(f"{len(results) - len(failed)} passed, {len(failed)} failed; report: {args.out}/crosscheck.md")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
