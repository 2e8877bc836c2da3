"""A sonar simulator with ground truth: worlds, robots, sonar physics and motion."""

from sonarcarve.sim.world import World, WorldError

__all__ = ["World", "WorldError"]
