"""`python scripts/span.py ARGS` is `stockbridge span ARGS` (see `stockbridge span --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("span")
