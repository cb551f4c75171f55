"""Conductor span with a Stockbridge damper at its clamp (co-simulation of ConductorSpan and DamperElement):
per mode in the aeolian band, the damping with the damper and the resonant amplitude reduction, for several
damper positions.

    python scripts/span.py [--positions 0.5 1.0 1.5 2.0] [--amplitude 0.005] [--out docs/figures/span] [--ssp FILE]
"""
import argparse
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.runtime.fmu import FmuRunner  # noqa: E402
from pyfit.runtime.examples import ensure_fmu  # noqa: E402
from pyfit.design.span import CONNECTIONS, reduction_table, write_report  # noqa: E402
from pyfit.runtime.ssp import write_ssp  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--positions", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0], help="damper positions [m]")
    ap.add_argument("--modes", type=int, nargs=2, default=[2, 22], help="first and last mode (default: 3-50 Hz)")
    ap.add_argument("--amplitude", type=float, default=5e-3, help="antinode amplitude at the start [m]")
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--out", default="docs/figures/span")
    ap.add_argument("--ssp", help="also write the coupled system as an SSP 1.0 archive (.ssp) for other tools")
    args = ap.parse_args()
    fmus = pathlib.Path(args.fmus)
    span, damper = (FmuRunner(str(ensure_fmu(n, fmus))) for n in ("ConductorSpan", "DamperElement"))
    rows = reduction_table(span, damper, range(args.modes[0], args.modes[1] + 1), args.positions,
                           amplitude=args.amplitude)
    write_report(rows, args.out)
    print((pathlib.Path(args.out) / "reduction.md").read_text())
    if args.ssp:
        write_ssp(args.ssp, "SpanWithDamper", {"span": span.path, "damper": damper.path}, CONNECTIONS,
                  {"span": {"exc_type": 1, "x_d": args.positions[0]}, "damper": {"m_c": 0.0}}, stop_time=10.0)
        print(f"wrote {args.ssp}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
