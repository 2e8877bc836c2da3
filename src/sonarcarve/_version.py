"""The package version, in a module that imports nothing.

``sonarcarve --version`` reads it from here, so that printing the version never loads the
library; ``sonarcarve.__version__`` is this value too. It must equal ``version`` in
``pyproject.toml`` (a test checks).
"""

__version__ = "0.1.0"
