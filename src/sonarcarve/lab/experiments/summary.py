"""Summaries over seeds shared by the simulated experiments (office, T junction, openings)."""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from sonarcarve.lab import metrics
from sonarcarve.typing import JsonDict

__all__ = ["binned_over_seeds", "spread"]


def spread(values: Iterable[float | None]) -> JsonDict:
    """Mean, min, max and standard deviation of the finite values, and every value.

    Returns ``{"mean", "min", "max", "std", "per_seed"}``; the four statistics are None when no
    value is finite, and ``per_seed`` holds None for each missing value.

    Examples
    --------
    >>> spread([1.0, None, 3.0])["mean"], spread([1.0, None, 3.0])["per_seed"]
    (2.0, [1.0, None, 3.0])
    >>> spread([None])["mean"] is None
    True
    """
    v = np.array([np.nan if x is None else x for x in values], dtype=np.float64)
    ok = v[np.isfinite(v)]
    if not ok.size:
        return {"mean": None, "min": None, "max": None, "std": None, "per_seed": []}
    return {"mean": float(ok.mean()), "min": float(ok.min()), "max": float(ok.max()),
            "std": float(ok.std()), "per_seed": [None if not math.isfinite(x) else float(x)
                                                 for x in v]}


def binned_over_seeds(outs: list[JsonDict], key: str, stat: str = "mean") -> JsonDict:
    """The binned curves ``out[key]`` of several runs combined
    (:func:`~sonarcarve.lab.metrics.combine_binned`)."""
    return metrics.combine_binned([o[key] for o in outs], stat)
