"""The grid as its compiled kernels take it: :class:`Model`, the geometry and the sensor model in
log-odds (``l_hit = logit(p_hit)``, ``l_miss = logit(p_miss)``, the clamp ``[l_min, l_max]``, the
band half-width ``b = (h + ε) / 2``), built from :class:`~sonarcarve.grids.carved.CarvedGridParams`
by :func:`model_of` (``docs/carved-grid.md``, "The sensor model"); and what each history slot drew
into a grid, :class:`SlotRecord`.

The kernels take arrays one by one, not in bundles: numba's dispatcher types a NamedTuple
argument field by field in Python (:func:`model_array` says what that costs for :class:`Model`),
and inside a kernel that counts references (one that allocates) a bundle of arrays costs an
atomic increment and decrement per array each time it is built or handed to a step
(:func:`~sonarcarve.grids.carved.kernels.refresh_kernel` has the measurement). Bundles of numbers
(the model, an arc's band, a beam) cost nothing, and the kernels use them freely.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.grids.carved.params import POSE_MARGIN_SIGMAS, CarvedGridParams
from sonarcarve.grids.cells import logit
from sonarcarve.typing import FloatArray

__all__ = [
    "DRAWN_HI",
    "DRAWN_LO",
    "DRAWN_R",
    "DRAWN_VALUE",
    "DRAWN_X",
    "DRAWN_Y",
    "Model",
    "SlotRecord",
    "model_array",
    "model_from",
    "model_of",
]


class Model(NamedTuple):
    """The grid's geometry and sensor model as the kernels use them (metres, log-odds), by
    name instead of twenty positional numbers that could be swapped unnoticed. The kernels are
    passed it as :func:`model_array` and name its fields again at their entry
    (:func:`model_from`)."""

    xmin: float
    ymin: float
    h: float
    band: float  # b, half-width of the occupied band
    l_hit: float
    l_miss: float
    l_heard: float  # logit(p_miss_heard)
    l_min: float
    l_max: float
    spread: float  # 1.0: spread each echo over its carved interval, 0.0: not
    unit: float  # max(spread_length, h)
    mark: float  # the newest echo's mark's length: mark_length, or unit when None
    fade: float  # d_f, inf: no fade
    aware: bool
    profile: float  # band_profile
    l_occupied: float  # logit(occupied_threshold)
    through: float  # see_through, metres (0: off)
    lobes: float  # side_lobes: the explanation reaches this many half beam widths past an edge
    lobe_range: float  # side_lobe_range, metres: only echoes at this range or nearer
    free_margin: float  # free space ends this much before the band, metres (pose_sigma's)


def model_of(params: CarvedGridParams, xmin: float, ymin: float, h: float,
             band: float) -> Model:
    """The kernels' model of a grid whose cells start at ``(xmin, ymin)``, of side ``h``, whose
    occupied band is ``band`` wide each side of the circle (metres), under ``params``."""
    p = params
    return Model(xmin=xmin, ymin=ymin, h=h, band=band, l_hit=logit(p.p_hit),
                 l_miss=logit(p.p_miss), l_heard=logit(p.p_miss_heard),
                 l_min=logit(p.p_min), l_max=logit(p.p_max),
                 spread=1.0 if p.spread else 0.0, unit=max(p.spread_length, h),
                 mark=max(p.spread_length, h) if p.mark_length is None else p.mark_length,
                 fade=float(p.fade_range), aware=p.surface_aware,
                 profile=float(p.band_profile), l_occupied=logit(p.occupied_threshold),
                 through=float(p.see_through), lobes=float(p.side_lobes),
                 lobe_range=float(p.side_lobe_range),
                 free_margin=POSE_MARGIN_SIGMAS * float(p.pose_sigma))


def model_array(m: Model) -> FloatArray:
    """``m`` as the float64 array the kernels take (:func:`model_from` makes it a
    :class:`Model` again, the same numbers; ``aware`` as 1.0 or 0.0).

    Why: numba's dispatcher works out the type of a named tuple argument in Python, about 1.5
    µs a call for :class:`Model`'s twenty fields, where an array costs 0.04 µs; the grid calls
    three such kernels a batch (``benchmarks/grid_reads.py``, a read every 5 readings)."""
    return np.array([float(value) for value in m], dtype=np.float64)


@compiled_inline
def model_from(v: FloatArray) -> Model:
    """The :class:`Model` of :func:`model_array` ``v``, inside a kernel (field by field, in
    :class:`Model`'s order)."""
    return Model(v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11],
                 v[12], v[13] != 0.0, v[14], v[15], v[16], v[17], v[18], v[19])


class SlotRecord(NamedTuple):
    """What each history slot drew into one grid (``live``, or ``points`` for the marks), so
    that it can be moved or taken out again; by slot. Only the fresh arc's judgment takes it
    as a bundle (:func:`~sonarcarve.grids.carved.mark._band_likeliest`, its own compiled
    function, called once a fresh arc); the steps that run for every arc take its two arrays
    (a bundle of arrays costs a reference count per array at each step it is handed to)."""

    drawn: FloatArray  # (storage, 6): the band's x, y, r, lo, hi, value (DRAWN_X .. DRAWN_VALUE)
    seq: npt.NDArray[np.int64]  # (storage,): the arc's sequence number, -1: nothing drawn


#: Columns of :attr:`SlotRecord.drawn`.
DRAWN_X, DRAWN_Y, DRAWN_R, DRAWN_LO, DRAWN_HI, DRAWN_VALUE = 0, 1, 2, 3, 4, 5
