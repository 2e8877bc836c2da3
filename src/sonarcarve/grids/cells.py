"""What every grid checks of its cells: a resolution and bounds, and how many cells they make.

One check for :class:`~sonarcarve.grids.OccupancyGrid`, :class:`~sonarcarve.grids.RangeSensorLayer`
and :class:`~sonarcarve.grids.CarvedGrid` (and one of the margin of a grid made ``around`` an
extent, :func:`bounds_around`), so their errors read alike and a limit cannot be forgotten by one
of them. The log-odds grids also share their probability check (:func:`check_probability`) and
:func:`logit` from here; and the extent a log's readings cover (:func:`readings_extent`), which a
grid over the whole log is made around.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from sonarcarve.constants import DEFAULT_BEAM_WIDTH
from sonarcarve.errors import SonarcarveError
from sonarcarve.typing import FloatArray

if TYPE_CHECKING:
    from sonarcarve.readings import ReadingBatch

__all__ = [
    "CellGrid",
    "GridError",
    "bounds_around",
    "check_probability",
    "check_real",
    "grid_cells",
    "logit",
    "readings_extent",
]

Bounds = tuple[float, float, float, float]


class GridError(SonarcarveError, ValueError):
    """A grid parameter out of range: resolution, bounds, model probabilities, threshold."""


def grid_cells(label: str, resolution: object, bounds: object, max_cells: int,
               limit_name: str) -> tuple[float, Bounds, int, int]:
    """``(h, (xmin, ymin, xmax, ymax), columns, rows)`` of a grid, or :class:`GridError`.

    ``label`` starts every message (``"grid"``, ``"carved grid"``, ...); ``max_cells`` bounds
    the cell count, named ``limit_name`` in the message, before anything is allocated.

    Examples
    --------
    >>> grid_cells("grid", 0.1, (0, 0, 1, 0.55), 100, "MAX_CELLS")
    (0.1, (0.0, 0.0, 1.0, 0.55), 10, 6)
    >>> try:
    ...     grid_cells("grid", 0.1, (0, 0, 1, 0), 100, "MAX_CELLS")
    ... except GridError as err:
    ...     print(err)
    grid: bounds need xmax > xmin and ymax > ymin, got (0, 0, 1, 0)
    """
    h = resolution
    if isinstance(h, bool) or not isinstance(h, int | float) or not math.isfinite(h) or h <= 0:
        msg = f"{label}: resolution must be a finite number > 0 metres, got {h!r}"
        raise GridError(msg)
    try:
        xmin, ymin, xmax, ymax = (float(v) for v in bounds)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        msg = f"{label}: bounds must be 4 numbers (xmin, ymin, xmax, ymax), got {bounds!r}"
        raise GridError(msg) from None
    if not all(math.isfinite(v) for v in (xmin, ymin, xmax, ymax)):
        msg = f"{label}: bounds must be finite, got {bounds!r}"
        raise GridError(msg)
    if not (xmax > xmin and ymax > ymin):
        msg = f"{label}: bounds need xmax > xmin and ymax > ymin, got {bounds!r}"
        raise GridError(msg)
    # The small allowance keeps a width that is a whole number of cells from gaining one.
    nx = max(1, math.ceil((xmax - xmin) / h - 1e-9))
    ny = max(1, math.ceil((ymax - ymin) / h - 1e-9))
    if nx * ny > max_cells:
        # The bounds say where the size comes from: a stray pose 900 km away, UTM coordinates.
        msg = (f"{label}: {nx} x {ny} cells of {h:g} m exceed the limit of {max_cells:,} "
               f"({limit_name}) over x from {xmin:.6g} to {xmax:.6g} m and y from {ymin:.6g} "
               f"to {ymax:.6g} m; use a coarser resolution or smaller bounds")
        raise GridError(msg)
    return float(h), (xmin, ymin, xmax, ymax), nx, ny


def bounds_around(label: str, extent: Bounds, margin: float) -> Bounds:
    """``extent = (xmin, ymin, xmax, ymax)`` grown by ``margin`` metres on every side: the
    bounds of a grid made ``around`` it, or :class:`GridError` (its message starting with
    ``label``) for a negative or non-finite margin. The extent itself is checked by the grid
    (:func:`grid_cells`): a flat extent needs a margin.

    Examples
    --------
    >>> bounds_around("grid", (0.0, 0.0, 4.0, 3.0), 0.5)
    (-0.5, -0.5, 4.5, 3.5)
    >>> try:
    ...     bounds_around("carved grid", (0.0, 0.0, 4.0, 3.0), -1.0)
    ... except GridError as err:
    ...     print(err)
    carved grid: margin must be a finite number >= 0 metres, got -1.0
    """
    if not (math.isfinite(margin) and margin >= 0.0):
        msg = f"{label}: margin must be a finite number >= 0 metres, got {margin!r}"
        raise GridError(msg)
    xmin, ymin, xmax, ymax = extent
    return xmin - margin, ymin - margin, xmax + margin, ymax + margin


def logit(p: float) -> float:
    """The log-odds ``ln(p / (1 - p))`` of a probability ``p`` in (0, 1).

    Examples
    --------
    >>> logit(0.5)
    0.0
    """
    return math.log(p / (1.0 - p))


def check_probability(label: str, name: str, value: object, lo: float, hi: float) -> float:
    """``value`` as a float if it is a real number (an int or a float, not a bool) in the open
    interval ``(lo, hi)``; else :class:`GridError` ``"<label>: <name> must lie in (lo, hi),
    got <value>"``.

    Examples
    --------
    >>> check_probability("grid", "p_hit", 0.7, 0.5, 1.0)
    0.7
    >>> try:
    ...     check_probability("carved grid", "p_hit", "0.7", 0.5, 1.0)
    ... except GridError as err:
    ...     print(err)
    carved grid: p_hit must lie in (0.5, 1), got '0.7'
    """
    ok = (not isinstance(value, bool) and isinstance(value, int | float)
          and math.isfinite(value) and lo < value < hi)
    if not ok:
        msg = f"{label}: {name} must lie in ({lo:g}, {hi:g}), got {value!r}"
        raise GridError(msg)
    return float(value)  # type: ignore[arg-type]


def check_real(label: str, name: str, value: object, ok: Callable[[float], bool],
               rule: str) -> float:
    """``value`` as a float if it is a real number (an int or a float, not a bool) for which
    ``ok`` holds; else :class:`GridError` ``"<label>: <name> must be <rule>, got <value>"``.
    ``ok`` sees only numbers, and must be false for NaN unless NaN is allowed.

    Examples
    --------
    >>> try:
    ...     check_real("carved grid", "band_profile", True, lambda v: v >= 0.0,
    ...                "a finite number >= 0")
    ... except GridError as err:
    ...     print(err)
    carved grid: band_profile must be a finite number >= 0, got True
    """
    if isinstance(value, bool) or not isinstance(value, int | float) or not ok(value):
        msg = f"{label}: {name} must be {rule}, got {value!r}"
        raise GridError(msg)
    return float(value)


def readings_extent(batch: ReadingBatch, margin: float = 0.0) -> Bounds:
    """``(xmin, ymin, xmax, ymax)`` of the sensors and their arcs, grown by ``margin`` metres:
    the bounds of a grid that holds every reading of ``batch``.

    An arc counts by both beam edges and its axis at the range (a no-echo reading's, range
    ``inf``, at its ``max_range``: the free space it clears); a reading without a beam width
    (NaN) has :data:`~sonarcarve.constants.DEFAULT_BEAM_WIDTH`.

    Raises
    ------
    GridError
        No readings, or a negative or non-finite ``margin`` (:func:`bounds_around`).

    Examples
    --------
    >>> from sonarcarve.readings import Reading, ReadingBatch
    >>> batch = ReadingBatch.from_readings([Reading(0.0, 0, 1.0, 2.0, 0.0, 3.0)])  # 22.5°
    >>> tuple(round(v, 2) for v in readings_extent(batch, margin=0.5))
    (0.5, 0.91, 4.5, 3.09)
    """
    if not len(batch):
        msg = "readings extent: no readings"
        raise GridError(msg)
    width = batch.beam_widths(DEFAULT_BEAM_WIDTH)
    reach = np.where(np.isfinite(batch.range), batch.range, batch.max_range)
    xs, ys = [batch.x], [batch.y]
    for k in (-0.5, 0.0, 0.5):
        xs.append(batch.x + reach * np.cos(batch.theta + k * width))
        ys.append(batch.y + reach * np.sin(batch.theta + k * width))
    x, y = np.concatenate(xs), np.concatenate(ys)
    extent = float(x.min()), float(y.min()), float(x.max()), float(y.max())
    return bounds_around("readings extent", extent, margin)


class CellGrid:
    """The cells every grid lays over the plane: checked by :func:`grid_cells`, then the
    geometry the grids share (resolution, bounds, shape, extent, cell centres)."""

    def __init__(self, label: str, resolution: object, bounds: object, max_cells: int,
                 limit_name: str) -> None:
        self._resolution, self._bounds, nx, ny = grid_cells(label, resolution, bounds,
                                                            max_cells, limit_name)
        self._shape = (ny, nx)

    @property
    def resolution(self) -> float:
        """Cell side h, metres."""
        return self._resolution

    @property
    def bounds(self) -> Bounds:
        """``(xmin, ymin, xmax, ymax)`` as given, metres (see :attr:`extent`)."""
        return self._bounds

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, columns)`` = cells along y, along x."""
        return self._shape

    @property
    def extent(self) -> Bounds:
        """``(xmin, ymin, xmax, ymax)`` actually covered by the cells, metres."""
        ny, nx = self._shape
        xmin, ymin = self._bounds[0], self._bounds[1]
        return xmin, ymin, xmin + nx * self._resolution, ymin + ny * self._resolution

    def cell_centers(self) -> tuple[FloatArray, FloatArray]:
        """``(xs, ys)``: centres of the columns, shape (columns,), and rows, shape (rows,)."""
        ny, nx = self._shape
        h = self._resolution
        xs = self._bounds[0] + (np.arange(nx, dtype=np.float64) + 0.5) * h
        ys = self._bounds[1] + (np.arange(ny, dtype=np.float64) + 0.5) * h
        return xs, ys
