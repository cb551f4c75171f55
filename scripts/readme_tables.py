"""Regenerate the README's result tables from the files the commands wrote.

    python scripts/readme_tables.py            copy results/... to docs/results/... and rewrite README.md
    python scripts/readme_tables.py --check    exit 1 if a README block differs from its file (no writing)
"""
import argparse
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from pyfit.report import readme  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only compare; exit 1 on a difference")
    args = ap.parse_args()
    path = ROOT / "README.md"
    text = path.read_text(encoding="utf-8")
    if args.check:
        bad = readme.stale(text, ROOT)
        for p in bad:
            print(f"README.md: the block generated from {p} differs from the file; run python scripts/readme_tables.py")
        return 1 if bad else 0
    for p in readme.collect(ROOT):
        print(f"collected {p}")
    path.write_text(readme.render(text, ROOT), encoding="utf-8")
    print(f"README.md: {len(readme.blocks(text))} generated blocks written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
