"""Write a README (variables with units) and a reference result CSV for every element FMU into docs/fmus/.

    python scripts/element_docs.py [--fmus fmus] [--out docs/fmus]
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.build.element_docs import REFERENCE_RUNS, write_docs  # noqa: E402
from pyfit.runtime.examples import ensure_fmu  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--fmus", default="fmus", help="FMU folder (built if missing; default: fmus)")
    ap.add_argument("--out", default="docs/fmus", help="output folder (default: docs/fmus)")
    args = ap.parse_args()
    for name in REFERENCE_RUNS:
        print(f"wrote {write_docs(name, ensure_fmu(name, pathlib.Path(args.fmus)), args.out)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
