"""stockbridge examples: the bundled datasets, listed or copied into a folder."""
from __future__ import annotations

import pathlib
import sys

EXAMPLE = """examples:
  stockbridge examples                          # list the bundled datasets
  stockbridge examples lab_sweeps my_first_test # copy one into my_first_test/ (its README.txt says what it is)
  stockbridge diagnose --model sdof --data my_first_test --check"""


def add_arguments(ap) -> None:
    """Arguments of `stockbridge examples`."""
    ap.add_argument("name", nargs="?", help="a bundled dataset to copy (default: list them)")
    ap.add_argument("to", nargs="?", help="the folder to copy it into (default: a folder of its name here)")


def run(args, ap) -> int:
    """List the bundled datasets, or copy one."""
    from pyfit.catalog import copy_dataset, datasets

    if not args.name:
        for name, what in datasets().items():
            print(f"{name}: {what}")
        return 0
    try:
        print(copy_dataset(args.name, pathlib.Path(args.to or args.name)))
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0
