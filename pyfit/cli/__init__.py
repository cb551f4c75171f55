"""The `stockbridge` command: one subcommand per job. Each module here parses arguments and calls the
library; none holds logic of its own."""
from __future__ import annotations

import argparse
import sys

from pyfit import __version__

# subcommand -> what it does; its module is pyfit.cli.<name with '_' for '-'>, imported only when it runs
COMMANDS = {
    "fit": "fit FMU parameters to a measurement (NNO, GA, DE, least squares); default: a bundled quick study",
    "diagnose": "sim-to-real gap: where the nominal model misfits measured data and which effect explains it",
    "design-check": "span design check: dampers needed, where, and the fatigue margin",
    "build": "build the FMUs (FMI 2.0 and 3.0, Model Exchange + Co-Simulation) from the Modelica library",
    "simulate": "simulate one example FMU with its built-in excitation (CSV + plot)",
    "sweep": "run a sweep study (models x parameter sets x levels) from a TOML file",
    "crosscheck": "check the FMUs against the independent CasADi reference",
    "energy-balance": "steady aeolian amplitudes of a span with and without the damper",
    "span": "co-simulate a conductor span with the damper at its clamp (damping per mode)",
    "verify-balance": "the energy balance against a co-simulation of the span in wind",
    "element-docs": "README and reference CSV for every element FMU",
    "docs-tables": "copy the result files the commands wrote into docs/results",
    "examples": "list the bundled datasets, or copy one into a folder to try the diagnosis on",
    "plan-test": "the test that would separate a diagnosis's close candidates, and its drive file",
}


def count(text: str) -> int:
    """An argparse type: a whole number of at least 1 (cases, workers, repeats)."""
    try:
        n = int(text)
    except ValueError:
        n = 0
    if n < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: a whole number of at least 1 is needed")
    return n


def parser() -> argparse.ArgumentParser:
    """The top-level parser with every subcommand (each adds its own arguments when it is chosen)."""
    ap = argparse.ArgumentParser(prog="stockbridge", description="Stockbridge damper and Bouc-Wen models as "
                                 "FMUs: fit, diagnose, design check.", epilog="stockbridge COMMAND --help shows "
                                 "a command's options and an example.")
    ap.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name, summary in COMMANDS.items():
        sub.add_parser(name, help=summary, add_help=False)
    return ap


def main(argv: list[str] | None = None) -> int:
    """Run `stockbridge COMMAND [options]`; returns the exit code."""
    import importlib

    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] not in COMMANDS:
        parser().parse_args(argv)  # prints usage or the error, and exits
        return 2
    module = importlib.import_module(f"pyfit.cli.{argv[0].replace('-', '_')}")
    ap = argparse.ArgumentParser(prog=f"stockbridge {argv[0]}", description=COMMANDS[argv[0]],
                                 epilog=module.EXAMPLE, formatter_class=argparse.RawDescriptionHelpFormatter)
    module.add_arguments(ap)
    return module.run(ap.parse_args(argv[1:]), ap)


def script(command: str) -> None:
    """Entry of the thin `scripts/*.py` wrappers: `python scripts/fit.py ARGS` is `stockbridge fit ARGS`."""
    sys.exit(main([command, *sys.argv[1:]]))
