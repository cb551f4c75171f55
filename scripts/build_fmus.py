"""`python scripts/build_fmus.py ARGS` is `stockbridge build ARGS` (see `stockbridge build --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("build")
