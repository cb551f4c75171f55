"""`python scripts/fit.py ARGS` is `stockbridge fit ARGS` (see `stockbridge fit --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("fit")
