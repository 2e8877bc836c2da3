"""How the reports print numbers: the one place for units, digits and the missing-value marker.

Every Markdown section of ``docs/RESULTS.md`` (:mod:`sonarcarve.lab.report` and the
experiments' own ``markdown``) formats its numbers with these functions, so a missing value
(None, NaN or infinite: a share over nothing, a median of no points) always prints as
:data:`MISSING`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

__all__ = [
    "MISSING",
    "fmt_cm",
    "fmt_dist",
    "fmt_mm",
    "fmt_ms",
    "fmt_num",
    "fmt_pct",
    "fmt_seeds",
    "fmt_span",
    "fmt_spread",
    "is_missing",
    "md_image",
]

#: What a report prints for a value that does not exist.
MISSING = "n/a"


def is_missing(value: float | None) -> bool:
    """True for None, NaN and infinities: values no report prints as a number."""
    return value is None or not math.isfinite(value)


def fmt_num(value: float | None, digits: int = 1, unit: str = "") -> str:
    """``value`` with ``digits`` decimals and ``unit`` appended; :data:`MISSING` if missing.

    Examples
    --------
    >>> fmt_num(3.14159, 2), fmt_num(12.0, 0, " %"), fmt_num(None), fmt_num(float("nan"))
    ('3.14', '12 %', 'n/a', 'n/a')
    """
    if value is None or is_missing(value):
        return MISSING
    return f"{value:.{digits}f}{unit}"


def fmt_cm(value: float | None) -> str:
    """A distance given in metres, shown in cm with one decimal.

    Examples
    --------
    >>> fmt_cm(0.0123), fmt_cm(None)
    ('1.2 cm', 'n/a')
    """
    return MISSING if value is None or is_missing(value) else f"{100.0 * value:.1f} cm"


def fmt_mm(value: float | None) -> str:
    """A distance given in metres, shown in mm with one decimal."""
    return MISSING if value is None or is_missing(value) else f"{1000.0 * value:.1f} mm"


def fmt_ms(value: float | None) -> str:
    """A time given in seconds, shown in ms with two decimals."""
    return MISSING if value is None or is_missing(value) else f"{1000.0 * value:.2f} ms"


def fmt_dist(value: float | None) -> str:
    """A distance given in metres: in cm below a metre, else in m with one decimal.

    Examples
    --------
    >>> fmt_dist(0.25), fmt_dist(3.04), fmt_dist(None)
    ('25.0 cm', '3.0 m', 'n/a')
    """
    if value is None or is_missing(value):
        return MISSING
    return fmt_cm(value) if abs(value) < 1.0 else f"{value:.1f} m"


def fmt_pct(value: float | None, digits: int = 0) -> str:
    """A percentage with the sign attached (``12%``)."""
    return MISSING if value is None or is_missing(value) else f"{value:.{digits}f}%"


def fmt_span(values: Sequence[float | None], fmt: Callable[[float | None], str]) -> str:
    """``a`` or ``a to b``: the smallest and largest of the values that exist, formatted.

    Examples
    --------
    >>> fmt_span([0.02, None, 0.05], fmt_cm), fmt_span([0.02, 0.02], fmt_cm), fmt_span([], fmt_cm)
    ('2.0 cm to 5.0 cm', '2.0 cm', 'n/a')
    """
    ok = [v for v in values if v is not None]
    if not ok:
        return MISSING
    lo, hi = fmt(min(ok)), fmt(max(ok))
    return lo if lo == hi else f"{lo} to {hi}"


def fmt_spread(spread: Mapping[str, Any] | None, digits: int = 1) -> str:
    """A mean over seeds with its min-max in brackets (just the mean for one seed).

    ``spread`` is a ``{"mean", "min", "max", "per_seed"}`` summary
    (:func:`~sonarcarve.lab.experiments.summary.spread`).

    Examples
    --------
    >>> fmt_spread({"mean": 2.0, "min": 1.0, "max": 3.0, "per_seed": [1.0, 2.0, 3.0]})
    '2.0 (1.0-3.0)'
    >>> fmt_spread({"mean": 2.0, "min": 2.0, "max": 2.0, "per_seed": [2.0, None]}, 2)
    '2.00'
    """
    if not spread or spread.get("mean") is None:
        return MISSING
    if len([v for v in spread["per_seed"] if v is not None]) <= 1:
        return fmt_num(spread["mean"], digits)
    return (f"{spread['mean']:.{digits}f} ({spread['min']:.{digits}f}-"
            f"{spread['max']:.{digits}f})")


def fmt_seeds(n: int) -> str:
    """``seed 0`` or ``seeds 0-{n-1}``."""
    return "seed 0" if n == 1 else f"seeds 0-{n - 1}"


def md_image(figs: Mapping[str, str], name: str, alt: str) -> list[str]:
    """A Markdown image line (and a blank line) for figure ``name`` at its path in ``figs``;
    nothing when the figure was not written."""
    return [f"![{alt}]({figs[name]})", ""] if name in figs else []
