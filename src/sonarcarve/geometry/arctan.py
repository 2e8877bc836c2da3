"""A short series for the arctangent of a bearing near an axis, with a bound on its error.

libm's ``atan2`` is a third of a beam cell's update in the grids and a large part of ATM's
crossing store. Within a 22.5° beam the tangent of a cell's bearing off the axis is at most 0.199,
where a Taylor series through ``t^17`` is within :data:`SERIES_ERROR` of the exact value. The
callers use it only where that bound proves the result they store is the one ``atan2`` would give
(the same bits), and take ``atan2`` elsewhere: ATM's float32 bearings
(:mod:`sonarcarve.methods.atm`), the carved grid's free space and the bearing a final band records
(:mod:`sonarcarve.grids.carved`).
"""

from __future__ import annotations

from sonarcarve.geometry._compiled import compiled_inline

__all__ = ["SERIES_ERROR", "SERIES_T", "atan_series"]

#: Largest ``|tan|`` of a bearing for which :func:`atan_series` holds its bound (a 22.5°
#: beam's cells are within 0.199 of its axis); the callers take libm's ``atan2`` past it.
SERIES_T = 0.2
#: Bound on ``|atan_series(t) - atan2(t·x, x)|`` for ``|t| <= SERIES_T``: the Taylor series'
#: remainder (alternating, terms falling: below the first term left out, ``T^19 / 19``,
#: 2.8e-15) plus the rounding of the division and of the sum (at most a dozen roundings of
#: numbers below 1, times ``t``: 3e-16) and libm's ``atan2`` error (a few ulp of 0.2, 1e-16).
SERIES_ERROR = SERIES_T ** 19 / 19.0 + 1e-15


@compiled_inline
def atan_series(t: float) -> float:
    """``atan(t)`` for ``|t| <= SERIES_T`` from its Taylor series through ``t^17`` (error below
    :data:`SERIES_ERROR`), instead of libm's ``atan2``. Evaluated in pairs of terms (Estrin's
    scheme, not Horner's): the same dozen roundings, half the chain of dependent operations."""
    u = t * t
    u2 = u * u
    u4 = u2 * u2
    low = (1.0 - u * (1.0 / 3.0)) + u2 * (1.0 / 5.0 - u * (1.0 / 7.0))
    high = (1.0 / 9.0 - u * (1.0 / 11.0)) + u2 * (1.0 / 13.0 - u * (1.0 / 15.0))
    return t * (low + u4 * (high + u4 * (1.0 / 17.0)))
