"""`python scripts/examples.py ARGS` is `stockbridge examples ARGS` (see `stockbridge examples --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("examples")
