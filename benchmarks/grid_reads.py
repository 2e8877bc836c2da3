"""CPU per reading when the map is read often: the carved grid against ROS's range sensor layer.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/grid_reads.py             # reads every 1/5/25 readings, once
    nice .venv/bin/python benchmarks/grid_reads.py --trinary --every 5 25 0
    nice .venv/bin/python benchmarks/grid_reads.py --physics amplitude   # the second model

A robot reads its costmap at 5-10 Hz, not once per log (``benchmarks/grids.py`` measures the
latter). Here the office log (seed 0, echoes only unless ``--no-echo``) is fed to each grid a few
readings at a time, ``--every`` k readings per ``add_many`` (0: the whole log at once), and the
map is read after each batch. A read is, by default, what a costmap layer does when asked for its
update: :meth:`~sonarcarve.grids.CarvedGrid.refresh` brings the carved grid's live overlay up to
date with carving (the layer's cells are up to date after each reading: nothing to do); with
``--trinary`` every read also classifies every cell (:func:`~sonarcarve.grids.trinary`, both
grids), what a planner reading the whole map pays on top. Timed in CPU time of this process
(``time.process_time``: on a shared machine the time spent waiting for a core does not count;
wall-clock ratios of the once-per-log runs swung 0.7-1.9 at a load of 2), best of
``--repeats`` runs after a warm-up, the two grids taking turns, one process: the ratio is of
numbers measured side by side. The load average of the machine is printed before and after.

``--split`` then says where the carved grid's CPU goes at the first ``--every`` that is not 0:
the compiled kernels' share (their own time under ``cProfile``, which times a kernel call as one
call, against the CPU time of the same run unprofiled) and the rest, Python and numpy between
the kernels (a batch's arcs, intervals, estimates and bookkeeping).
"""

from __future__ import annotations

import argparse
import cProfile
import math
import os
import pstats
import sys
import time
from collections.abc import Callable, Sequence

from sonarcarve.grids import CarvedGrid, RangeSensorLayer, trinary
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.simulate import simulate
from sonarcarve.sim.sonar import DEFAULT_PHYSICS

MARGIN = 0.5
Bounds = tuple[float, float, float, float]
Grid = CarvedGrid | RangeSensorLayer
GRIDS: dict[str, Callable[[float, Bounds], Grid]] = {
    "carved grid": lambda h, b: CarvedGrid(h, b),
    "RangeSensorLayer, ROS defaults": lambda h, b: RangeSensorLayer(h, b),
}


def _readings(world: str, seed: int, no_echo: bool, limit: int | None,
              physics: str) -> tuple[ReadingBatch, Bounds]:
    """The scenario's log and the grids' bounds: the world's plus :data:`MARGIN` (as
    ``benchmarks/grids.py``, without its random shift). ``physics`` names the simulator's echo
    model (the default adds no override, so the log is that of the other benchmarks)."""
    override = () if physics == DEFAULT_PHYSICS.echo_model else (("echo_model", physics),)
    sim = run_simulation(Scenario(world, seed, physics=override))
    if no_echo:
        sim = simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics,
                       sim.odometry, no_echo=True)
    readings = sim.readings if limit is None else sim.readings[:limit]
    xmin, ymin, xmax, ymax = sim.world.bounds
    return readings, (xmin - MARGIN, ymin - MARGIN, xmax + MARGIN, ymax + MARGIN)


def _read(grid: Grid, classify: bool) -> None:
    if classify:
        trinary(grid)
    elif isinstance(grid, CarvedGrid):
        grid.refresh()


def _run(make: Callable[[], Grid], batch: ReadingBatch, every: int, classify: bool) -> float:
    """µs per reading of feeding ``batch`` ``every`` readings at a time (0: all at once),
    reading the map after each."""
    grid = make()
    n = len(batch)
    step = n if every == 0 else every
    tic = time.process_time()
    for start in range(0, n, step):
        grid.add_many(batch[start:start + step])
        _read(grid, classify)
    return (time.process_time() - tic) / n * 1e6


def _table(batch: ReadingBatch, bounds: Bounds, resolutions: Sequence[float],
           schedules: Sequence[int], repeats: int, classify: bool) -> None:
    seconds = (batch.t[-1] - batch.t[0]) / max(1, len(batch) - 1)
    print("| resolution (m) | read every (readings) | between reads (s) | carved grid (µs per "
          "reading) | layer (µs per reading) | ratio carved / layer |")
    print("|---:|---:|---:|---:|---:|---:|")
    for h in resolutions:
        makers = {label: (lambda f=f, h=h: f(h, bounds)) for label, f in GRIDS.items()}
        for make in makers.values():  # compile and warm up
            _run(make, batch[:300], 5, classify)
        for every in schedules:
            best = dict.fromkeys(makers, math.inf)
            # Turns rather than one grid's runs in a row: load from other processes on a shared
            # machine then falls on both grids alike, and the minimum drops the disturbed runs.
            for _ in range(repeats):
                for label, make in makers.items():
                    best[label] = min(best[label], _run(make, batch, every, classify))
            carved, layer = best["carved grid"], best["RangeSensorLayer, ROS defaults"]
            label = "once per log" if every == 0 else str(every)
            gap = "-" if every == 0 else f"{every * seconds:.2f}"
            print(f"| {h:.2f} | {label} | {gap} | {carved:.1f} | {layer:.1f} | "
                  f"{carved / layer:.2f} |", flush=True)


def _kernel_codes() -> set[tuple[str, int, str]]:
    """``(file, first line, name)`` of every numba kernel of the loaded ``sonarcarve`` modules,
    as :mod:`pstats` keys its entries."""
    from numba.core.registry import CPUDispatcher

    codes = set()
    for name, module in list(sys.modules.items()):
        if not name.startswith("sonarcarve"):
            continue
        for value in vars(module).values():
            if isinstance(value, CPUDispatcher):
                code = value.py_func.__code__
                codes.add((code.co_filename, code.co_firstlineno, code.co_name))
    return codes


def _split(batch: ReadingBatch, bounds: Bounds, resolutions: Sequence[float],
           schedules: Sequence[int]) -> None:
    every = next((k for k in schedules if k > 0), 5)
    print(f"\ncarved grid, read every {every} readings: where its CPU goes\n")
    print("| resolution (m) | CPU per reading (µs) | compiled kernels (%) | the rest (%) |")
    print("|---:|---:|---:|---:|")
    for h in resolutions:
        def make(h: float = h) -> Grid:
            return CarvedGrid(h, bounds)

        _run(make, batch[:300], every, False)  # compiled and warm
        plain = _run(make, batch, every, False) * len(batch) / 1e6
        # CPU time, as ``plain``: the profiler's default clock is wall time, which on a loaded
        # machine put the kernels above the whole run's CPU time (a share of 100 %).
        profiler = cProfile.Profile(time.process_time)
        profiler.runcall(_run, make, batch, every, False)
        entries = pstats.Stats(profiler).stats  # type: ignore[attr-defined]  # untyped
        kernels = _kernel_codes()
        inside = sum(entry[2] for key, entry in entries.items() if key in kernels)
        share = min(1.0, inside / plain)
        print(f"| {h:.2f} | {plain / len(batch) * 1e6:.1f} | {100 * share:.0f} | "
              f"{100 * (1 - share):.0f} |", flush=True)


def main(argv: list[str] | None = None) -> int:
    """Simulate the log, time both grids at every schedule and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--world", default="office")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.05, 0.1])
    parser.add_argument("--every", type=int, nargs="+", default=[1, 5, 25, 0],
                        help="readings per batch, the map read after each (0: once per log)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-echo", action="store_true",
                        help="every firing that heard nothing is a reading too")
    parser.add_argument("--trinary", action="store_true",
                        help="each read also classifies every cell (both grids)")
    parser.add_argument("--limit", type=int, default=None, help="only the first N readings")
    parser.add_argument("--physics", choices=("specular", "amplitude"), default="specular",
                        help="the simulator's echo model (specular: its default)")
    parser.add_argument("--split", action="store_true",
                        help="then the carved grid's CPU split: compiled kernels and the rest")
    args = parser.parse_args(argv)
    batch, bounds = _readings(args.world, args.seed, args.no_echo, args.limit, args.physics)
    read = ("refresh (carved grid) / nothing (layer), then trinary of every cell"
            if args.trinary else "refresh (carved grid) / nothing (layer)")
    print(f"CPU per reading, {args.world} seed {args.seed}, {args.physics} physics, "
          f"{len(batch):,} readings"
          f"{' with no-echo readings' if args.no_echo else ', echoes only'}; a read: {read}; "
          f"CPU time, best of {args.repeats}, the grids taking turns, one process; "
          f"load average {os.getloadavg()[0]:.1f} (2 cores)\n")
    _table(batch, bounds, args.resolutions, args.every, args.repeats, args.trinary)
    if args.split:
        _split(batch, bounds, args.resolutions, args.every)
    print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
