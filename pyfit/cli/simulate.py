"""stockbridge simulate: one example FMU with its built-in excitation."""
from __future__ import annotations

import pathlib
import sys

from pyfit.catalog import EXAMPLES

EXAMPLE = """examples:
  stockbridge simulate SDOFBoucWen --set exc_amplitude=60 --set beta=0 --stop 120 --out results
  stockbridge simulate StockbridgeDamper"""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge simulate`."""
    ap.add_argument("model", choices=sorted(EXAMPLES))
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="parameter value")
    ap.add_argument("--stop", type=float, help="stop time [s] (default: the model's experiment annotation)")
    ap.add_argument("--interval", type=float, default=1e-3, help="output interval [s]")
    ap.add_argument("--fmus", default="fmus", help="folder with the built FMUs (built if missing)")
    ap.add_argument("--out", default="results", help="output folder")


def run(args, ap) -> int:
    """Simulate and write <out>/<model>.csv and .png."""
    from pyfit.runtime.examples import run_example
    from pyfit.runtime.fmu import ParameterError

    try:
        params = {k: float(v) for k, v in (s.split("=", 1) for s in args.set)}
    except ValueError:
        ap.error("--set takes NAME=VALUE with a numeric VALUE")
    try:
        csv, png = run_example(args.model, params, args.stop, args.interval, pathlib.Path(args.fmus),
                               pathlib.Path(args.out))
    except (ParameterError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {csv} and {png}")
    return 0
