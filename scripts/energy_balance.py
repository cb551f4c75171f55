"""`python scripts/energy_balance.py ARGS` is `stockbridge energy-balance ARGS` (see `stockbridge energy-balance --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("energy-balance")
