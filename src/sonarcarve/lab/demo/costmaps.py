"""The demo's occupancy grids: the carved grid and ROS's range sensor layer on the same readings.

What robots with sonars run today is ROS's ``range_sensor_layer``, a costmap; the carved grid
(:class:`~sonarcarve.grids.CarvedGrid`, the paper's section 4 proposal) is sonarcarve's. The
demo builds both, with their defaults, over the tour's readings at
:data:`~sonarcarve.lab.demo.scenario.GRID_RESOLUTION`, reads each as a trinary map (occupied,
free, unknown) and measures it against the true walls
(:func:`~sonarcarve.lab.grid_measures.grid_measures`: occupied precision and recall, phantoms,
seen wall covered, the free floor near the robot's path marked free), and times it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from sonarcarve.grids import CarvedGrid, Grid, make_grid, trinary
from sonarcarve.lab.demo.results import GridSummary
from sonarcarve.lab.demo.scenario import GRID_MARGIN, GRID_RESOLUTION, ProgressCallback
from sonarcarve.lab.grid_measures import grid_measures
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import EchoKind

__all__ = ["GRID_KINDS", "GridKind", "grid_bounds", "run_grids"]

Bounds = tuple[float, float, float, float]

#: Readings of the (untimed) run that loads or compiles a grid's kernels before its timed run,
#: beyond a carved grid's history capacity.
_WARM_UP = 64
#: Progress reports per grid: the readings go in this many batches (the map is the same as with
#: one batch; both grids fold readings strictly in order).
_BATCHES = 40


@dataclass(frozen=True)
class GridKind:
    """One grid of the demo: its :func:`~sonarcarve.grids.make_grid` name (as ``sonarcarve
    grid --model`` names it) and its label."""

    kind: str
    label: str

    def make(self, resolution: float, bounds: Bounds) -> Grid:
        """A new grid of this kind, with its defaults."""
        return make_grid(self.kind, resolution, bounds)


#: The demo's grids, in table order: sonarcarve's, then the baseline ROS users run.
GRID_KINDS = (
    GridKind("carved", "carved grid"),
    GridKind("range-sensor-layer", "ROS RangeSensorLayer (defaults)"),
)


def grid_bounds(world_bounds: Bounds, margin: float = GRID_MARGIN) -> Bounds:
    """The rectangle the grids cover: the world's walls grown by ``margin`` metres."""
    xmin, ymin, xmax, ymax = world_bounds
    return xmin - margin, ymin - margin, xmax + margin, ymax + margin


def run_grids(sim: Simulation, resolution: float = GRID_RESOLUTION,
              on_progress: ProgressCallback | None = None,
              seconds: dict[str, float] | None = None) -> tuple[GridSummary, ...]:
    """Every grid of :data:`GRID_KINDS` over all of ``sim``'s readings, measured.

    Parameters
    ----------
    sim : Simulation
        The readings and their truth (walls, reflection points of the direct echoes).
    resolution : float
        Cell side, metres.
    on_progress : callable, optional
        ``on_progress("grid:" + kind, readings done, readings)``.
    seconds : dict, optional
        Receives each grid's wall time (filling, reading, measuring) as ``grid:KIND``.

    Returns
    -------
    tuple of GridSummary
        In :data:`GRID_KINDS` order.
    """
    bounds = grid_bounds(sim.world.bounds)
    direct = sim.truth.kind == EchoKind.DIRECT
    reflections = sim.truth.reflection[direct]
    path = np.column_stack((sim.readings.x, sim.readings.y))
    out = []
    for kind in GRID_KINDS:
        tic = time.perf_counter()
        grid, cells, cpu = _fill(kind, resolution, bounds, sim.readings, on_progress)
        measures = grid_measures(grid, sim.world.segments, reflections, sim.world.bounds,
                                 cells=cells, path=path)
        out.append(GridSummary(kind.kind, kind.label, grid.resolution,
                               (grid.bounds[0], grid.bounds[1]), cells, measures,
                               len(sim.readings), cpu))
        if seconds is not None:
            seconds[f"grid:{kind.kind}"] = time.perf_counter() - tic
    return tuple(out)


def _fill(kind: GridKind, resolution: float, bounds: Bounds, readings: ReadingBatch,
          on_progress: ProgressCallback | None) -> tuple[Grid, np.ndarray, float]:
    """The grid with every reading in, its trinary map, and the processor time both took."""
    # Compile (or load) the kernels first, so that the time is the grid's, not numba's: with
    # enough readings to push arcs out of a carved grid's history (its commit path).
    warm = kind.make(resolution, bounds)
    capacity = warm.method.history.capacity if isinstance(warm, CarvedGrid) else 0
    warm.add_many(readings[:capacity + _WARM_UP])
    trinary(warm)
    del warm
    grid = kind.make(resolution, bounds)
    n = len(readings)
    step = max(1, -(-n // _BATCHES))
    cpu = 0.0
    for start in range(0, n, step):
        tic = time.process_time()  # processor time: the machine may be shared
        grid.add_many(readings[start:start + step])
        cpu += time.process_time() - tic
        if on_progress is not None:
            on_progress(f"grid:{kind.kind}", min(start + step, n), n)
    tic = time.process_time()
    cells = trinary(grid)
    cpu += time.process_time() - tic
    return grid, cells, cpu
