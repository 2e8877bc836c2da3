"""Any grid's cells as occupied, free or unknown (:func:`trinary`), each grid by its own rule: ROS
``nav_msgs/OccupancyGrid``'s 100, 0 and -1 (``docs/carved-grid.md``, "The grids' shared protocol").
"""

from __future__ import annotations

import numpy as np

from sonarcarve.grids.carved.grid import CarvedGrid
from sonarcarve.grids.carved.params import CarvedGridParams
from sonarcarve.grids.elfes import OccupancyGrid
from sonarcarve.grids.occupancy import FREE, OCCUPIED, UNKNOWN, Int8Grid, OccupancyMap
from sonarcarve.grids.range_sensor_layer import (
    FREE_SPACE,
    LETHAL_OBSTACLE,
    RangeSensorLayer,
)
from sonarcarve.typing import FloatArray

__all__ = ["trinary"]

def trinary(grid: OccupancyMap) -> Int8Grid:
    """Occupied (100), free (0) or unknown (-1) for every cell, shape ``grid.shape``.

    Each grid with its own rule: :class:`~sonarcarve.grids.carved.CarvedGrid` with its
    :attr:`~sonarcarve.grids.carved.CarvedGridParams.occupied_threshold` and ``free_threshold``,
    compared in log-odds (:meth:`~sonarcarve.grids.carved.CarvedGrid.trinary`: equal to comparing
    probabilities up to rounding within a few ulp of the thresholds);
    :class:`~sonarcarve.grids.RangeSensorLayer` as it writes its master costmap
    (:meth:`~sonarcarve.grids.RangeSensorLayer.costs`: lethal above ``mark_threshold``, free below
    ``clear_threshold``); :class:`~sonarcarve.grids.OccupancyGrid` (Elfes) occupied above its
    default threshold (0.65) and free below :data:`~sonarcarve.grids.carved.DEFAULT_FREE_THRESHOLD`
    (0.35), as the carved grid by default; any other
    :class:`~sonarcarve.grids.OccupancyMap` by probability with those two thresholds.

    Examples
    --------
    >>> g = CarvedGrid(0.1, (0.0, 0.0, 1.0, 1.0))
    >>> trinary(g)[0, :3].tolist()  # nothing seen yet
    [-1, -1, -1]
    """
    if isinstance(grid, CarvedGrid):
        return grid.trinary()
    if isinstance(grid, RangeSensorLayer):
        costs = grid.costs()
        out = np.full(costs.shape, UNKNOWN, dtype=np.int8)
        out[costs == LETHAL_OBSTACLE] = OCCUPIED
        out[costs == FREE_SPACE] = FREE
        return out
    if isinstance(grid, OccupancyGrid):
        return _classify(grid.probabilities(), CarvedGridParams.occupied_threshold,
                         CarvedGridParams.free_threshold)
    return _classify(np.asarray(grid.probabilities(), dtype=np.float64),
                     CarvedGridParams.occupied_threshold, CarvedGridParams.free_threshold)


def _classify(p: FloatArray, occupied: float, free: float) -> Int8Grid:
    """Occupied where the probability ``p`` is above ``occupied``, free below ``free``."""
    out = np.full(p.shape, UNKNOWN, dtype=np.int8)
    out[p > occupied] = OCCUPIED
    out[p < free] = FREE
    return out
