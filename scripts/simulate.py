"""`python scripts/simulate.py ARGS` is `stockbridge simulate ARGS` (see `stockbridge simulate --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("simulate")
