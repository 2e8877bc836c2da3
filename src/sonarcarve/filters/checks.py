"""The map and reading filters' error, and the one check of their distances."""

from __future__ import annotations

import math
import numbers

from sonarcarve.errors import SonarcarveError

__all__ = ["FilterError", "check_positive"]


class FilterError(SonarcarveError, ValueError):
    """A filter parameter outside its valid range."""


def check_positive(name: str, value: float | None, unit: str = "metres",
                   error: type[FilterError] = FilterError) -> None:
    """Refuse a distance (or another quantity: ``unit``) that is given (not ``None``) but no
    finite number > 0, with ``error`` (a :class:`FilterError`)."""
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        msg = f"{name} must be a finite number > 0 ({unit}), got {type(value).__name__} {value!r}"
        raise error(msg)
    if not (math.isfinite(value) and value > 0.0):
        msg = f"{name} must be a finite number > 0 ({unit}), got {value}"
        raise error(msg)

