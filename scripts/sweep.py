"""`python scripts/sweep.py ARGS` is `stockbridge sweep ARGS` (see `stockbridge sweep --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("sweep")
