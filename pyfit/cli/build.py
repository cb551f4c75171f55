"""stockbridge build: the Modelica library's examples as FMUs."""
from __future__ import annotations

import os
import pathlib
import sys

from pyfit.catalog import EXAMPLES, LIBRARY

EXAMPLE = """examples:
  stockbridge build                       # every example into fmus/ (FMI 2.0) and fmus/fmi3/ (FMI 3.0)
  stockbridge build StockbridgeDamper --out my_fmus
  stockbridge build --library my_copy_of_the_library SDOFBoucWen
  stockbridge build --with my_models MyDampers.SDOFMaxwell --out my_fmus   # your model, using this library"""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge build`."""
    ap.add_argument("names", nargs="*", help=f"examples to build (default: all of {', '.join(EXAMPLES)}), or "
                                              "classes by full name")
    ap.add_argument("--out", default="fmus", help="output folder (default: fmus)")
    ap.add_argument("--library", default=str(LIBRARY), help="Modelica library folder (default: the package's)")
    ap.add_argument("--with", dest="extra", action="append", default=[], metavar="DIR",
                    help="a folder of your own Modelica packages, loaded beside the library (repeatable); "
                         "name their classes in full")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="FMUs built at once, one process each (default: one per core)")


def run(args, ap) -> int:
    """Build the FMUs, one line per FMU."""
    from pyfit.build import ModelicaError, build_all

    try:
        library = [pathlib.Path(args.library), *map(pathlib.Path, args.extra)] if args.extra else \
            pathlib.Path(args.library)
        build_all(pathlib.Path(args.out), args.names or None, library,
                  on_built=lambda r: print(f"built {r.fmu} and {r.fmu3} ({r.n_states} states)"), workers=args.workers)
    except (ModelicaError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    return 0
