"""Optional dependencies: import one, or fail with a line that says which extra installs it.

The library core needs numpy, scipy and numba only. The command line, YAML files, figures,
image maps and ROS bags come with extras (``pip install 'sonarcarve[cli]'``, ``[plot]``,
``[ros]``, or ``[all]`` for everything)."""

from __future__ import annotations

import importlib
from types import ModuleType

from sonarcarve.errors import SonarcarveError

__all__ = ["MissingExtraError", "require"]


class MissingExtraError(SonarcarveError, ImportError):
    """An optional dependency that the feature needs is not installed."""


def require(module: str, extra: str, feature: str) -> ModuleType:
    """Import ``module`` or raise :class:`MissingExtraError` naming the ``extra`` to install.

    Examples
    --------
    >>> require("math", "cli", "arithmetic").__name__
    'math'
    >>> require("no_such_module", "plot", "figures")
    Traceback (most recent call last):
    ...
    sonarcarve.extras.MissingExtraError: figures need no_such_module: pip install 'sonarcarve[plot]'
    """
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as err:
        if err.name is not None and module.split(".")[0] != err.name.split(".")[0]:
            raise  # the module is there but something it imports is broken: show that
        top = module.split(".")[0]
        msg = f"{feature} need {top}: pip install 'sonarcarve[{extra}]'"
        raise MissingExtraError(msg) from None
