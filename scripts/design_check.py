"""`python scripts/design_check.py ARGS` is `stockbridge design-check ARGS` (see `stockbridge design-check --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("design-check")
