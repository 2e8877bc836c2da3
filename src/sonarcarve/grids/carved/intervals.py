"""The interval ``[θ1', θ2']`` and weight ``c`` each live arc's band is drawn with, from the
method's estimates: the point's bearing ± width/2 and the confidence (:func:`intervals`); for plain
carving from its model's state, without the estimates' other fields (:func:`carving_intervals`).
``docs/carved-grid.md``, "The sensor model" and "Reading the map".
"""

from __future__ import annotations

import numpy as np

from sonarcarve.geometry.fate import ALIVE
from sonarcarve.history import SonarHistory
from sonarcarve.methods import SonarMethod
from sonarcarve.methods.atm import AtmModel
from sonarcarve.methods.base import Estimates, arc_point
from sonarcarve.methods.carving import CarvingMethod, CarvingModel
from sonarcarve.methods.combined import CombinedMethod
from sonarcarve.typing import FloatArray, SlotArray

__all__ = ["carving_intervals", "intervals", "known_models"]



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
    weight = np.where(model.status[slots] == ALIVE, 1.0, 0.0)  # no confidence: 1 if alive
    return _interval_ends(np.arctan2(xy[:, 1] - history.y[slots], xy[:, 0] - history.x[slots]),
                          0.5 * (hi - lo), weight)


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
    weight = np.ones(len(x)) if est.confidence is None else np.where(
        np.isnan(est.confidence), 1.0, np.clip(est.confidence, 0.0, 1.0))
    return _interval_ends(np.arctan2(est.xy[:, 1] - y, est.xy[:, 0] - x), 0.5 * est.width,
                          np.where(est.alive, weight, 0.0))


def _interval_ends(bearing: FloatArray, half: FloatArray,
                   weight: FloatArray) -> tuple[FloatArray, ...]:
    """``(bearing - half, bearing + half, weight)``, all zero for an arc that adds nothing (no
    weight, or no point: NaN)."""
    dead = ~(weight > 0.0) | np.isnan(bearing) | np.isnan(half)
    bearing = np.where(dead, 0.0, bearing)
    half = np.where(dead, 0.0, half)
    weight = np.where(dead, 0.0, weight)
    return (np.ascontiguousarray(bearing - half), np.ascontiguousarray(bearing + half),
            np.ascontiguousarray(weight, dtype=np.float64))
