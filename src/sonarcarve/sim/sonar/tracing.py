"""What both echo models' tracing shares: the traced record, batches of firings, ray casts.

:class:`_Traced` holds the per-firing results of a model's deterministic geometry;
:func:`_trace_all` runs a model's batch tracer over the firings :data:`_CHUNK_FIRINGS` at a
time; :func:`_cast` and :func:`_in_sight` cast rays on a sub-world of the walls near a batch.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from sonarcarve.sim.world import World
from sonarcarve.typing import BoolArray, FloatArray, IntArray

#: Firings traced together: bounds the (rays x walls) arrays to a few tens of megabytes while
#: keeping each batch's robot positions close together, so the wall pre-filter stays tight.
_CHUNK_FIRINGS = 256


#: Distance (m) by which a bounced ray starts off its first wall, so it does not re-hit it.
_BOUNCE_OFFSET = 1e-7


@dataclass(frozen=True, eq=False)
class _Traced:
    """Per-firing results of the deterministic geometry (no randomness).

    ``echo_distance`` and ``echo_point`` (shapes (n, R) and (n, R, 2)) keep every ray that
    echoes diffusely, out to the crosstalk horizon: the raw material of late echoes.
    """

    direct_range: FloatArray
    direct_point: FloatArray
    multipath_range: FloatArray
    multipath_point: FloatArray
    echo_distance: FloatArray
    echo_point: FloatArray

    @classmethod
    def empty(cls, n: int, rays: int) -> _Traced:
        """Nothing heard yet by ``n`` firings of ``rays`` late-echo rays each."""
        return cls(
            direct_range=np.full(n, np.inf), direct_point=np.full((n, 2), np.nan),
            multipath_range=np.full(n, np.inf), multipath_point=np.full((n, 2), np.nan),
            echo_distance=np.full((n, rays), np.inf), echo_point=np.full((n, rays, 2), np.nan),
        )


#: Ranges a model's tracing yields: the beams (direct and multipath echoes, late-echo raw
#: material), then the crosstalk and multipath echo heard by each firing (inf: none).
_ModelEchoes = tuple["_Traced", FloatArray, FloatArray]


def _batches(start: int, n: int) -> Iterator[tuple[int, int]]:
    """Firings ``start:n`` as batches ``lo:hi`` of :data:`_CHUNK_FIRINGS` (the last shorter),
    the one place the batch size is read (both models' tracing and the amplitude crosstalk)."""
    for lo in range(start, n, _CHUNK_FIRINGS):
        yield lo, min(lo + _CHUNK_FIRINGS, n)


def _trace_all(out: _Traced, walls: int, trace_chunk: Callable[[int, int], None],
               on_progress: Callable[[int, int], None] | None) -> _Traced:
    """Fill ``out`` batch by batch: ``trace_chunk(lo, hi)`` traces firings ``lo:hi`` into it
    (skipped when the world has no ``walls``)."""
    n = out.direct_range.shape[0]
    for lo, hi in _batches(0, n):
        if walls:
            trace_chunk(lo, hi)
        if on_progress is not None:
            on_progress(hi, n)
    return out


def _cast(world: World, index: IntArray, origin: FloatArray, angle: FloatArray,
          limit: float) -> tuple[FloatArray, IntArray]:
    """``World.cast_rays`` on a sub-world, with wall indices mapped back to the full world."""
    if origin.shape[0] == 0 or index.size == 0:
        return np.full(origin.shape[0], np.inf), np.full(origin.shape[0], -1, dtype=np.int64)
    distance, local = world.cast_rays(origin, angle, max_range=limit)
    return distance, np.where(local >= 0, index[np.maximum(local, 0)], -1).astype(np.int64)


def _in_sight(world: World, origin: FloatArray, target: FloatArray, limit: float) -> BoolArray:
    """Whether nothing stops the straight line from each origin (k, 2) before its target."""
    if origin.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    gap = target - origin
    length = np.hypot(gap[:, 0], gap[:, 1])
    seen, _ = world.cast_rays(origin, np.arctan2(gap[:, 1], gap[:, 0]), max_range=limit)
    return np.asarray(seen >= length * (1.0 - 1e-9) - 1e-9)


def _wrap(angle: FloatArray) -> FloatArray:
    """Angles folded into [-π, π]."""
    return np.asarray(np.angle(np.exp(1j * angle)))
