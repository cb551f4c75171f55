"""Build every example of modelica/ into fmus/ (FMI 2.0) and fmus/fmi3/ (FMI 3.0), Model Exchange + Co-Simulation.

    python scripts/build_fmus.py [--out fmus] [NAME ...]
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.build import EXAMPLES, LIBRARY, ModelicaError, build_all  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help=f"examples to build (default: all of {', '.join(EXAMPLES)})")
    ap.add_argument("--out", default="fmus", help="output folder (default: fmus)")
    ap.add_argument("--library", default=str(LIBRARY), help="Modelica library folder (default: modelica/)")
    args = ap.parse_args()
    try:
        build_all(pathlib.Path(args.out), args.names or None, pathlib.Path(args.library),
                  on_built=lambda r: print(f"built {r.fmu} and {r.fmu3} ({r.n_states} states)"))
    except (ModelicaError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
