"""What the demo simulates: its world and tour, its methods, and how it looks at them.

The demo drives a world's built-in tour with a Scout2-like sonar ring and maps the readings
with each of :data:`DEMO_METHODS`. This module holds the settings every other part of
:mod:`sonarcarve.lab.demo` shares, and checks a request before anything runs.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from sonarcarve.errors import SonarcarveError
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.lab.analyses import METHOD_LABELS as EXPERIMENT_LABELS
from sonarcarve.lab.drawing import METHOD_COLORS as EXPERIMENT_COLORS
from sonarcarve.methods import MethodConfig
from sonarcarve.sim.world import World, WorldError, load_world

__all__ = [
    "APPROACH_DISTANCE",
    "CLOSEUP_METHODS",
    "DEMO_METHODS",
    "GRID_MARGIN",
    "GRID_RESOLUTION",
    "METHOD_COLORS",
    "METHOD_LABELS",
    "PAPER_METHODS",
    "SAMPLE_EVERY",
    "DemoError",
    "ProgressCallback",
    "demo_config",
    "load_demo_world",
]


#: The paper's four methods (CLI names): the baseline first, the paper's own last. Figures 1-3
#: show these.
PAPER_METHODS = ("centerline", "atm", "carve", "combined")
#: The methods of the demo, in table order: the paper's, then evidence carving (beyond it).
DEMO_METHODS = (*PAPER_METHODS, "evidence")
#: Row labels of the table and legends.
METHOD_LABELS = {"centerline": "centerline", "atm": "ATM", "carve": "carving",
                 "combined": "combined", "evidence": "evidence carving (beyond the paper)"}
#: One colour per method: the colour of the point source it stands for (``SOURCE_COLORS``);
#: combined, which mixes carved and ATM points, in purple (as in the experiments' figures).
METHOD_COLORS = {name: EXPERIMENT_COLORS[label] for name, label in EXPERIMENT_LABELS.items()}
#: Methods shown in the doorway close-up (the brief of Fig. 2: centerline against carving).
CLOSEUP_METHODS = ("centerline", "carve", "combined")

#: How far before a door the close-up and the door counts look at the local map: metres of
#: driving before the tour passes through the door (or, for doors it does not pass through,
#: the straight-line distance from the robot to the middle of the gap).
APPROACH_DISTANCE = 1.5
#: Readings between two snapshots of the history for the unprocessed share (16 = one cycle of
#: the Scout2 ring, 0.64 s; the experiments use the same).
SAMPLE_EVERY = 16

#: Cell side of the demo's occupancy grids (the carved grid and ROS's range sensor layer),
#: metres: the resolution of the issue's targets that a whole office fits at (610 x 910 cells).
GRID_RESOLUTION = 0.10
#: The grids cover the world's walls plus this margin on every side, metres.
GRID_MARGIN = 0.5

#: ``on_progress(step, done, total)``: ``step`` is ``simulate`` (firings), a method name or
#: ``grid:`` and a grid kind (readings).
ProgressCallback = Callable[[str, int, int], None]


class DemoError(SonarcarveError):
    """A demo request that cannot run: bad option value, world without a tour, bad output path."""


def load_demo_world(world: str | World) -> World:
    """The world of a demo: loaded (:func:`~sonarcarve.sim.world.load_world`) and with a tour.

    Raises
    ------
    WorldError
        Unknown or unreadable world, or one without a tour.
    """
    the_world = world if isinstance(world, World) else load_world(world)
    if the_world.tour is None:
        msg = f"world {the_world.name!r} has no tour to drive; the demo needs one"
        raise WorldError(msg)
    return the_world


def demo_config(history_size: int = DEFAULT_HISTORY_SIZE,
                methods: tuple[str, ...] = DEMO_METHODS, max_length: float | None = None,
                grid_resolution: float | None = GRID_RESOLUTION) -> MethodConfig:
    """The methods' parameters of a demo, after checking the request.

    Raises
    ------
    ConfigError
        ``history_size`` that :class:`~sonarcarve.methods.MethodConfig` refuses (a whole
        number of arcs in [1, :data:`~sonarcarve.history.MAX_HISTORY_SIZE`]); its message names
        the parameter, which the command line rewords as ``--history``.
    DemoError
        An unknown method, or a ``max_length`` or ``grid_resolution`` that is not a finite
        number > 0.
    """
    config = MethodConfig(history_size=history_size)
    unknown = [m for m in methods if m not in DEMO_METHODS]
    if unknown or not methods:
        msg = f"unknown demo method(s) {unknown}; choose from {', '.join(DEMO_METHODS)}"
        raise DemoError(msg)
    if max_length is not None and not (math.isfinite(max_length) and max_length > 0.0):
        msg = f"max_length must be a positive number of metres, got {max_length}"
        raise DemoError(msg)
    if grid_resolution is not None and not (math.isfinite(grid_resolution)
                                            and grid_resolution > 0.0):
        msg = f"grid_resolution must be a positive number of metres, got {grid_resolution}"
        raise DemoError(msg)
    return config
