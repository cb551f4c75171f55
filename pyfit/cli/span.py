"""stockbridge span: a conductor span with the damper at its clamp, co-simulated mode by mode."""
from __future__ import annotations

import pathlib

EXAMPLE = """examples:
  stockbridge span --positions 0.5 1.0 1.5 2.0 --amplitude 0.005 --out results/span
  stockbridge span --ssp span_with_damper.ssp     # also the coupled system as SSP 1.0 for other FMI tools

Per mode in the aeolian band: the damping with the damper and the resonant amplitude reduction."""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge span`."""
    ap.add_argument("--positions", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0], help="damper positions [m]")
    ap.add_argument("--modes", type=int, nargs=2, default=[2, 22], help="first and last mode (default: 3-50 Hz)")
    ap.add_argument("--amplitude", type=float, default=5e-3, help="antinode amplitude at the start [m]")
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--out", default="docs/figures/span")
    ap.add_argument("--ssp", help="also write the coupled system as an SSP 1.0 archive (.ssp) for other tools")


def run(args, ap) -> int:
    """Co-simulate, print the reduction table, optionally write the SSP archive."""
    from pyfit.design.span import reduction_table, write_report, write_span_ssp
    from pyfit.runtime.examples import ensure_fmu
    from pyfit.runtime.fmu import FmuRunner

    fmus = pathlib.Path(args.fmus)
    span, damper = (FmuRunner(str(ensure_fmu(n, fmus))) for n in ("ConductorSpan", "DamperElement"))
    rows = reduction_table(span, damper, range(args.modes[0], args.modes[1] + 1), args.positions,
                           amplitude=args.amplitude)
    print(write_report(rows, args.out).read_text())
    if args.ssp:
        print(f"wrote {write_span_ssp(args.ssp, span, damper, args.positions[0])}")
    return 0
