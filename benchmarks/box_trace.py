"""Which occupied cells keep the changing-scenes box "not gone" in the carved grid, and until when.

Run from the repository root::

    .venv/bin/python benchmarks/box_trace.py --resolution 0.05          # seeds 0-2
    .venv/bin/python benchmarks/box_trace.py --resolution 0.05 --cells  # every snapshot's cells

The box scene (``sim/scene.py``): a 0.5 m box against the corridor's left wall (x = -1.2 m) is
removed while the robot is in a side room and driven past again. ``benchmarks/changing_scenes.py``
reports how long after the robot passes it the map still holds an unexplained occupied cell
within 0.25 m of where the box stood (explained: within 1.5 cells of a present wall). This
replays the same snapshots (every 0.2 s, no-echo readings, specular physics unless
``--physics amplitude``) for the carved grid alone and prints, per seed, that latency counting
every such cell and counting only the cells on the corridor's side of the wall the box stood
against (x > -1.2 m): cells behind a wall are ones no beam can look at again.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

import numpy as np

from sonarcarve.grids.carved import CarvedGrid
from sonarcarve.lab.changing_scenes import (
    SNAPSHOT_PERIOD,
    grid_tolerance,
    scene_changes,
    simulate_changing_scene,
)
from sonarcarve.sim.sonar import SonarPhysics
from sonarcarve.sim.walls import World

#: The wall the box stands against (``_box_scene``), metres.
WALL_X = -1.2


def trace(seed: int, resolution: float, physics: SonarPhysics, show_cells: bool) -> None:
    """Print seed ``seed``'s latencies (and, with ``show_cells``, the cells at each snapshot)."""
    _, sim = simulate_changing_scene("box", seed, no_echo=True, physics=physics)
    change = next(c for c in scene_changes(sim) if c.label == "box gone")
    xmin, ymin, xmax, ymax = sim.world.bounds
    grid = CarvedGrid(resolution, (xmin - 0.5, ymin - 0.5, xmax + 0.5, ymax + 0.5))
    t0, t1 = float(sim.trajectory.t[0]), float(sim.trajectory.t[-1])
    times = t0 + SNAPSHOT_PERIOD * np.arange(1, math.floor((t1 - t0) / SNAPSHOT_PERIOD + 1e-9) + 1)
    cut = np.searchsorted(sim.readings.t, times, side="right")
    place, xs, ys = World(change.place), *grid.cell_centers()
    last_any = last_inside = math.nan
    lo = 0
    for t, hi in zip(times.tolist(), cut.tolist(), strict=True):
        if hi > lo:
            grid.add_many(sim.readings[lo:hi])
        lo = hi
        if t < change.t_ref:
            continue
        rows, cols = np.nonzero(grid.occupied_mask())
        cells = np.column_stack((xs[cols], ys[rows]))
        bad = ((place.distance_to_walls(cells) <= 0.25)
               & (sim.world.distance_to_walls(cells) > grid_tolerance(resolution)))
        if bad.any():
            last_any = t
            if show_cells:
                log_odds = grid.log_odds[rows[bad], cols[bad]]
                print(f"  t {t:.1f} s ({t - change.t_past:+.1f} after passing): "
                      + ", ".join(f"({x:.3f}, {y:.3f}) {v:.2f}"
                                  for (x, y), v in zip(cells[bad], log_odds, strict=True)))
        if (bad & (cells[:, 0] > WALL_X)).any():
            last_inside = t
    after = [last + SNAPSHOT_PERIOD - change.t_past for last in (last_any, last_inside)]
    print(f"seed {seed}: {after[0]:+.2f} s after passing, every cell; "
          f"{after[1]:+.2f} s on the corridor's side of the wall (nan: never marked)")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--resolution", type=float, default=0.05)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--physics", choices=("specular", "amplitude"), default="specular")
    parser.add_argument("--cells", action="store_true", help="print every snapshot's cells")
    args = parser.parse_args(argv)
    physics = SonarPhysics(echo_model=args.physics)
    for seed in range(args.seeds):
        trace(seed, args.resolution, physics, args.cells)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
