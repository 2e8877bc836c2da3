"""Occupancy grids built from sonar readings."""

from sonarcarve.grids.elfes import GridError, OccupancyGrid, SonarConeModel

__all__ = ["GridError", "OccupancyGrid", "SonarConeModel"]
