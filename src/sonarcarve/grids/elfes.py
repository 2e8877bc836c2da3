"""The Elfes/octomap baseline: a log-odds occupancy grid with the classic sonar cone model.

This is *not* ROS's ``range_sensor_layer``: it borrows that layer's angular profile and distance
fade but updates clamped log-odds (octomap's way) with its own band and probabilities. The layer
itself, with its unclamped Bayes update on costs and its quirks, is
:mod:`sonarcarve.grids.range_sensor_layer`.

Beyond the paper, which compares arc carving with occupancy grids only in words (section 2-B):
this module lets the comparison be measured (``benchmarks/grid_baseline.py``).

The grid (Moravec & Elfes 1985 [8], Elfes 1987 [7]) divides a rectangle of the world into square
cells and keeps for each the log-odds ``l = ln(p / (1 - p))`` that it is occupied, starting at 0
(p = 1/2, unknown). Each reading adds the log-odds of an *inverse sensor model*, a planar cone,
to the cells it covers (Bayes' rule in log-odds form, cells independent), and every cell is then
clamped to ``[logit(p_min), logit(p_max)]`` so that it can still change its mind.

The cone of a reading from origin ``(x, y)`` along ``θ`` with range ``r`` and beam width ``φ``
(:class:`SonarConeModel`), for a cell whose centre lies at distance ``d`` and at angle ``α``
off the axis (in ``(-π, π]``), with weight ``w``:

- outside the beam (``|α| > φ/2``) or beyond the echo (``d > r + b``): unchanged (unknown);
- free, ``d < r - b``: ``l += w · logit(p_miss)`` (a decrement: ``p_miss < 1/2``);
- occupied, ``|d - r| <= b``: ``l += w · logit(p_hit)`` on the whole arc, since the echo came
  from *somewhere* on it (the azimuth uncertainty, paper section 2; [8] calls this region
  "somewhere occupied": overlapping free regions of other readings condense it).

The weight ``w = (1 - (2α/φ)²) · f(d)`` is 1 on the axis and 0 at the beam's edges, the angular
profile of Elfes' model [7] and of ROS's ``range_sensor_layer`` (costmap_2d plugin), times that
layer's distance fade ``f(d) = (1 - tanh(2 (d - d_f))) / 2`` (``fade_range`` ``d_f``, ROS's
``phi``, 1.2 m by default; ``inf`` switches it off: Elfes' cone). The band half-width is
``b = (h + ε) / 2`` for cell size ``h`` and range tolerance ``ε``: a wall at distance r passes
through cells whose centres lie up to h/2 from it, and the range itself is uncertain by about
ε/2 (carving's ε, :data:`~sonarcarve.methods.carving.DEFAULT_RANGE_TOLERANCE`). With ``b = h/2``
alone, wall cells on the band's edge were cleared by their own readings' noise.

Defaults, as ROS users get them: ``p_hit = 0.7``, ``p_miss = 0.4``, clamped to ``[0.12, 0.97]``
(``octomap_server``'s ``sensor_model/hit``, ``miss``, ``min``, ``max``), the 1.2 m fade and
angular profile of ``range_sensor_layer``, and :data:`DEFAULT_OCCUPIED_THRESHOLD` (0.65) for
:meth:`OccupancyGrid.occupied_points`, between that layer's ``clear_threshold`` 0.2 and
``mark_threshold`` 0.8. What the fade does, measured with ``benchmarks/grid_baseline.py``
(Scout2 ring, 3 seeds, 0.05 m cells): in the office's 2.2 m corridors it is what makes the grid
usable (median / p90 distance of occupied cells to the walls 0.035 / 0.070 m with it, 0.235 /
1.207 m without: without it, long echoes through the wide cone clear true walls and leave whole
arcs marked); in the 8 m doorway room it maps under 10 % of the wall length seen, and a door
1 m ahead stays unknown (no cell of it below p = 0.2), not free.

A cell is judged by its centre only: the grid's resolution is the map's resolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.cells import CellGrid, GridError, bounds_around, check_probability, logit
from sonarcarve.grids.scan import cell_range, sector_box
from sonarcarve.methods.config import DEFAULT_RANGE_TOLERANCE, MAX_RANGE_TOLERANCE
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch
from sonarcarve.typing import FloatArray

__all__ = [
    "DEFAULT_OCCUPIED_THRESHOLD",
    "MAX_CELLS",
    "ROS_FADE_RANGE",
    "GridError",
    "OccupancyGrid",
    "SonarConeModel",
]

GridArray = npt.NDArray[np.float32]

#: Probability above which :meth:`OccupancyGrid.occupied_points` calls a cell occupied. Chosen
#: by measurement (``benchmarks/grid_baseline.py``, threshold table: office, 3 seeds, 0.05 m,
#: default model): 0.5 leaves 40 % of occupied cells more than 0.25 m from any wall, 0.65
#: 0.2 % at 78 % of the seen wall length covered, 0.8 none but covers 63 %.
DEFAULT_OCCUPIED_THRESHOLD = 0.65
#: ROS ``range_sensor_layer``'s default distance fade (its parameter ``phi``), metres.
ROS_FADE_RANGE = 1.2
#: Most cells a grid may have: 2**28 float32 cells are 1 GiB (a 0.05 m grid of 819 m x 819 m).
MAX_CELLS = 2**28

#: Slope of ROS range_sensor_layer's distance fade, 1/m (its ``delta(phi)``: ``tanh(2 (d - phi))``).
_FADE_SLOPE = 2.0

@dataclass(frozen=True)
class SonarConeModel:
    """Parameters of the cone inverse sensor model (module docstring; Elfes 1987 [7]).

    Attributes
    ----------
    beam_width : float
        φ for readings whose beam width is NaN, radians in (0, π); default 22.5° (paper).
    range_tolerance : float
        ε, metres >= 0: the occupied band is ``r ± (h + ε)/2`` for cell size h; default
        carving's 5 cm.
    p_hit : float
        Occupancy probability one reading gives an on-axis cell of its arc band (before the
        fade), in (0.5, 1).
    p_miss : float
        Occupancy probability one reading gives an on-axis free cell (before the fade), in
        (0, 0.5).
    p_min, p_max : float
        Clamp of every cell's probability, ``p_min < 0.5 < p_max``.
    fade_range : float
        ROS ``range_sensor_layer``'s distance fade (its parameter ``phi``), metres > 0: every
        update of a cell at distance d is scaled by ``(1 - tanh(2 (d - fade_range))) / 2``
        (1/2 at ``fade_range``, under 2 % a metre beyond). Default :data:`ROS_FADE_RANGE`;
        ``inf`` switches it off (Elfes' cone).
    """

    beam_width: float = DEFAULT_BEAM_WIDTH
    range_tolerance: float = DEFAULT_RANGE_TOLERANCE
    p_hit: float = 0.7
    p_miss: float = 0.4
    p_min: float = 0.12
    p_max: float = 0.97
    fade_range: float = ROS_FADE_RANGE

    def __post_init__(self) -> None:
        if not (math.isfinite(self.beam_width) and 0.0 < self.beam_width < math.pi):
            msg = f"grid: beam_width must lie in (0, pi) radians, got {self.beam_width!r}"
            raise GridError(msg)
        if not 0.0 <= self.range_tolerance <= MAX_RANGE_TOLERANCE:
            msg = (f"grid: range_tolerance must be a number in [0, {MAX_RANGE_TOLERANCE:g}] "
                   f"metres, got {self.range_tolerance!r}")
            raise GridError(msg)
        check_probability("grid", "p_hit", self.p_hit, 0.5, 1.0)
        check_probability("grid", "p_miss", self.p_miss, 0.0, 0.5)
        check_probability("grid", "p_min", self.p_min, 0.0, 0.5)
        check_probability("grid", "p_max", self.p_max, 0.5, 1.0)
        if math.isnan(self.fade_range) or self.fade_range <= 0.0:
            msg = f"grid: fade_range must be > 0 metres (inf: no fade), got {self.fade_range!r}"
            raise GridError(msg)

    @property
    def log_odds(self) -> tuple[float, float, float, float]:
        """``(l_hit, l_miss, l_min, l_max)``: the four probabilities as log-odds."""
        return (logit(self.p_hit), logit(self.p_miss), logit(self.p_min),
                logit(self.p_max))


class OccupancyGrid(CellGrid):
    """Log-odds occupancy grid over a rectangle, updated with :class:`SonarConeModel`.

    Cell ``(i, j)`` (row ``i`` along y, column ``j`` along x) is the square of side
    ``resolution`` whose centre is ``(xmin + (j + 1/2) h, ymin + (i + 1/2) h)``; the grid has
    ``ceil((xmax - xmin) / h)`` columns and ``ceil((ymax - ymin) / h)`` rows, so it may reach a
    little past ``xmax, ymax`` (:attr:`extent`). Readings partly outside update the cells inside.

    Parameters
    ----------
    resolution : float
        Cell side h, metres (> 0).
    bounds : tuple of 4 floats
        ``(xmin, ymin, xmax, ymax)`` of the mapped rectangle, metres.
    model : SonarConeModel, optional
        The inverse sensor model (default: :class:`SonarConeModel` defaults).

    Attributes
    ----------
    log_odds : ndarray of float32, shape (rows, columns)
        The state: each cell's log-odds of occupancy (0 = unknown). Updated in place.
    readings : int
        Readings folded in so far.

    Raises
    ------
    GridError
        A resolution or bounds that are not finite, not positive, or need more than
        :data:`MAX_CELLS` cells.

    Examples
    --------
    >>> g = OccupancyGrid(0.1, (0.0, 0.0, 2.0, 1.0))
    >>> g.shape, g.nbytes
    ((10, 20), 800)
    >>> g.add(Reading(t=0.0, sensor=0, x=0.05, y=0.55, theta=0.0, range=1.0))
    >>> p = g.probabilities()
    >>> float(p[5, 10].round(3)), float(p[5, 5].round(3))  # on the axis: the arc, free space
    (0.642, 0.406)
    >>> g.occupied_points(0.6).round(2).tolist()  # the arc's cells near the axis
    [[1.05, 0.45], [1.05, 0.55], [1.05, 0.65]]
    """

    def __init__(self, resolution: float, bounds: tuple[float, float, float, float],
                 model: SonarConeModel | None = None) -> None:
        super().__init__("grid", resolution, bounds, MAX_CELLS, "MAX_CELLS")
        ny, nx = self._shape
        self._model = model if model is not None else SonarConeModel()
        self.log_odds: GridArray = np.zeros((ny, nx), dtype=np.float32)
        self.readings = 0

    def __repr__(self) -> str:
        ny, nx = self.shape
        return (f"OccupancyGrid({self._resolution:g} m, {nx} x {ny} cells, "
                f"bounds={self._bounds}, {self.readings} readings)")

    @property
    def model(self) -> SonarConeModel:
        """The inverse sensor model."""
        return self._model

    @classmethod
    def around(cls, extent: tuple[float, float, float, float], resolution: float,
               margin: float = 0.5, model: SonarConeModel | None = None) -> OccupancyGrid:
        """A grid over ``extent = (xmin, ymin, xmax, ymax)`` (for example a world's
        ``bounds``) grown by ``margin`` metres on every side.

        Raises
        ------
        GridError
            A negative or non-finite margin; a flat extent and no margin.
        """
        return cls(resolution, bounds_around("grid", extent, margin), model or SonarConeModel())

    # -- shape -------------------------------------------------------------------------------

    @property
    def nbytes(self) -> int:
        """Memory of the grid's state (the float32 log-odds array), bytes."""
        return int(self.log_odds.nbytes)

    # -- updates -----------------------------------------------------------------------------

    def add(self, reading: Reading) -> None:
        """Fold one reading into the grid (validated like a :class:`ReadingBatch` row)."""
        self.add_many(ReadingBatch.from_readings([reading]))

    def add_many(self, batch: ReadingBatch) -> None:
        """Fold every reading of ``batch`` into the grid, in order (clamping after each).

        A no-echo reading (``range`` = +inf) is free space only: every cell of its cone up to
        its ``max_range`` gets the miss update (same angular profile and fade), no hit band.
        """
        if not len(batch):
            return
        phi = batch.beam_widths(self.model.beam_width)
        l_hit, l_miss, l_min, l_max = self.model.log_odds
        no_echo = batch.range == math.inf
        if not no_echo.any():
            _update_kernel(self.log_odds, self.bounds[0], self.bounds[1], self.resolution,
                           batch.x, batch.y, batch.theta, batch.range, phi, self.band,
                           self.model.fade_range, l_hit, l_miss, l_min, l_max)
            self.readings += len(batch)
            return
        # Runs of echoes and of no-echo readings, in order. A no-echo run is the same update
        # at range max_range - b (so that the cone reaches max_range) with the hit taken as a
        # miss: the whole cone is free, there is no band.
        r = np.where(no_echo, batch.max_range - self.band, batch.range)
        edges = np.flatnonzero(np.diff(no_echo.astype(np.int8))) + 1
        for part in np.split(np.arange(len(batch)), edges):
            free_only = bool(no_echo[part[0]])
            _update_kernel(self.log_odds, self.bounds[0], self.bounds[1], self.resolution,
                           batch.x[part], batch.y[part], batch.theta[part], r[part], phi[part],
                           self.band, self.model.fade_range, l_miss if free_only else l_hit,
                           l_miss, l_min, l_max)
        self.readings += len(batch)

    @property
    def band(self) -> float:
        """Half-width b of the occupied band around the range, metres: ``(h + ε) / 2``."""
        return 0.5 * (self.resolution + self.model.range_tolerance)

    def reset(self) -> None:
        """Forget everything: every cell back to p = 1/2."""
        self.log_odds.fill(0.0)
        self.readings = 0

    # -- reading the map ---------------------------------------------------------------------

    def probabilities(self) -> FloatArray:
        """Occupancy probability of every cell, shape :attr:`shape`, ``1 / (1 + exp(-l))``."""
        return np.asarray(1.0 / (1.0 + np.exp(-self.log_odds.astype(np.float64))))

    def occupied_mask(self, threshold: float = DEFAULT_OCCUPIED_THRESHOLD) -> npt.NDArray[np.bool_]:
        """Cells whose probability is strictly above ``threshold`` (in (0, 1)), shape :attr:`shape`.

        Evaluated as ``l > logit(threshold)`` in float64, without a float64 copy of the grid.
        """
        limit = check_probability("grid", "threshold", threshold, 0.0, 1.0)
        return np.asarray(self.log_odds > np.float64(logit(limit)))

    def occupied_points(self, threshold: float = DEFAULT_OCCUPIED_THRESHOLD) -> FloatArray:
        """Centres of the occupied cells (:meth:`occupied_mask`), shape (n, 2), metres.

        Row-major order (by y, then x): the grid as a point map, comparable with a
        :class:`~sonarcarve.maps.GlobalMap`'s ``xy``.
        """
        rows, cols = np.nonzero(self.occupied_mask(threshold))
        xs, ys = self.cell_centers()
        return np.column_stack((xs[cols], ys[rows])).astype(np.float64)


@compiled_inline
def _beam_cells(x: float, y: float, theta: float, half: float, reach: float, xmin: float,
                ymin: float, h: float, nx: int, ny: int) -> tuple[int, int, int, int]:
    """Columns ``j0..j1`` and rows ``i0..i1`` whose centres may lie in the beam: those of the
    bounding box of the sector of radius ``reach`` from ``(x, y)`` over ``θ ± half``
    (:func:`~sonarcarve.grids.scan.sector_box` with ``r_in = 0``), one cell of slack each side
    against rounding (the cone test decides each cell exactly)."""
    xlo, ylo, xhi, yhi = sector_box(x, y, theta - half, theta + half, 0.0, reach)
    j0, j1 = cell_range(xlo, xhi, xmin, h, nx)
    i0, i1 = cell_range(ylo, yhi, ymin, h, ny)
    return j0, j1, i0, i1


def _update_py(log_odds: GridArray, xmin: float, ymin: float, h: float,
               x: FloatArray, y: FloatArray, theta: FloatArray, r: FloatArray, phi: FloatArray,
               band: float, fade: float, l_hit: float, l_miss: float, l_min: float,
               l_max: float) -> None:
    # One reading at a time over the cells of the beam's bounding box. Cheap tests first (the
    # distance, then the bearing through a dot product): about half the box lies outside the
    # cone, and only cells inside pay for atan2.
    ny, nx = log_odds.shape
    for k in range(x.shape[0]):
        xk, yk, rk, half = x[k], y[k], r[k], 0.5 * phi[k]
        c, s, cos_half = math.cos(theta[k]), math.sin(theta[k]), math.cos(half)
        reach = rk + band
        j0, j1, i0, i1 = _beam_cells(xk, yk, theta[k], half, reach, xmin, ymin, h, nx, ny)
        for i in range(i0, i1 + 1):
            dy = ymin + (i + 0.5) * h - yk
            for j in range(j0, j1 + 1):
                dx = xmin + (j + 0.5) * h - xk
                d2 = dx * dx + dy * dy
                if d2 > reach * reach:
                    continue
                d = math.sqrt(d2)
                along = dx * c + dy * s
                if along < d * cos_half:
                    continue
                a = math.atan2(dy * c - dx * s, along)
                w = 1.0 - (a / half) ** 2
                if fade < math.inf:
                    w *= 0.5 * (1.0 - math.tanh(_FADE_SLOPE * (d - fade)))
                step = w * l_miss if d < rk - band else w * l_hit
                log_odds[i, j] = min(l_max, max(l_min, log_odds[i, j] + step))


#: Compiled update. Measured against the numpy version below (``benchmarks/grid_baseline.py``,
#: engine table, office, 13,534 readings, one core): 33k against 15k readings/s at 0.05 m,
#: 444k against 20k at 0.20 m. numpy pays a fixed cost per reading, the loop only per cell.
_update_kernel = compiled(_update_py)


def _update_numpy(log_odds: GridArray, xmin: float, ymin: float, h: float,
                  x: FloatArray, y: FloatArray, theta: FloatArray, r: FloatArray,
                  phi: FloatArray, band: float, fade: float, l_hit: float, l_miss: float,
                  l_min: float, l_max: float) -> None:
    """The same update as :func:`_update_kernel`, vectorised with numpy over each reading's box.

    Kept as an independent implementation: the tests check the compiled kernel against it and
    the benchmark times both.
    """
    ny, nx = log_odds.shape
    for xk, yk, tk, rk, pk in zip(x.tolist(), y.tolist(), theta.tolist(), r.tolist(),
                                  phi.tolist(), strict=True):
        reach = rk + band
        j0, j1, i0, i1 = _beam_cells(xk, yk, tk, 0.5 * pk, reach, xmin, ymin, h, nx, ny)
        if j1 < j0 or i1 < i0:
            continue
        dx = xmin + (np.arange(j0, j1 + 1) + 0.5) * h - xk
        dy = (ymin + (np.arange(i0, i1 + 1) + 0.5) * h - yk)[:, None]
        d = np.sqrt(dx * dx + dy * dy)
        along = dx * math.cos(tk) + dy * math.sin(tk)
        inside = (d * d <= reach * reach) & (along >= d * math.cos(0.5 * pk))
        a = np.arctan2(dy * math.cos(tk) - dx * math.sin(tk), along)[inside]
        w = 1.0 - (a / (0.5 * pk)) ** 2
        if fade < math.inf:
            w *= 0.5 * (1.0 - np.tanh(_FADE_SLOPE * (d[inside] - fade)))
        step = np.where(d[inside] < rk - band, w * l_miss, w * l_hit)
        box = log_odds[i0 : i1 + 1, j0 : j1 + 1]
        box[inside] = np.clip(box[inside] + step, l_min, l_max)
