"""`python -m pyfit.cli ARGS` is `stockbridge ARGS`."""
import sys

from pyfit.cli import main

sys.exit(main())
