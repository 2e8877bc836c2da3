"""The carved grid against ROS's range sensor layer (and the Elfes/octomap grid), on the simulator.

Run from the repository root::

    .venv/bin/python benchmarks/grids.py            # tables, and docs/figures/grids-office.png
    .venv/bin/python benchmarks/grids.py --no-echo --figure ""     # with the silent firings
    .venv/bin/python benchmarks/grids.py --physics amplitude --figure ""  # the second model

For the ``office``, ``t-junction`` and ``doorway`` tours (Scout2 ring, seeds 0-2), at 0.05 and
0.10 m cells, each grid maps the whole log and its trinary map (:func:`~sonarcarve.grids.trinary`)
is measured against the true walls (:mod:`sonarcarve.lab.grid_measures`): occupied precision and
recall (within one cell of a wall), phantoms (truly free cells marked occupied), seen wall length
covered. Grids: :class:`~sonarcarve.grids.CarvedGrid` (defaults), the faithful
:class:`~sonarcarve.grids.RangeSensorLayer` with ROS's defaults, the same with the ``phi`` and
``clear_on_max_reading`` that maximise F1 (harmonic mean of precision and recall) on the office
at that resolution (the sweep is printed), and :class:`~sonarcarve.grids.OccupancyGrid` (Elfes /
octomap). Each grid's origin is shifted by a seeded random fraction of a cell.

Then Fig. 2's door: a 0.85 m door approached at 0°, 20°, -35° and 45° from the wall normal,
aiming 0 and ±0.15 m off its centre, seeds 0-2 (36 approaches, as the openings experiment;
``--door-seeds 9`` draws the same 12 approaches on seeds 0-8, 108 in all);
when the robot is first 1 m short of the door, is it passable in the grid, i.e. a stretch of at
least 0.46 m (Scout2 + 5 cm) of the door line with no occupied cell square within 0.25 m (and,
strictly, with only free cells)? And CPU per reading of each grid on the office log at both
resolutions, best of three runs after a warm-up with the grids taking turns, all in one
process (ratios in one run).

``--physics amplitude`` simulates every run (tours, door approaches, CPU log) with the second
sonar model (:mod:`sonarcarve.sim.amplitude`) instead of the default specular one, as
``benchmarks/changing_scenes.py --physics amplitude`` does.
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sonarcarve.grids import (
    CarvedGrid,
    CarvedGridParams,
    OccupancyGrid,
    OccupancyMap,
    RangeSensorLayer,
    RangeSensorLayerParams,
    trinary,
)
from sonarcarve.lab.analyses import GAP_DEPTH, first_reading_within, passage_clearance
from sonarcarve.lab.grid_measures import GridMeasures, grid_free_width, grid_measures
from sonarcarve.lab.metrics import gap_region
from sonarcarve.lab.scenarios import Scenario, build_world, run_simulation
from sonarcarve.plotting import plot_trinary
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import DEFAULT_PHYSICS, EchoKind

Bounds = tuple[float, float, float, float]
Factory = Callable[[float, Bounds], OccupancyMap]

MARGIN = 0.5
PHIS = (0.6, 1.2, 2.0, 3.0, 5.0)
DOOR_WIDTH = 0.85
HEADINGS_DEG = (0.0, 20.0, -35.0, 45.0)
OFFSETS = (0.0, 0.15, -0.15)
FIGURE = Path("docs/figures/grids-office.png")
CPU_REPEATS = 3


@dataclass(frozen=True)
class GridKind:
    label: str
    make: Factory


def _carved(h: float, b: Bounds) -> OccupancyMap:
    return CarvedGrid(h, b)


def _layer(params: RangeSensorLayerParams) -> Factory:
    def make(h: float, b: Bounds) -> OccupancyMap:
        return RangeSensorLayer(h, b, params)
    return make


def _elfes(h: float, b: Bounds) -> OccupancyMap:
    return OccupancyGrid(h, b)


def _scenario(world: str, seed: int, physics: str,
              path: tuple[tuple[float, float], ...] | None = None) -> Scenario:
    """The scenario of ``world`` and ``seed`` under the echo model ``physics`` (the default
    physics adds no override, so its simulations are those of the other benchmarks)."""
    override = () if physics == DEFAULT_PHYSICS.echo_model else (("echo_model", physics),)
    return Scenario(world, seed, path=path, physics=override)


def _simulate(scenario: Scenario, no_echo: bool) -> Simulation:
    """The scenario's simulation; with ``no_echo`` every firing that heard nothing is a reading
    too (range inf up to the robot's max range: the echoes are the same)."""
    sim = run_simulation(scenario)
    if not no_echo:
        return sim
    return simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics, sim.odometry,
                    no_echo=True)


def _bounds(world_bounds: Bounds, h: float, seed: int) -> Bounds:
    shift = np.random.default_rng(seed).uniform(0.0, h, 2)
    xmin, ymin, xmax, ymax = world_bounds
    return (xmin - MARGIN - shift[0], ymin - MARGIN - shift[1], xmax + MARGIN, ymax + MARGIN)


def _fill(make: Factory, h: float, sim: Simulation, seed: int,
          batch: ReadingBatch | None = None) -> OccupancyMap:
    grid = make(h, _bounds(sim.world.bounds, h, seed))
    assert isinstance(grid, CarvedGrid | RangeSensorLayer | OccupancyGrid)
    grid.add_many(sim.readings if batch is None else batch)
    return grid


def _measure(grid: OccupancyMap, sim: Simulation) -> GridMeasures:
    direct = sim.truth.kind == EchoKind.DIRECT
    return grid_measures(grid, sim.world.segments, sim.truth.reflection[direct],
                         sim.world.bounds, path=np.column_stack((sim.readings.x, sim.readings.y)))


def _mean(rows: Sequence[GridMeasures]) -> GridMeasures:
    mean = GridMeasures(*(float(np.nanmean(column)) for column in zip(*rows, strict=True)))
    return mean._replace(occupied_cells=round(mean.occupied_cells))


def _f1(m: GridMeasures) -> float:
    return 2 * m.precision * m.recall / (m.precision + m.recall)


def _sweep(office: Sequence[Simulation], h: float) -> RangeSensorLayerParams:
    print(f"\nrange sensor layer sweep: office, seeds 0-{len(office) - 1}, {h:.2f} m; mean "
          "over seeds\n")
    print("| phi (m) | clear_on_max_reading | precision | recall | F1 | phantoms (%) |")
    print("|---:|---|---:|---:|---:|---:|")
    best, best_f1 = RangeSensorLayerParams(), -1.0
    for phi in PHIS:
        for clear in (False, True):
            params = RangeSensorLayerParams(phi=phi, clear_on_max_reading=clear)
            m = _mean([_measure(_fill(_layer(params), h, sim, s), sim)
                       for s, sim in enumerate(office)])
            f1 = _f1(m)
            print(f"| {phi:g} | {clear} | {m.precision:.3f} | {m.recall:.3f} | {f1:.3f} | "
                  f"{100 * m.phantoms:.3f} |")
            if f1 > best_f1:
                best, best_f1 = params, f1
    print(f"\nbest at {h:.2f} m: phi {best.phi:g}, clear_on_max_reading "
          f"{best.clear_on_max_reading}")
    return best


def _carved_with_side_lobes(lobes: float) -> Factory:
    def make(h: float, b: Bounds) -> OccupancyMap:
        return CarvedGrid(h, b, params=CarvedGridParams(side_lobes=lobes))
    return make


def _carved_with_free_threshold(threshold: float) -> Factory:
    def make(h: float, b: Bounds) -> OccupancyMap:
        return CarvedGrid(h, b, params=CarvedGridParams(free_threshold=threshold))
    return make


def _carved_with_mark_length(length: float) -> Factory:
    def make(h: float, b: Bounds) -> OccupancyMap:
        return CarvedGrid(h, b, params=CarvedGridParams(mark_length=length))
    return make


def _kinds(best: RangeSensorLayerParams, side_lobes: float | None = None,
           free_threshold: float | None = None,
           mark_length: float | None = None) -> list[GridKind]:
    kinds = [GridKind("carved grid", _carved)]
    if side_lobes is not None:  # the opt-in rule as a row of its own
        kinds.append(GridKind(f"carved grid, side_lobes {side_lobes:g}",
                              _carved_with_side_lobes(side_lobes)))
    if free_threshold is not None:  # another free threshold as a row of its own
        kinds.append(GridKind(f"carved grid, free below {free_threshold:g}",
                              _carved_with_free_threshold(free_threshold)))
    if mark_length is not None:  # another length of the newest echo's mark
        kinds.append(GridKind(f"carved grid, mark_length {mark_length:g}",
                              _carved_with_mark_length(mark_length)))
    return [
        *kinds,
        GridKind("RangeSensorLayer, ROS defaults", _layer(RangeSensorLayerParams())),
        GridKind(f"RangeSensorLayer, phi {best.phi:g}, clear_on_max_reading "
                 f"{str(best.clear_on_max_reading).lower()}", _layer(best)),
        GridKind("Elfes/octomap grid", _elfes)]


def _measures_table(sims: dict[str, list[Simulation]], h: float,
                    kinds: Sequence[GridKind]) -> dict[tuple[str, str], GridMeasures]:
    out = {}
    print(f"\ngrid measures at {h:.2f} m, seeds 0-{len(next(iter(sims.values()))) - 1}, "
          "mean over seeds\n")
    print("| world | grid | precision | recall | phantoms (%) | wall covered (%) | "
          "occupied cells | free near the path (%) | seen walls freed (%) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for world, runs in sims.items():
        for kind in kinds:
            m = _mean([_measure(_fill(kind.make, h, sim, s), sim) for s, sim in enumerate(runs)])
            out[(world, kind.label)] = m
            print(f"| {world} | {kind.label} | {m.precision:.3f} | {m.recall:.3f} | "
                  f"{100 * m.phantoms:.3f} | {100 * m.wall_covered:.1f} | "
                  f"{m.occupied_cells:,.0f} | {100 * m.free_near_path:.1f} | "
                  f"{100 * m.walls_freed:.2f} |")
    return out


def _door_runs(seeds: int, width: float, physics: str, no_echo: bool
               ) -> list[tuple[int, float, float, Simulation, int]]:
    """Fig. 2's approaches: every heading and offset on each of ``seeds`` seeds, each as
    (seed, heading in degrees, offset in metres, simulation, readings until 1 m short)."""
    gap = build_world(f"doorway:{width:g}").openings[0]
    runs = []
    for seed in range(seeds):
        for heading in HEADINGS_DEG:
            for offset in OFFSETS:
                aim = 0.5 * (gap[0] + gap[1]) + np.array([offset, 0.0])
                hd = math.radians(heading)
                direction = np.array([math.sin(hd), math.cos(hd)])
                path = tuple((float(p[0]), float(p[1]))
                             for p in (aim - 4.3 * direction, aim - 0.8 * direction))
                sim = _simulate(_scenario(f"doorway:{width:g}", seed, physics, path),
                                no_echo)
                runs.append((seed, heading, offset, sim, first_reading_within(sim, gap, 1.0)))
    return runs


def _door_table(seeds: int, resolutions: Sequence[float],
                kinds_by_h: dict[float, list[GridKind]],
                no_echo: bool = False, physics: str = "specular", width: float = DOOR_WIDTH
                ) -> dict[tuple[float, str], float]:
    gap = build_world(f"doorway:{width:g}").openings[0]
    region = gap_region(gap[0], gap[1], GAP_DEPTH)
    runs = _door_runs(seeds, width, physics, no_echo)
    clearance = passage_clearance(runs[0][3].robot.robot_radius)
    print(f"\nFig. 2 door: {width:g} m, {len(runs)} approaches (headings "
          f"{', '.join(f'{h:g}' for h in HEADINGS_DEG)}°, offsets "
          f"{', '.join(f'{o:g}' for o in OFFSETS)} m, seeds 0-{seeds - 1}); grid when the robot "
          f"is first 1 m short; passable: a stretch >= {clearance:.2f} m with no occupied cell "
          f"within {GAP_DEPTH:g} m of the door line (strict: only free cells)\n")
    print("| resolution (m) | grid | passable | passable (%) | passable, strict (%) | "
          "free width (m), mean | closed approaches (seed/heading°/offset m) |")
    print("|---:|---|---:|---:|---:|---:|---|")
    out = {}
    for h in resolutions:
        for kind in kinds_by_h[h]:
            widths, strict, closed = [], [], []
            for seed, heading, offset, sim, stop in runs:
                grid = _fill(kind.make, h, sim, seed, sim.readings[:stop])
                cells = trinary(grid)
                widths.append(grid_free_width(grid, region, cells=cells))
                strict.append(grid_free_width(grid, region, strict=True, cells=cells))
                if widths[-1] < clearance:
                    closed.append(f"{seed}/{heading:g}/{offset:+g}")
            passable = sum(w >= clearance for w in widths)
            share = 100.0 * passable / len(runs)
            out[(h, kind.label)] = share
            listed = ", ".join(closed) if len(closed) <= 12 else f"{len(closed)} approaches"
            print(f"| {h:.2f} | {kind.label} | {passable} of {len(runs)} | {share:.0f} | "
                  f"{100.0 * float(np.mean([w >= clearance for w in strict])):.0f} | "
                  f"{np.mean(widths):.2f} | {listed} |")
    return out


def _cpu_table(sim: Simulation, resolutions: Sequence[float],
               kinds_by_h: dict[float, list[GridKind]]) -> None:
    batch = sim.readings
    print(f"\nCPU per reading: office seed 0, {len(batch):,} readings, whole log in one "
          f"add_many then the trinary map read once; CPU time, best of {CPU_REPEATS} runs "
          "after a warm-up, the grids taking turns, one process\n")
    print("| resolution (m) | grid | µs per reading | ratio to the layer (defaults) |")
    print("|---:|---|---:|---:|")
    for h in resolutions:
        times = {kind.label: math.inf for kind in kinds_by_h[h]}
        for kind in kinds_by_h[h]:
            trinary(_fill(kind.make, h, sim, 0, batch[:300]))  # compile
        # Turns rather than one grid's runs in a row: load from other processes on a shared
        # machine then falls on every grid alike, and the minimum drops the disturbed runs.
        # CPU time, not wall clock: time spent waiting for a core does not count (wall-clock
        # ratios of identical code swung 0.7-1.3 between runs under a load of 3-6).
        for _ in range(CPU_REPEATS):
            for kind in kinds_by_h[h]:
                tic = time.process_time()
                trinary(_fill(kind.make, h, sim, 0))
                us = (time.process_time() - tic) / len(batch) * 1e6
                times[kind.label] = min(times[kind.label], us)
        ref = times["RangeSensorLayer, ROS defaults"]
        for label, us in times.items():
            print(f"| {h:.2f} | {label} | {us:.1f} | {us / ref:.2f} |")


def _figure(sim: Simulation, h: float, path: Path) -> None:
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    grids = [("carved grid", _fill(_carved, h, sim, 0)),
             ("RangeSensorLayer (ROS defaults)",
              _fill(_layer(RangeSensorLayerParams()), h, sim, 0))]
    fig, axes = plt.subplots(1, 2, figsize=(16, 6.2), constrained_layout=True)
    for ax, (title, grid) in zip(axes, grids, strict=True):
        plot_trinary(trinary(grid), grid.extent, ax)
        for seg in sim.world.segments:
            ax.plot(seg[[0, 2]], seg[[1, 3]], color="#d62728", lw=0.7)
        m = _measure(grid, sim)
        ax.set_title(f"{title}: precision {m.precision:.2f}, recall {m.recall:.2f}")
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
    fig.suptitle(f"office, Scout2 tour seed 0, {len(sim.readings):,} readings, {h:.2f} m cells; "
                 "black occupied, white free, grey unknown, red the true walls")
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"\nfigure written to {path}")


def main(argv: list[str] | None = None) -> int:
    """Simulate, measure, print the tables and write the figure."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=["office", "t-junction", "doorway"])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--door-seeds", type=int, default=None, metavar="N",
                        help="seeds of the door approaches (default: --seeds); each seed adds "
                             "the same 12 headings and offsets, 9 seeds make 108 approaches")
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.05, 0.10])
    parser.add_argument("--figure", type=Path, default=FIGURE)
    parser.add_argument("--no-echo", action="store_true",
                        help="also feed the firings that heard nothing (range inf: free space "
                             "up to the robot's max range); the layer drops them (ROS default)")
    parser.add_argument("--physics", choices=("specular", "amplitude"), default="specular",
                        help="echo model of the simulated sonar (default specular, the "
                             "simulator's default physics)")
    parser.add_argument("--door-width", type=float, default=DOOR_WIDTH,
                        help="width of the Fig. 2 experiment's door, metres (default 0.85, the "
                             "width the grids were developed on; 0.75 and 1.0 are held out)")
    parser.add_argument("--side-lobes", type=float, default=None, metavar="HALF_WIDTHS",
                        help="add a row for the carved grid with the opt-in side-lobe rule "
                             "(CarvedGridParams.side_lobes, e.g. 1)")
    parser.add_argument("--free-threshold", type=float, default=None, metavar="P",
                        help="add a row for the carved grid calling a cell free below P "
                             "(CarvedGridParams.free_threshold; 0.196, map_saver's, was the "
                             "default before 0.35)")
    parser.add_argument("--mark-length", type=float, default=None, metavar="M",
                        help="add a row for the carved grid whose newest echo's mark is M "
                             "metres long (CarvedGridParams.mark_length; default: "
                             "spread_length, 0.2; 0: the point's cell)")
    parser.add_argument("--doors-only", action="store_true",
                        help="only the door table (the layer's phi sweep on the office still "
                             "runs: it picks the layer's best settings)")
    args = parser.parse_args(argv)
    if args.door_seeds is not None and args.door_seeds < 1:
        parser.error(f"--door-seeds must be at least 1, got {args.door_seeds}")
    if not 0.3 <= args.door_width <= 3.0:
        parser.error(f"--door-width must lie in [0.3, 3] metres, got {args.door_width:g}")
    tic = time.perf_counter()
    if args.physics != DEFAULT_PHYSICS.echo_model:
        print(f"\nPhysics: {args.physics}.")
    if args.no_echo:
        print("\nWith no-echo readings (every firing that heard nothing: free space up to the "
              "robot's max range; ROS's layer drops +Inf unless inf_is_max_reading).")
    worlds = [] if args.doors_only else args.worlds
    sims = {w: [_simulate(_scenario(w, s, args.physics), args.no_echo)
                for s in range(args.seeds)] for w in worlds}
    office = sims.get("office") or [_simulate(_scenario("office", s, args.physics), args.no_echo)
                                    for s in range(args.seeds)]
    kinds_by_h = {h: _kinds(_sweep(office, h), args.side_lobes, args.free_threshold,
                            args.mark_length)
                  for h in args.resolutions}
    if not args.doors_only:
        for h in args.resolutions:
            _measures_table(sims, h, kinds_by_h[h])
    _door_table(args.door_seeds or args.seeds, args.resolutions, kinds_by_h, args.no_echo,
                args.physics, args.door_width)
    if not args.doors_only:
        _cpu_table(office[0], args.resolutions, kinds_by_h)
    if args.figure.name and not args.doors_only:  # --figure "" skips it
        _figure(office[0], args.resolutions[0], args.figure)
    print(f"\nruntime: {time.perf_counter() - tic:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
