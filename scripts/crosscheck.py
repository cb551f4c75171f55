"""`python scripts/crosscheck.py ARGS` is `stockbridge crosscheck ARGS` (see `stockbridge crosscheck --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("crosscheck")
