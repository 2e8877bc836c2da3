"""The three grids on the real roboND-sonar-8 log: what a costmap of real sonar looks like.

Run from the repository root::

    .venv/bin/python benchmarks/real_log_grids.py     # table, and docs/figures/grids-real-log.png

The bundled log (8 sensors, 1,043 echoes after dropping no-echo values and stale repeats; see
``sonarcarve/data/roboND-sonar-8/README.md``) has no ground truth, and the occupancy picture that
ships with it is another sonar grid made from the same readings, not a floor plan (its walls are
bands 0.3-1 m thick, and it marks a 5 m disc round the turn that no grid here hears), so nothing
here is scored against it. What is measured needs no truth:

- occupied and free area: how much of the floor each grid lets a planner use, and how much wall
  it shows;
- wall sharpness: the line spread of the occupied cells' centres (the RMS distance of the cells
  within 0.25 m from their best-fit line, :func:`~sonarcarve.lab.experiments.real_log.line_spread`,
  the measure of the point maps in RESULTS' real-log section) and the share of isolated cells
  (fewer than 5 others within 0.25 m: specks a planner must route round);
- CPU per reading: the whole log in one ``add_many``, then the trinary map read once; CPU time,
  best of 3 after a warm-up, the grids taking turns in one process (ratios in one run).

Grids: :class:`~sonarcarve.grids.CarvedGrid` and :class:`~sonarcarve.grids.RangeSensorLayer`
with their defaults, :class:`~sonarcarve.grids.OccupancyGrid` (Elfes / octomap), each on
``readings_extent(batch, 0.5)`` (``sonarcarve grid``'s extent) at 0.05 and 0.10 m.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sonarcarve import make_grid, readings_extent
from sonarcarve.grids import FREE, OCCUPIED, Grid, trinary
from sonarcarve.io import read_robond
from sonarcarve.lab.experiments.real_log import line_spread
from sonarcarve.plotting import plot_trinary
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import FloatArray

GRIDS = {"carved grid": "carved", "RangeSensorLayer, ROS defaults": "range-sensor-layer",
         "Elfes/octomap grid": "elfes"}
MARGIN = 0.5  # metres round the readings, as `sonarcarve grid`
SPREAD_RADIUS = 0.25  # metres, the real-log experiment's neighbourhood
SPREAD_MIN_POINTS = 5
ROUNDS = 3


class GridRow(NamedTuple):
    """One grid's measures on the log."""

    label: str
    occupied_cells: int
    occupied_m2: float
    free_m2: float
    spread_median: float
    spread_p90: float
    isolated_percent: float
    us_per_reading: float


def occupied_centres(grid: Grid) -> FloatArray:
    """Centres of the cells the trinary map calls occupied, shape (n, 2), metres."""
    cells = trinary(grid)
    cx, cy = grid.cell_centers()
    rows, cols = np.nonzero(cells == OCCUPIED)
    return np.column_stack((cx[cols], cy[rows]))


def _fill(name: str, h: float, batch: ReadingBatch) -> tuple[Grid, float]:
    """A grid of the whole log and the CPU seconds its filling and one read took."""
    grid = make_grid(name, h, readings_extent(batch, MARGIN))
    start = time.process_time()
    grid.add_many(batch)
    trinary(grid)
    return grid, time.process_time() - start


def measure(label: str, grid: Grid, seconds: float, readings: int) -> GridRow:
    """The table row of one filled grid."""
    cells = trinary(grid)
    area = grid.resolution ** 2
    spread = line_spread(occupied_centres(grid), SPREAD_RADIUS, SPREAD_MIN_POINTS).summary()
    occupied = int((cells == OCCUPIED).sum())
    return GridRow(label, occupied, occupied * area, float((cells == FREE).sum()) * area,
                   spread["median"], spread["p90"], spread["isolated_percent"],
                   1e6 * seconds / readings)


def run(batch: ReadingBatch, h: float) -> list[GridRow]:
    """Every grid at cell side ``h``: warm-up, then ``ROUNDS`` rounds taking turns."""
    best = dict.fromkeys(GRIDS, np.inf)
    grids: dict[str, Grid] = {}
    for name in GRIDS.values():
        _fill(name, h, batch)  # compile and warm caches outside the timing
    for _ in range(ROUNDS):
        for label, name in GRIDS.items():
            grids[label], seconds = _fill(name, h, batch)
            best[label] = min(best[label], seconds)
    return [measure(label, grids[label], best[label], len(batch)) for label in GRIDS]


def table(rows: Sequence[GridRow], h: float) -> str:
    """Markdown table of one resolution, with the CPU ratio to the layer."""
    layer = next(r.us_per_reading for r in rows if r.label.startswith("RangeSensorLayer"))
    lines = [f"roboND-sonar-8, {h:.2f} m cells",
             "",
             "| grid | occupied cells | occupied (m²) | free (m²) | wall spread median / p90 "
             "(cm) | isolated cells (%) | µs per reading | ratio to the layer |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r.label} | {r.occupied_cells:,} | {r.occupied_m2:.1f} | {r.free_m2:.1f} "
                     f"| {100 * r.spread_median:.1f} / {100 * r.spread_p90:.1f} "
                     f"| {r.isolated_percent:.0f} | {r.us_per_reading:.1f} "
                     f"| {r.us_per_reading / layer:.2f} |")
    return "\n".join(lines)


def figure(batch: ReadingBatch, h: float, path: Path) -> None:
    """The three grids side by side with the robot's path."""
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(GRIDS), figsize=(18, 6.5), constrained_layout=True)
    for ax, (label, name) in zip(axes, GRIDS.items(), strict=True):
        grid, _ = _fill(name, h, batch)
        plot_trinary(trinary(grid), grid.extent, ax)
        ax.plot(batch.x, batch.y, color="#1f77b4", lw=0.8)
        ax.set_title(label)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    fig.suptitle(f"the real roboND-sonar-8 log, {len(batch):,} echoes, {h:.2f} m cells; black "
                 "occupied, white free, grey unknown, blue the robot's path (no ground truth)")
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"\nfigure written to {path}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.05, 0.10])
    parser.add_argument("--figure", default="docs/figures/grids-real-log.png",
                        help="figure path ('' for none), drawn at the first resolution")
    args = parser.parse_args(argv)
    batch = read_robond().batch
    for h in args.resolutions:
        print(table(run(batch, h), h), end="\n\n")
    if args.figure:
        figure(batch, args.resolutions[0], Path(args.figure))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
