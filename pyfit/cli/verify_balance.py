"""stockbridge verify-balance: the energy balance against a co-simulation of the span in wind."""
from __future__ import annotations

import pathlib

EXAMPLE = """examples:
  stockbridge verify-balance --modes 3 5 8 10 12 17 22 --x-d 1.0 --out results/verify_balance

Per mode, the steady antinode amplitude by the energy balance with and without the damper's reaction on the
string, and by the co-simulation (ConductorSpan with the wind on one mode + DamperElement at its clamp)."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge verify-balance`."""
    ap.add_argument("--modes", type=int, nargs="+", default=[3, 5, 8, 10, 12, 17, 22])
    ap.add_argument("--x-d", type=float, default=1.0, help="damper position from the span end [m]")
    ap.add_argument("--duration", type=float, default=16.0, help="co-simulated time per mode [s]")
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--out", default="results/verify_balance")


def run(args, ap) -> int:
    """Check each mode and print the table."""
    from pyfit.design.verification import check_mode, write_table
    from pyfit.runtime.examples import ensure_fmu
    from pyfit.runtime.fmu import FmuRunner

    fmus = pathlib.Path(args.fmus)
    span, damper = (FmuRunner(str(ensure_fmu(n, fmus))) for n in ("ConductorSpan", "DamperElement"))
    rows = [check_mode(span, damper, n, args.x_d, duration=args.duration) for n in args.modes]
    print(write_table(rows, args.out).read_text())
    return 0
