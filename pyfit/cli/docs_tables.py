"""stockbridge docs-tables: the result files the commands wrote, copied to docs/results/."""
from __future__ import annotations

import pathlib

EXAMPLE = """examples:
  stockbridge docs-tables            # copy results/... to docs/results/... and rewrite the README's block
  stockbridge docs-tables --check    # exit 1 if a generated block differs from its file (no writing)

Run from the repository's root, after the commands named on the docs' validation page."""


SETTINGS = "docs/results/diagnose_settings.md"  # the diagnosis's settings table (pyfit.gap.config.settings_table)


def add_arguments(ap) -> None:
    """Arguments of `stockbridge docs-tables`."""
    ap.add_argument("--check", action="store_true", help="only compare; exit 1 on a difference")
    ap.add_argument("--root", default=".", help="repository root (default: the current folder)")


def run(args, ap) -> int:
    """Collect the results and re-render the generated blocks (or only check them)."""
    from pyfit.gap.config import settings_table
    from pyfit.report import generated

    root = pathlib.Path(args.root)
    if args.check:
        bad = generated.stale_files(root)
        for p in bad:
            print(f"{p}: a generated block differs from its result file; run stockbridge docs-tables")
        return 1 if bad else 0
    for p in generated.collect(root):
        print(f"collected {p}")
    print(f"wrote {generated.headlines(root)}")
    settings = root / SETTINGS
    settings.write_text(settings_table(), encoding="utf-8")
    print(f"wrote {settings}")
    for p in generated.render_files(root):
        print(f"rewrote {p}")
    return 0
