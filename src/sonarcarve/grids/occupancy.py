"""What every occupancy grid offers (:class:`OccupancyMap`) and the ROS trinary cell values.

Shared by the three grids of :mod:`sonarcarve.grids`, and depending on none of them, so that
any grid module can name the protocol and the values without importing another grid.
:func:`~sonarcarve.grids.trinary` turns any :class:`OccupancyMap` into the values.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from sonarcarve.typing import FloatArray

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "Int8Grid", "OccupancyMap"]

#: Trinary cell values, as in ROS ``nav_msgs/OccupancyGrid``.
OCCUPIED = 100
FREE = 0
UNKNOWN = -1
Int8Grid = npt.NDArray[np.int8]


@runtime_checkable
class OccupancyMap(Protocol):
    """What every grid of :mod:`sonarcarve.grids` offers: geometry and probabilities.

    Cell ``(i, j)`` (row i along y, column j along x) is the square of side ``resolution`` whose
    centre is ``(xmin + (j + 1/2) h, ymin + (i + 1/2) h)`` for ``(xmin, ymin)`` the first two
    numbers of ``bounds``.
    """

    @property
    def resolution(self) -> float:
        """Cell side, metres."""

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` as given, metres."""

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` covered by the cells, metres."""

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, columns)``."""

    def cell_centers(self) -> tuple[FloatArray, FloatArray]:
        """Centres of the columns and of the rows, metres."""

    def probabilities(self) -> FloatArray:
        """Occupancy probability of every cell, shape :attr:`shape`."""
