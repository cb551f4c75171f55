"""`python scripts/verify_balance.py ARGS` is `stockbridge verify-balance ARGS` (see `stockbridge verify-balance --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("verify-balance")
