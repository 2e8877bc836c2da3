"""What a demo measured: one :class:`MethodSummary` per method, one :class:`GridSummary` per
occupancy grid, and the whole :class:`DemoResult`.

These records are what the table (:mod:`~sonarcarve.lab.demo.table`) and the figures
(:mod:`~sonarcarve.lab.demo.figures`) are drawn from; :func:`~sonarcarve.lab.demo.run_demo`
makes them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from sonarcarve.lab.demo.doors import DoorApproach, LocalView
from sonarcarve.lab.demo.scenario import METHOD_LABELS
from sonarcarve.lab.grid_measures import GridMeasures
from sonarcarve.lab.output import json_ready
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import MethodConfig
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.world import World
from sonarcarve.typing import FloatArray, Int8Array

__all__ = ["DemoResult", "FilterSummary", "GridSummary", "MethodSummary"]


@dataclass(frozen=True)
class MethodSummary:
    """One row of the demo table: one method over the whole tour.

    Attributes
    ----------
    method : str
        CLI name (``centerline``, ``atm``, ``carve``, ``combined``).
    readings : int
        Readings the method processed.
    unprocessed_pct : float
        Mean share of the history not yet processed, percent (Table I): over snapshots every
        :data:`~sonarcarve.lab.demo.scenario.SAMPLE_EVERY` readings once the history is full
        (all snapshots if it never is).
        Arcs carving removed stay in the history and count as processed (the library's
        measure); the paper's history drops them.
    median_error_m, p90_error_m : float
        Median and 90th percentile distance of the global map's points to the true walls, m.
    fully_carved_pct : float
        Share of all readings whose arc carving emptied completely, percent (section 5-C;
        evidence carving: no bin of the arc's profile survived).
    spurious_removed_pct : float
        Of the spurious readings (crosstalk, floor and multipath echoes), the share missing
        from the method's global map (fully carved, or split and dropped; evidence carving
        also leaves out arcs below its confidence), percent; NaN if there were no spurious
        readings.
    true_lost_pct : float
        Of the direct readings (true echoes off a wall), the share left out the same way,
        percent; NaN if there were none.
    map_points : int
        Points in the global map.
    seconds : float
        Time spent inside the method (snapshots excluded), seconds.
    """

    method: str
    readings: int
    unprocessed_pct: float
    median_error_m: float
    p90_error_m: float
    fully_carved_pct: float
    spurious_removed_pct: float
    true_lost_pct: float
    map_points: int
    seconds: float

    @property
    def label(self) -> str:
        """The method's display name."""
        return METHOD_LABELS.get(self.method, self.method)

    @property
    def readings_per_second(self) -> float:
        """Throughput of the method on this tour."""
        return self.readings / self.seconds if self.seconds > 0.0 else math.inf

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN and inf become None)."""
        row: dict[str, Any] = {"method": self.method, "label": self.label}
        for name in ("readings", "unprocessed_pct", "median_error_m", "p90_error_m",
                     "fully_carved_pct", "spurious_removed_pct", "true_lost_pct", "map_points",
                     "seconds", "readings_per_second"):
            row[name] = json_ready(getattr(self, name))
        return row


@dataclass(frozen=True)
class FilterSummary:
    """A method's final map after the occlusion map filter (``sonarcarve process
    --occlusion-depth``): what the demo's caption adds to that method's table row.

    Attributes
    ----------
    method : str
        The method whose global map was filtered (``evidence``).
    depth_m : float
        The filter's depth, metres (:data:`~sonarcarve.filters.OCCLUSION_DEPTH`).
    spurious_removed_pct, true_lost_pct : float
        As :class:`MethodSummary`'s, for the filtered map, percent.
    map_points : int
        Points left.
    """

    method: str
    depth_m: float
    spurious_removed_pct: float
    true_lost_pct: float
    map_points: int

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN becomes None)."""
        return {name: json_ready(getattr(self, name)) for name in
                ("method", "depth_m", "spurious_removed_pct", "true_lost_pct", "map_points")}


@dataclass(frozen=True, eq=False)
class GridSummary:
    """One row of the demo's grid table: one occupancy grid over the whole tour.

    Attributes
    ----------
    kind : str
        The grid's ``sonarcarve grid --model`` name (``carved``, ``range-sensor-layer``).
    label : str
        Display name.
    resolution : float
        Cell side, metres.
    origin : tuple of 2 floats
        ``(x, y)`` of the lower-left corner of cell ``(0, 0)``, metres.
    cells : ndarray of int8, shape (rows, columns)
        The trinary map (:func:`~sonarcarve.grids.trinary`): 100 occupied, 0 free, -1 unknown;
        row 0 the bottom (y up).
    measures : GridMeasures
        The map against the true walls (:func:`~sonarcarve.lab.grid_measures.grid_measures`).
    readings : int
        Readings folded in.
    cpu_seconds : float
        Processor time of folding the readings in and reading the trinary map once, seconds
        (kernels compiled beforehand).
    """

    kind: str
    label: str
    resolution: float
    origin: tuple[float, float]
    cells: Int8Array
    measures: GridMeasures
    readings: int
    cpu_seconds: float

    @property
    def cpu_us_per_reading(self) -> float:
        """Processor time per reading, microseconds (NaN without readings)."""
        return 1e6 * self.cpu_seconds / self.readings if self.readings else math.nan

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` covered by the cells, metres."""
        rows, cols = self.cells.shape
        x0, y0 = self.origin
        return x0, y0, x0 + cols * self.resolution, y0 + rows * self.resolution

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the settings and measures (shares in [0, 1]; NaN becomes None)."""
        rows, cols = self.cells.shape
        row: dict[str, Any] = {"kind": self.kind, "label": self.label,
                               "resolution_m": self.resolution, "origin": list(self.origin),
                               "rows": rows, "columns": cols}
        row |= {name: json_ready(value) for name, value in self.measures._asdict().items()}
        row |= {"readings": self.readings, "cpu_seconds": self.cpu_seconds,
                "cpu_us_per_reading": json_ready(self.cpu_us_per_reading)}
        return row


@dataclass(frozen=True, eq=False)
class DemoResult:
    """Everything :func:`run_demo` measured, ready for the table and the figures.

    Attributes
    ----------
    world : World
        The simulated world.
    seed : int
        Simulation seed.
    config : MethodConfig
        The methods' parameters.
    simulation : Simulation
        The readings and their ground truth.
    methods : tuple of MethodSummary
        One row per method, in :data:`~sonarcarve.lab.demo.scenario.DEMO_METHODS` order.
    global_maps : dict of str to GlobalMap
        Method -> its global map.
    map_errors : dict of str to ndarray
        Method -> distance of each global map point to the true walls, metres, shape (points,).
    doors : tuple of DoorApproach
        Every door the tour approaches, in tour order.
    closeup : DoorApproach or None
        The door shown in the close-up figure (None when the tour approaches none).
    fallback_view : LocalView or None
        Local maps at mid-tour, for the close-up when there is no door.
    grids : tuple of GridSummary
        The occupancy grids of the same readings (carved grid, then ROS's range sensor layer);
        empty when the run built none.
    seconds : dict of str to float
        Wall time per step (``simulate``, each method incl. its snapshots, ``measure``, each
        grid as ``grid:KIND`` incl. its measures).
    door_scene : DemoResult or None
        The approach to the doorway world's 0.85 m door (the paper's Fig. 2), run beside the
        tour when no door of the tour tells the methods apart (:func:`run_demo`); fig. 4 and
        the animation then draw it (:attr:`door_source`). None: they draw this tour's door.
    occlusion : FilterSummary or None
        Evidence carving's final map after the occlusion map filter (None when evidence
        carving did not run).
    """

    world: World
    seed: int
    config: MethodConfig
    simulation: Simulation
    methods: tuple[MethodSummary, ...]
    global_maps: dict[str, GlobalMap]
    map_errors: dict[str, FloatArray]
    doors: tuple[DoorApproach, ...]
    closeup: DoorApproach | None
    fallback_view: LocalView | None
    grids: tuple[GridSummary, ...]
    seconds: dict[str, float]
    door_scene: DemoResult | None = None
    occlusion: FilterSummary | None = None

    @property
    def door_source(self) -> DemoResult:
        """The run whose door fig. 4 and the animation draw: :attr:`door_scene` if any, else
        this one."""
        return self.door_scene if self.door_scene is not None else self

    def summary(self, method: str) -> MethodSummary:
        """The table row of ``method``."""
        for row in self.methods:
            if row.method == method:
                return row
        msg = f"no method {method!r} in this demo"
        raise KeyError(msg)

    def grid(self, kind: str) -> GridSummary:
        """The grid table row of ``kind``."""
        for row in self.grids:
            if row.kind == kind:
                return row
        msg = f"no grid {kind!r} in this demo"
        raise KeyError(msg)
