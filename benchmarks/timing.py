"""Timing helpers shared by the benchmark scripts."""

from __future__ import annotations

import math
import time
from collections.abc import Callable


def best_seconds(run: Callable[[], object], repeats: int, *,
                 clock: Callable[[], float] = time.process_time, warm_up: bool = True) -> float:
    """The least seconds of ``repeats`` calls of ``run`` by ``clock`` (CPU time by default:
    steadier than wall time on a shared machine), after one call not counted when
    ``warm_up``: on a shared machine the fastest run is the one least slowed by others."""
    if warm_up:
        run()
    best = math.inf
    for _ in range(repeats):
        start = clock()
        run()
        best = min(best, clock() - start)
    return best
