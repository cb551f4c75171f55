"""The energy balance against a time-domain co-simulation of the same span in wind (ConductorSpan with the
wind on one mode + DamperElement at its clamp), mode by mode.

    python scripts/verify_balance.py [--modes 3 5 8 10 12 17 22] [--x-d 1.0] [--duration 16] [--out results/verify_balance]

Writes verify_balance.md: per mode, the steady antinode amplitude by the energy balance with and without the
damper's reaction on the string, and by the co-simulation.
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.design.verification import check_mode, write_table  # noqa: E402
from pyfit.runtime.examples import ensure_fmu  # noqa: E402
from pyfit.runtime.fmu import FmuRunner  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--modes", type=int, nargs="+", default=[3, 5, 8, 10, 12, 17, 22])
    ap.add_argument("--x-d", type=float, default=1.0, help="damper position from the span end [m]")
    ap.add_argument("--duration", type=float, default=16.0, help="co-simulated time per mode [s]")
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--out", default="results/verify_balance")
    args = ap.parse_args()
    fmus = pathlib.Path(args.fmus)
    span, damper = (FmuRunner(str(ensure_fmu(n, fmus))) for n in ("ConductorSpan", "DamperElement"))
    rows = [check_mode(span, damper, n, args.x_d, duration=args.duration) for n in args.modes]
    print(write_table(rows, args.out).read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
