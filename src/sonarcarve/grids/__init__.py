"""Occupancy grids built from sonar readings.

The carved grid, :class:`CarvedGrid` (:mod:`.carved`): an occupancy grid whose occupied band
follows each reading's carved arc over time (paper, section 4). Two baselines:
:class:`OccupancyGrid`, the Elfes/octomap log-odds grid (:mod:`.elfes`), and
:class:`RangeSensorLayer`, a faithful re-implementation of ROS's ``range_sensor_layer``
costmap plugin (:mod:`.range_sensor_layer`). All three are :class:`OccupancyMap` objects:
``probabilities()`` as an array, and :func:`trinary` (occupied 100, free 0, unknown -1).
"""

from sonarcarve.grids.carved import CarvedGrid, CarvedGridParams, trinary
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
    "LETHAL_OBSTACLE",
    "NO_INFORMATION",
    "OCCUPIED",
    "UNKNOWN",
    "CarvedGrid",
    "CarvedGridParams",
    "GridError",
    "InputSensorType",
    "OccupancyGrid",
    "OccupancyMap",
    "RangeSensorLayer",
    "RangeSensorLayerParams",
    "SonarConeModel",
    "angular_term",
    "distance_term",
    "master_costs",
    "sensor_model",
    "trinary",
]
