"""Occupancy grids built from sonar readings.

Two baselines: :class:`OccupancyGrid`, the Elfes/octomap log-odds grid (:mod:`.elfes`), and
:class:`RangeSensorLayer`, a faithful re-implementation of ROS's ``range_sensor_layer``
costmap plugin (:mod:`.range_sensor_layer`).
"""

from sonarcarve.grids.elfes import GridError, OccupancyGrid, SonarConeModel
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
    "FREE_SPACE",
    "LETHAL_OBSTACLE",
    "NO_INFORMATION",
    "GridError",
    "InputSensorType",
    "OccupancyGrid",
    "RangeSensorLayer",
    "RangeSensorLayerParams",
    "SonarConeModel",
    "angular_term",
    "distance_term",
    "master_costs",
    "sensor_model",
]
