"""`python scripts/docs_tables.py ARGS` is `stockbridge docs-tables ARGS` (see `stockbridge docs-tables --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("docs-tables")
