"""Simulate one example FMU with its built-in excitation and write a CSV and a plot.

    python scripts/simulate.py SDOFBoucWen [--set exc_amplitude=60 --set beta=0] [--stop 120] [--out results]
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.build import EXAMPLES  # noqa: E402
from pyfit.runtime.fmu import ParameterError  # noqa: E402
from pyfit.runtime.examples import run_example  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("model", choices=sorted(EXAMPLES))
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="parameter value")
    ap.add_argument("--stop", type=float, help="stop time [s] (default: the model's experiment annotation)")
    ap.add_argument("--interval", type=float, default=1e-3, help="output interval [s]")
    ap.add_argument("--fmus", default="fmus", help="folder with the built FMUs (built if missing)")
    ap.add_argument("--out", default="results", help="output folder")
    args = ap.parse_args()
    try:
        params = {k: float(v) for k, v in (s.split("=", 1) for s in args.set)}
    except ValueError:
        print("error: --set takes NAME=VALUE with a numeric VALUE", file=sys.stderr)
        return 2
    try:
        csv, png = run_example(args.model, params, args.stop, args.interval, pathlib.Path(args.fmus),
                               pathlib.Path(args.out))
    except (ParameterError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"wrote {csv} and {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
