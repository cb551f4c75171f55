"""stockbridge element-docs: a README and a reference CSV for every element FMU."""
from __future__ import annotations

import pathlib

EXAMPLE = """examples:
  stockbridge element-docs --out docs/fmus"""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge element-docs`."""
    ap.add_argument("--fmus", default="fmus", help="FMU folder (built if missing; default: fmus)")
    ap.add_argument("--out", default="docs/fmus", help="output folder (default: docs/fmus)")


def run(args, ap) -> int:
    """Write the README and reference CSV of each element FMU."""
    from pyfit.runtime.element_docs import REFERENCE_RUNS, write_docs
    from pyfit.runtime.examples import ensure_fmu

    for name in REFERENCE_RUNS:
        print(f"wrote {write_docs(name, ensure_fmu(name, pathlib.Path(args.fmus)), args.out)}")
    return 0
