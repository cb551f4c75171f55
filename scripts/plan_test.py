"""`python scripts/plan_test.py ARGS` is `stockbridge plan-test ARGS` (see `stockbridge plan-test --help`)."""
from pyfit.cli import script

if __name__ == "__main__":
    script("plan-test")
