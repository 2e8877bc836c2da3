"""What the filters share: their error, the check of a positive parameter, and the lookup of
each map point's reading by its id."""

from __future__ import annotations

import math
import numbers

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError
from sonarcarve.typing import IntArray

__all__ = ["FilterError", "check_positive", "rows_of_ids"]


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


def rows_of_ids(point_ids: npt.ArrayLike, ids: npt.ArrayLike,
                error: type[FilterError] = FilterError) -> IntArray:
    """The position in ``ids`` (the readings' ids) of each of ``point_ids`` (the map points'
    reading ids); ``error`` if ``ids`` repeat or a point's id is not among them."""
    wanted = np.asarray(point_ids, dtype=np.int64)
    known = np.asarray(ids, dtype=np.int64)
    order = np.argsort(known, kind="stable")
    sorted_ids = known[order]
    if np.any(sorted_ids[1:] == sorted_ids[:-1]):
        msg = "reading ids must be unique to look up a point's reading"
        raise error(msg)
    at = np.searchsorted(sorted_ids, wanted)
    found = at < len(known)
    found[found] = sorted_ids[at[found]] == wanted[found]
    if not found.all():
        msg = (f"map point of reading id {int(wanted[~found][0])} has no reading among the "
               f"{len(known):,} given: pass the readings the map was made from")
        raise error(msg)
    return np.asarray(order[at])
