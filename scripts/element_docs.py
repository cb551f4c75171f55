"""`python scripts/element_docs.py ARGS` is `stockbridge element-docs ARGS` (see `stockbridge element-docs --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("element-docs")
