"""The interval ``[θ1', θ2']`` and weight ``c`` each live arc's band is drawn with, from the
method's estimates: the point's bearing ± width/2 and the confidence (:func:`intervals`); for plain
carving from its model's state, without the estimates' other fields (:func:`carving_intervals`).
``docs/carved-grid.md``, "The sensor model" and "Reading the map".
"""

from __future__ import annotations

import numpy as np

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.fate import ALIVE
from sonarcarve.history import SonarHistory
from sonarcarve.methods import SonarMethod
from sonarcarve.methods.atm import AtmModel
from sonarcarve.methods.base import Estimates, arc_point
from sonarcarve.methods.carving import CarvingMethod, CarvingModel
from sonarcarve.methods.combined import CombinedMethod
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = ["carving_intervals", "intervals", "known_models", "store_intervals"]



def known_models(method: SonarMethod) -> tuple[CarvingModel | None, AtmModel | None]:
    """The carving model of a plain :class:`~sonarcarve.methods.carving.CarvingMethod`, or the
    carving and ATM models of a plain :class:`~sonarcarve.methods.combined.CombinedMethod` (no
    subclass: one that overrides its estimates must be asked), else ``(None, None)``."""
    models = method.models
    if type(method) is CarvingMethod and len(models) == 1 and type(models[0]) is CarvingModel:
        return models[0], None
    if (type(method) is CombinedMethod and len(models) == 2
            and type(models[0]) is CarvingModel and type(models[1]) is AtmModel):
        return models[0], models[1]
    return None, None


def carving_intervals(history: SonarHistory, model: CarvingModel,
                      slots: SlotArray) -> tuple[FloatArray, ...]:
    """``intervals(x, y, model.estimates(slots))`` for plain carving, with the same
    operations on the same numbers (so the same bits: the tests compare it with the method's
    estimates), without the fields of the estimates the grid does not read (half the cost)."""
    lo, hi = model.lo[slots], model.hi[slots]
    xy = arc_point(history, slots, 0.5 * (lo + hi))  # the point, as CarvingModel.estimates
    alive = model.status[slots] == ALIVE  # no confidence: 1 if alive
    return _ends(history.x[slots], history.y[slots], xy, hi - lo, alive, None)


def intervals(x: FloatArray, y: FloatArray, est: Estimates) -> tuple[FloatArray, ...]:
    """``(lo, hi, weight)`` of arcs from their estimates: the point's bearing ± width/2, and
    the confidence (1 where NaN or not modelled; 0 where the arc is not alive).

    Centred on the point even where the point is not the interval's middle (evidence
    carving's posterior point, off its kept run's middle), a choice measured, not an
    oversight (review rev9p found the band leaving the kept run in 95-98 % of cut evidence
    arcs): under evidence carving, office, seeds 0-2, specular,
    precision / recall / phantoms % at 0.10 m, a band centred on the point 0.864 / 0.947 /
    0.248, over the kept run 0.822 / 0.948 / 0.341, over their overlap 0.850 / 0.948 / 0.278
    (0.05 m: 0.736, 0.698, 0.712 precision; ``benchmarks/grid_methods.py --physics specular``
    on the three variants). The posterior point is where the echo most likely came from, so a
    band around it puts the arc's weight where the surface is.
    """
    return _ends(x, y, est.xy, est.width, est.alive, est.confidence)


def _ends(x: FloatArray, y: FloatArray, xy: FloatArray, width: FloatArray, alive: BoolArray,
          confidence: FloatArray | None) -> tuple[FloatArray, ...]:
    """``(bearing - half, bearing + half, weight)`` with the bearing of ``xy`` seen from
    ``(x, y)``, ``half = width / 2`` and the weight of :func:`intervals`; all zero for an arc
    that adds nothing (no weight, or no point: NaN).

    Two compiled passes around numpy's arctangent (kept numpy's, as the bits of the maps
    depend on it): the numpy version, about 15 array operations, cost some 13 µs for the five
    arcs of a read every 5 readings, twice a batch (``benchmarks/grid_reads.py``)."""
    n = len(x)
    rows = np.empty((2, n))
    _offsets(x, y, xy, rows)
    bearing = np.arctan2(rows[0], rows[1])
    out = np.empty((3, n))
    if confidence is None:
        _interval_ends(bearing, width, alive, _NONE, False, out)
    else:
        _interval_ends(bearing, width, alive, confidence, True, out)
    return out[0], out[1], out[2]


#: The confidence :func:`_interval_ends` is given for estimates without one (not read).
_NONE = np.zeros(0)


@compiled
def _offsets(x: FloatArray, y: FloatArray, xy: FloatArray, rows: FloatArray) -> None:
    """``rows[0] = xy[:, 1] - y``, ``rows[1] = xy[:, 0] - x``: the point seen from the sensor."""
    for k in range(x.shape[0]):
        rows[0, k] = xy[k, 1] - y[k]
        rows[1, k] = xy[k, 0] - x[k]


@compiled
def _interval_ends(bearing: FloatArray, width: FloatArray, alive: BoolArray,
                   confidence: FloatArray, weighed: bool, out: FloatArray) -> None:
    """``out[0], out[1], out[2]``: ``bearing ∓ width / 2`` and the weight, the confidence
    clipped to [0, 1] (1 where NaN or not ``weighed``; 0 where not ``alive``); all three zero
    where the weight is not positive or the bearing or width is NaN (:func:`_interval`)."""
    for k in range(bearing.shape[0]):
        weight = 1.0
        if weighed:
            c = confidence[k]
            weight = 1.0 if c != c else min(max(c, 0.0), 1.0)
        if not alive[k]:
            weight = 0.0
        out[0, k], out[1, k], out[2, k] = _interval(bearing[k], width[k], weight)


@compiled
def store_intervals(slots: SlotArray, bearing: FloatArray, width: FloatArray,
                    alive: BoolArray, chain: FloatArray, lo: FloatArray, hi: FloatArray,
                    weight: FloatArray) -> None:
    """The intervals of arcs without a confidence (weight 1 if ``alive``, else 0) into ``lo,
    hi, weight`` by slot, the weight times the arc's factor ``chain`` (by slot): what
    :func:`intervals` and then the grid's ``lo[slots] = ...`` give, in one pass."""
    for k in range(slots.shape[0]):
        s = slots[k]
        start, end, w = _interval(bearing[k], width[k], 1.0 if alive[k] else 0.0)
        lo[s] = start
        hi[s] = end
        weight[s] = w * chain[s]


@compiled_inline
def _interval(bearing: float, width: float, weight: float) -> tuple[float, float, float]:
    """``(bearing - width / 2, bearing + width / 2, weight)``, all zero where the weight is not
    positive or the bearing or width is NaN (the arc adds nothing)."""
    half = 0.5 * width
    if not weight > 0.0 or bearing != bearing or half != half:
        return 0.0, 0.0, 0.0
    return bearing - half, bearing + half, weight
