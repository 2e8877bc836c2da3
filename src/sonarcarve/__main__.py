"""``python -m sonarcarve ...``: the same command line as the ``sonarcarve`` script (for a venv
whose scripts folder is not on PATH, or to pick the Python that runs it)."""

import sys

from sonarcarve.cli import main

if __name__ == "__main__":
    sys.exit(main())
