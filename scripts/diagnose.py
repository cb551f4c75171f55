"""`python scripts/diagnose.py ARGS` is `stockbridge diagnose ARGS` (see `stockbridge diagnose --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("diagnose")
