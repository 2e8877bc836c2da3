"""Occupancy grids built from sonar readings.

The carved grid, :class:`CarvedGrid` (:mod:`.carved`): an occupancy grid whose occupied band
follows each reading's carved arc over time (paper, section 4). Two baselines:
:class:`OccupancyGrid`, the Elfes/octomap log-odds grid (:mod:`.elfes`), and
:class:`RangeSensorLayer`, a faithful re-implementation of ROS's ``range_sensor_layer``
costmap plugin (:mod:`.range_sensor_layer`). All three are :class:`OccupancyMap` objects:
``probabilities()`` as an array, and :func:`trinary` (occupied 100, free 0, unknown -1).

:func:`make_grid` builds one by name (the keys of :data:`GRIDS`, as ``sonarcarve grid --model``
names them), like :func:`~sonarcarve.methods.make_method` for the methods;
:func:`readings_extent` gives the bounds of a grid that holds a whole log.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from sonarcarve.grids.carved import CarvedGrid, CarvedGridParams, trinary
from sonarcarve.grids.cells import readings_extent
from sonarcarve.grids.elfes import GridError, OccupancyGrid, SonarConeModel
from sonarcarve.grids.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from sonarcarve.grids.range_sensor_layer import (
    FREE_SPACE,
    LETHAL_OBSTACLE,
    NO_INFORMATION,
    InputSensorType,
    RangeSensorLayer,
    RangeSensorLayerParams,
    angular_term,
    distance_term,
    master_costs,
    sensor_model,
)

__all__ = [
    "FREE",
    "FREE_SPACE",
    "GRIDS",
    "LETHAL_OBSTACLE",
    "NO_INFORMATION",
    "OCCUPIED",
    "UNKNOWN",
    "CarvedGrid",
    "CarvedGridParams",
    "Grid",
    "GridError",
    "InputSensorType",
    "OccupancyGrid",
    "OccupancyMap",
    "RangeSensorLayer",
    "RangeSensorLayerParams",
    "SonarConeModel",
    "angular_term",
    "distance_term",
    "make_grid",
    "master_costs",
    "readings_extent",
    "sensor_model",
    "trinary",
]

Bounds = tuple[float, float, float, float]
#: Any grid :func:`make_grid` builds.
Grid = CarvedGrid | RangeSensorLayer | OccupancyGrid


def _carved(resolution: float, bounds: Bounds, params: Any) -> Grid:
    return CarvedGrid(resolution, bounds, params=params)


def _layer(resolution: float, bounds: Bounds, params: Any) -> Grid:
    return RangeSensorLayer(resolution, bounds, params)


def _elfes(resolution: float, bounds: Bounds, params: Any) -> Grid:
    return OccupancyGrid(resolution, bounds, params)


#: Grid name -> (the class of its parameters, factory ``(resolution, bounds, params or None)``).
GRIDS: dict[str, tuple[type, Callable[[float, Bounds, Any], Grid]]] = {
    "carved": (CarvedGridParams, _carved),
    "range-sensor-layer": (RangeSensorLayerParams, _layer),
    "elfes": (SonarConeModel, _elfes),
}


def make_grid(name: str, resolution: float, bounds: Bounds,
              params: CarvedGridParams | RangeSensorLayerParams | SonarConeModel | None = None,
              ) -> Grid:
    """A new, empty grid by name.

    Parameters
    ----------
    name : str
        ``"carved"`` (:class:`CarvedGrid`, the paper's section 4), ``"range-sensor-layer"``
        (:class:`RangeSensorLayer`, ROS's costmap layer) or ``"elfes"`` (:class:`OccupancyGrid`,
        the Elfes/octomap log-odds grid); the keys of :data:`GRIDS`.
    resolution : float
        Cell side h, metres (> 0).
    bounds : tuple of float
        ``(xmin, ymin, xmax, ymax)``, metres; e.g. :func:`readings_extent` of a log.
    params : CarvedGridParams, RangeSensorLayerParams or SonarConeModel, optional
        The grid's parameters, of the class :data:`GRIDS` gives for ``name``; default: that
        grid's defaults.

    Raises
    ------
    GridError
        An unknown ``name``, ``params`` of another grid, or a resolution or bounds the grid
        refuses (the message names the parameter).

    Examples
    --------
    >>> make_grid("elfes", 0.5, (0.0, 0.0, 2.0, 1.0)).shape
    (2, 4)
    >>> make_grid("octomap", 0.5, (0.0, 0.0, 2.0, 1.0))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sonarcarve.grids.cells.GridError: unknown grid 'octomap'; choose one of carved, ...
    """
    try:
        params_class, factory = GRIDS[name]
    except (KeyError, TypeError):
        msg = f"unknown grid {name!r}; choose one of {', '.join(GRIDS)}"
        raise GridError(msg) from None
    if params is not None and not isinstance(params, params_class):
        msg = (f"params of the {name} grid must be a {params_class.__name__}, got "
               f"{type(params).__name__}")
        raise GridError(msg)
    return factory(resolution, bounds, params)
