"""What every grid checks of its cells: a resolution and bounds, and how many cells they make.

One check for :class:`~sonarcarve.grids.OccupancyGrid`,
:class:`~sonarcarve.grids.RangeSensorLayer` and :class:`~sonarcarve.grids.CarvedGrid`, so their
errors read alike and a limit cannot be forgotten by one of them.
"""

from __future__ import annotations

import math

from sonarcarve.errors import SonarcarveError

__all__ = ["GridError", "grid_cells"]

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
        msg = (f"{label}: {nx} x {ny} cells of {h:g} m exceed the limit of {max_cells:,} "
               f"({limit_name}); use a coarser resolution or smaller bounds")
        raise GridError(msg)
    return float(h), (xmin, ymin, xmax, ymax), nx, ny
