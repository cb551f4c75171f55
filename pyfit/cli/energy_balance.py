"""stockbridge energy-balance: steady aeolian amplitudes of a span with and without the damper."""
from __future__ import annotations

import pathlib

EXAMPLE = """examples:
  stockbridge energy-balance                                   # Drake, 30 m and 300 m spans, the default damper
  stockbridge energy-balance --case 250:0.0003 --positions 0.8 1.2 --wind cigre --nominal my_damper.toml

Wind input: the CIGRE polynomial or a published laboratory curve; self-damping: the span's ζ; damper: the
DamperElement FMU driven by the conductor motion at its position."""


def _case(text: str) -> tuple[float, float]:
    length, zeta = text.split(":")
    return float(length), float(zeta)


def add_arguments(ap) -> None:
    """Arguments of `stockbridge energy-balance`."""
    from pyfit.design.energy_balance import DRAKE_DIAMETER
    from pyfit.design.wind import CURVES

    ap.add_argument("--case", nargs="+", type=_case, default=[(30.0, 0.002), (300.0, 0.0002)],
                    help="span cases SPAN_LENGTH_M:ZETA (other conductor data: the ConductorSpan FMU's)")
    ap.add_argument("--diameter", type=float, default=DRAKE_DIAMETER, help="conductor diameter [m] (default: Drake)")
    ap.add_argument("--positions", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0], help="damper positions [m]")
    ap.add_argument("--freqs", type=float, nargs=3, default=[3.0, 50.0, 1.0], metavar=("FIRST", "LAST", "STEP"),
                    help="frequency grid [Hz]")
    ap.add_argument("--amplitudes", type=float, nargs=3, default=[1e-5, 3e-2, 12], metavar=("MIN", "MAX", "N"),
                    help="clamp amplitude grid of the damper power table [m] (log-spaced)")
    ap.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="damper FMU parameters")
    ap.add_argument("--nominal", help="TOML describing your damper ([nominal] fixed and free parameters; --set wins)")
    ap.add_argument("--wind", choices=CURVES, default="cigre", help="wind power curve")
    ap.add_argument("--turbulence", type=float, default=0.0, help="turbulence intensity I_v [-] (0: smooth flow)")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--out", default="docs/figures/energy_balance")


def run(args, ap) -> int:
    """Run the study and print each span's report."""
    import numpy as np

    from pyfit.design.energy_balance import energy_balance_study
    from pyfit.design.wind import WindPower
    from pyfit.io.nominal import load_nominal
    from pyfit.runtime.examples import ensure_fmu
    from pyfit.runtime.fmu import FmuRunner

    fmus = pathlib.Path(args.fmus)
    try:
        overrides = {k: float(v) for k, v in (s.split("=", 1) for s in args.set)}
    except ValueError:
        ap.error("--set takes NAME=VALUE with a numeric VALUE")
    params = {**(load_nominal(args.nominal).parameters() if args.nominal else {}), **overrides}
    first, last, step = args.freqs
    reports = energy_balance_study(
        ensure_fmu("DamperElement", fmus), FmuRunner(str(ensure_fmu("ConductorSpan", fmus))), args.case,
        args.positions, np.arange(first, last + step / 2, step),
        np.geomspace(args.amplitudes[0], args.amplitudes[1], int(args.amplitudes[2])), params, args.diameter,
        WindPower(args.wind, args.turbulence), args.workers, args.out)
    for md in reports:
        print(md.read_text())
    return 0
