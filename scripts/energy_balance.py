"""Energy balance design check of the Stockbridge damper over the aeolian band: steady vibration amplitude
of a span with and without the damper (wind input: the CIGRE polynomial or a published curve; self-damping: the span's zeta; damper:
the DamperElement FMU driven by the conductor motion at its position).

    python scripts/energy_balance.py [--case 30:0.002 300:0.0002] [--positions 0.5 1 1.5 2]
        [--freqs 3 50 1] [--set NAME=VALUE ...] [--wind cigre] [--turbulence 0] [--out docs/figures/energy_balance]
"""
import argparse
import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pyfit.design import energy_balance as eb  # noqa: E402
from pyfit.design.wind import CURVES, WindPower  # noqa: E402
from pyfit.io.nominal import load_nominal  # noqa: E402
from pyfit.runtime.fmu import FmuRunner  # noqa: E402
from pyfit.runtime.examples import ensure_fmu  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", nargs="+", default=["30:0.002", "300:0.0002"],
                    help="span cases SPAN_LENGTH_M:ZETA (other conductor data: the ConductorSpan FMU's)")
    ap.add_argument("--diameter", type=float, default=eb.DRAKE_DIAMETER, help="conductor diameter [m]")
    ap.add_argument("--positions", type=float, nargs="+", default=[0.5, 1.0, 1.5, 2.0], help="damper positions [m]")
    ap.add_argument("--freqs", type=float, nargs=3, default=[3.0, 50.0, 1.0], metavar=("FIRST", "LAST", "STEP"),
                    help="frequency grid [Hz]")
    ap.add_argument("--amplitudes", type=float, nargs=3, default=[1e-5, 3e-2, 12], metavar=("MIN", "MAX", "N"),
                    help="clamp amplitude grid of the damper power table [m] (log-spaced)")
    ap.add_argument("--set", nargs="*", default=[], metavar="NAME=VALUE", help="damper FMU parameters")
    ap.add_argument("--nominal", help="TOML describing your damper ([nominal] fixed and free parameters; --set wins)")
    ap.add_argument("--wind", choices=CURVES, default="cigre", help="wind power curve (pyfit/design/wind.py)")
    ap.add_argument("--turbulence", type=float, default=0.0, help="turbulence intensity I_v [-] (0: smooth flow)")
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--fmus", default="fmus")
    ap.add_argument("--out", default="docs/figures/energy_balance")
    args = ap.parse_args()
    fmus = pathlib.Path(args.fmus)
    span = FmuRunner(str(ensure_fmu("ConductorSpan", fmus)))
    params = {**(load_nominal(args.nominal).parameters() if args.nominal else {}),
              **{k: float(v) for k, v in (s.split("=", 1) for s in args.set)}}
    first, last, step = args.freqs
    freqs = np.arange(first, last + step / 2, step)
    amps = np.geomspace(args.amplitudes[0], args.amplitudes[1], int(args.amplitudes[2]))
    table = eb.damper_power_table(ensure_fmu("DamperElement", fmus), freqs, amps, params, workers=args.workers)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    table.save(out / "damper_power.csv")
    for case in args.case:
        length, zeta = (float(x) for x in case.split(":"))
        conductor = eb.conductor_of_span(span, args.diameter, span_length=length, zeta=zeta)
        wind = WindPower(args.wind, args.turbulence)
        rows = eb.energy_balance(conductor, table, args.positions, wind)
        md = eb.write_report(rows, conductor, table, out, name=f"span_{length:g}m_zeta_{zeta:g}", wind=wind)
        print(md.read_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
