"""What no-echo readings (a firing that heard nothing: free space up to max range) add.

Run from the repository root::

    .venv/bin/python benchmarks/no_echo.py              # office, t-junction, doorway; seeds 0-1

Each world's built-in tour is simulated once with the Scout2 ring and default physics, with
``no_echo=True`` (:func:`~sonarcarve.sim.simulate.simulate`): the echoes are exactly those of the
default simulation, plus one reading with ``range`` = inf and ``max_range`` = 6.477 m (the
Scout2's) per firing that heard nothing. Every map is made twice, from the echoes only and from
every reading, and measured against the simulator's truth:

* methods (``carve``, ``combined``, ``evidence``, library defaults): *direct kept*, the share of
  direct echoes with a point in the global map; *spurious removed*, the share of spurious echoes
  (crosstalk, floor, multipath) without one; median and 90th percentile of the map points'
  distance to the nearest true wall, metres;
* grids at 0.10 m (:class:`~sonarcarve.grids.CarvedGrid`, :class:`~sonarcarve.grids.OccupancyGrid`,
  :class:`~sonarcarve.grids.RangeSensorLayer` with ROS's defaults, which drop +Inf, and with
  ``inf_is_max_reading`` and ``clear_on_max_reading``, which clear the cone to max range):
  occupied precision, recall and phantoms (:mod:`sonarcarve.lab.grid_measures`), in %.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence

import numpy as np

from sonarcarve.grids import (
    CarvedGrid,
    OccupancyGrid,
    OccupancyMap,
    RangeSensorLayer,
    RangeSensorLayerParams,
)
from sonarcarve.lab.grid_measures import grid_measures
from sonarcarve.lab.metrics import segment_distance
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import make_method
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import NO_ECHO, EchoKind

WORLDS = ("office", "t-junction", "doorway")
METHODS = ("carve", "combined", "evidence")
RESOLUTION = 0.1
MARGIN = 0.5
Bounds = tuple[float, float, float, float]


def _simulations(world: str, seed: int) -> tuple[Simulation, Simulation]:
    """The default simulation and the same one with no-echo readings."""
    sim = run_simulation(Scenario(world, seed))
    every = simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics, sim.odometry,
                     scene=sim.scene, no_echo=True)
    return sim, every


def _method_row(name: str, readings: ReadingBatch, kind: np.ndarray,
                sim: Simulation) -> tuple[float, float, float, float]:
    method = make_method(name)
    method.add_many(readings)
    gmap = method.finish()
    in_map = np.zeros(len(readings), dtype=bool)
    in_map[gmap.reading_id] = True
    direct = kind == EchoKind.DIRECT
    spurious = (kind != EchoKind.DIRECT) & (kind != NO_ECHO)
    err = segment_distance(gmap.xy, sim.world.segments)[0]
    return (float(in_map[direct].mean()), float((~in_map[spurious]).mean()),
            float(np.median(err)), float(np.percentile(err, 90)))


def _grids(max_range: float) -> dict[str, Callable[[float, Bounds], OccupancyMap]]:
    clearing = RangeSensorLayerParams(max_range=max_range, inf_is_max_reading=True,
                                      clear_on_max_reading=True)
    return {
        "carved grid": lambda h, b: CarvedGrid(h, b),
        "elfes grid": lambda h, b: OccupancyGrid(h, b),
        "range sensor layer (ROS defaults)": lambda h, b: RangeSensorLayer(h, b),
        "range sensor layer, +Inf clears": lambda h, b: RangeSensorLayer(h, b, clearing),
    }


def _grid_row(make: Callable[[float, Bounds], OccupancyMap], readings: ReadingBatch,
              sim: Simulation) -> tuple[float, float, float]:
    xmin, ymin, xmax, ymax = sim.world.bounds
    grid = make(RESOLUTION, (xmin - MARGIN, ymin - MARGIN, xmax + MARGIN, ymax + MARGIN))
    assert isinstance(grid, CarvedGrid | OccupancyGrid | RangeSensorLayer)
    grid.add_many(readings)
    direct = sim.truth.kind == EchoKind.DIRECT
    m = grid_measures(grid, sim.world.segments, sim.truth.reflection[direct], sim.world.bounds)
    return m.precision, m.recall, m.phantoms


def _pct(a: float, b: float) -> str:
    return f"{100 * a:.1f} → {100 * b:.1f}"


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS))
    args = parser.parse_args(argv)
    seeds = range(args.seeds)
    sims = {w: [_simulations(w, s) for s in seeds] for w in args.worlds}

    print(f"\n### No-echo readings: how many (seeds 0-{args.seeds - 1})\n")
    print("| world | echoes | no-echo readings | share of firings |")
    print("|---|---:|---:|---:|")
    for w, pairs in sims.items():
        echoes = np.mean([len(a.readings) for a, _ in pairs])
        silent = np.mean([int(b.readings.no_echo.sum()) for _, b in pairs])
        print(f"| {w} | {echoes:.0f} | {silent:.0f} | {100 * silent / (echoes + silent):.1f} % |")

    print(f"\n### Methods: echoes only → with no-echo readings (means over seeds "
          f"0-{args.seeds - 1})\n")
    print("| world | method | direct kept % | spurious removed % | median error m | p90 m |")
    print("|---|---|---:|---:|---:|---:|")
    for w, pairs in sims.items():
        for name in METHODS:
            before = np.mean([_method_row(name, a.readings, a.truth.kind, a)
                              for a, _ in pairs], axis=0)
            after = np.mean([_method_row(name, b.readings, b.truth.kind, b)
                             for _, b in pairs], axis=0)
            print(f"| {w} | {name} | {_pct(before[0], after[0])} | "
                  f"{_pct(before[1], after[1])} | {before[2]:.3f} → {after[2]:.3f} | "
                  f"{before[3]:.3f} → {after[3]:.3f} |")

    max_range = next(iter(sims.values()))[0][0].robot.max_range
    print(f"\n### Grids at {RESOLUTION:.2f} m: echoes only → with no-echo readings (means over "
          f"seeds 0-{args.seeds - 1}), %\n")
    print("| world | grid | precision | recall | phantoms |")
    print("|---|---|---:|---:|---:|")
    for w, pairs in sims.items():
        for label, make in _grids(max_range).items():
            before = np.mean([_grid_row(make, a.readings, a) for a, _ in pairs], axis=0)
            after = np.mean([_grid_row(make, b.readings, b) for _, b in pairs], axis=0)
            print(f"| {w} | {label} | {_pct(before[0], after[0])} | "
                  f"{_pct(before[1], after[1])} | "
                  f"{100 * before[2]:.2f} → {100 * after[2]:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
