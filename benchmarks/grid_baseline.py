"""An occupancy grid (the baseline sonar users know) against arc carving, on the simulator.

Run from the repository root::

    .venv/bin/python benchmarks/grid_baseline.py

Beyond the paper, which argues (section 2-B) that grids trade resolution for memory and compute.
For each world (``office``, ``t-junction`` and ``doorway`` tours, Scout2 ring, seeds 0-2) the
script simulates the tour once per seed, then maps the whole log with

* the methods ``centerline``, ``carve`` and ``combined`` (library defaults; their global map);
* ``carve`` and ``combined`` fed only readings of at most 3.81 m (the paper's maximum-range
  filter, Appendix B, :data:`~sonarcarve.filters.PAPER_MAX_RANGE`);
* :class:`~sonarcarve.grids.elfes.OccupancyGrid` at 0.05, 0.10 and 0.20 m, with the cone model of
  Elfes (no distance fade) and with ROS ``range_sensor_layer``'s 1.2 m fade (the library's
  default); the map is the centres of the cells above the default threshold (0.65). Each grid's
  origin is shifted by a seeded random fraction of a cell, so that walls do not sit on cell
  centres or edges by construction of the worlds' round coordinates;

and prints markdown tables, means over seeds, of:

* points in the map; median and 90th percentile of their distance to the nearest true wall
  (:func:`~sonarcarve.lab.metrics.segment_distance`), and the share farther than
  0.25 m (phantom obstacles: 0.25 m is the depth at which a point blocks an opening, Fig. 2);
* covered: the share of *seen* wall patches that hold a map point. Walls are cut into 0.5 m
  patches (:func:`~sonarcarve.lab.metrics.patch_index`); a patch is seen if the true
  reflection point of at least one direct echo lies on it, and covered if at least one map
  point lies within 0.10 m of its nearest wall and projects onto that patch;
* memory: the grid's float32 array, and the peak traced memory (tracemalloc) of one untimed run
  building the map (method: ``add_many`` + ``finish``; grid: construction, ``add_many`` and
  ``occupied_points``), which sees every numpy array allocated from Python;
* throughput: readings fed per second, median of ``--repeats`` timed runs of the same calls,
  one core, after a warm-up run that compiles the numba kernels.

Further tables: the occupancy threshold (office), the grid's update engines (numba loop against
the numpy version, office seed 0), and the doorway of Fig. 2: on the ``doorway`` world (a
0.85 m door, the tour stops 1 m short of it) is the door passable in the final map, i.e. is
there a stretch of at least 0.46 m (Scout2 diameter + 5 cm) of the door line with no map point
within 0.25 m of it (:func:`~sonarcarve.lab.metrics.free_width`)? For grids this is
measured on the occupied cells' centres and, more strictly, on their whole squares.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import dataclass, fields

import numpy as np
import numpy.typing as npt

from sonarcarve import ReadingBatch, make_method
from sonarcarve.filters import PAPER_MAX_RANGE
from sonarcarve.grids.elfes import (
    DEFAULT_OCCUPIED_THRESHOLD,
    ROS_FADE_RANGE,
    OccupancyGrid,
    SonarConeModel,
    _update_kernel,
    _update_numpy,
)
from sonarcarve.lab.analyses import GAP_DEPTH, passage_clearance
from sonarcarve.lab.metrics import (
    GapRegion,
    PatchIndex,
    free_width,
    gap_region,
    patch_index,
    patch_of_points,
    segment_distance,
)
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.sim.world import World, load_world

FloatArray = npt.NDArray[np.float64]

#: Wall patch length and the distance within which a map point covers a patch, metres.
PATCH_LENGTH = 0.5
COVER_DISTANCE = 0.10
#: Map points farther than this from every wall count as phantoms, metres (GAP_DEPTH).
PHANTOM_DISTANCE = GAP_DEPTH
#: Margin of the grid around the world's walls, metres.
MARGIN = 0.5
#: ROS range_sensor_layer's clear_threshold: below it a cell counts as known free.
CLEAR_THRESHOLD = 0.2
ELFES = SonarConeModel(fade_range=math.inf)
ROS = SonarConeModel(fade_range=ROS_FADE_RANGE)


@dataclass(frozen=True)
class Variant:
    """One way of making a map: a method (``resolution`` None) or a grid."""

    label: str
    method: str = ""
    max_range: float = math.inf
    resolution: float | None = None
    model: SonarConeModel = ROS


@dataclass(frozen=True)
class Row:
    """Measures of one variant on one simulation (shares in percent, distances in m)."""

    points: float
    median: float
    p90: float
    phantom: float
    covered: float
    grid_mib: float
    peak_mib: float
    readings_per_s: float


def _variants(resolutions: Sequence[float]) -> list[Variant]:
    paper = f"r ≤ {PAPER_MAX_RANGE:.2f} m"
    out = [Variant("centerline", "centerline"), Variant("carve", "carve"),
           Variant("combined", "combined"),
           Variant(f"carve, {paper}", "carve", PAPER_MAX_RANGE),
           Variant(f"combined, {paper}", "combined", PAPER_MAX_RANGE)]
    out += [Variant(f"grid {h:.2f} m, Elfes cone", resolution=h, model=ELFES)
            for h in resolutions]
    out += [Variant(f"grid {h:.2f} m, ROS fade {ROS_FADE_RANGE:g} m", resolution=h, model=ROS)
            for h in resolutions]
    return out


def _simulate(world_name: str, seed: int) -> Simulation:
    world = load_world(world_name)
    if world.tour is None:
        msg = f"world {world_name!r} has no tour"
        raise SystemExit(msg)
    return simulate(world, load_robot("scout2"), follow_waypoints(world.tour), seed)


def _grid(world: World, resolution: float, model: SonarConeModel, seed: int) -> OccupancyGrid:
    """A grid over the world with its origin shifted by a seeded random fraction of a cell."""
    shift = np.random.default_rng(seed).uniform(0.0, resolution, 2)
    xmin, ymin, xmax, ymax = world.bounds
    bounds = (xmin - MARGIN - shift[0], ymin - MARGIN - shift[1], xmax + MARGIN, ymax + MARGIN)
    return OccupancyGrid(resolution, bounds, model)


def _mapper(variant: Variant, world: World, seed: int,
            batch: ReadingBatch) -> Callable[[], tuple[FloatArray, int]]:
    """A function that builds the variant's map from scratch: ``(points, grid bytes)``."""
    if variant.resolution is not None:
        resolution = variant.resolution

        def grid_map() -> tuple[FloatArray, int]:
            grid = _grid(world, resolution, variant.model, seed)
            grid.add_many(batch)
            return grid.occupied_points(DEFAULT_OCCUPIED_THRESHOLD), grid.nbytes

        return grid_map

    def method_map() -> tuple[FloatArray, int]:
        method = make_method(variant.method)
        method.add_many(batch)
        return method.finish().xy, 0

    return method_map


def _seen_patches(sim: Simulation, patches: PatchIndex) -> npt.NDArray[np.int64]:
    direct = sim.truth.kind == EchoKind.DIRECT
    ids = patch_of_points(sim.truth.reflection[direct], sim.world.segments, patches)
    return np.unique(ids[ids >= 0])


def _covered_patches(points: FloatArray, segments: FloatArray,
                     patches: PatchIndex) -> npt.NDArray[np.int64]:
    """Patches with a map point within :data:`COVER_DISTANCE` of their (nearest) wall."""
    if not points.shape[0]:
        return np.zeros(0, dtype=np.int64)
    distance, wall = segment_distance(points, segments)
    near = distance <= COVER_DISTANCE
    p, k = points[near], wall[near]
    start, step = segments[k, :2], segments[k, 2:] - segments[k, :2]
    length = np.hypot(step[:, 0], step[:, 1])
    along = np.clip(np.einsum("ij,ij->i", p - start, step) / length**2, 0.0, 1.0) * length
    pieces = np.diff(np.concatenate((patches.first, [len(patches)])))
    piece = np.minimum((along / patches.length).astype(np.int64), pieces[k] - 1)
    return np.unique(patches.first[k] + piece)


def _peak_mib(build: Callable[[], object]) -> float:
    tracemalloc.start()
    try:
        build()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def _measure(sim: Simulation, variant: Variant, seed: int, repeats: int) -> Row:
    batch = sim.readings
    if math.isfinite(variant.max_range):
        batch = batch[np.flatnonzero(batch.range <= variant.max_range)]
    build = _mapper(variant, sim.world, seed, batch)
    seconds = []
    for _ in range(repeats):
        tic = time.perf_counter()
        points, grid_bytes = build()
        seconds.append(time.perf_counter() - tic)
    peak = _peak_mib(build)
    distance = segment_distance(points, sim.world.segments)[0]
    patches = patch_index(sim.world.segments, PATCH_LENGTH)
    seen = _seen_patches(sim, patches)
    covered = np.isin(seen, _covered_patches(points, sim.world.segments, patches))
    return Row(
        points=float(points.shape[0]),
        median=float(np.median(distance)) if distance.size else math.nan,
        p90=float(np.percentile(distance, 90.0)) if distance.size else math.nan,
        phantom=100.0 * float(np.mean(distance > PHANTOM_DISTANCE)) if distance.size else 0.0,
        covered=100.0 * float(np.mean(covered)) if seen.size else math.nan,
        grid_mib=grid_bytes / 2**20,
        peak_mib=peak,
        readings_per_s=len(batch) / statistics.median(seconds),
    )


def _mean(rows: Sequence[Row]) -> Row:
    return Row(**{f.name: float(np.mean([getattr(r, f.name) for r in rows]))
                  for f in fields(Row)})


def _warm_up(sim: Simulation, resolutions: Sequence[float]) -> None:
    """Compile every numba kernel before anything is timed."""
    for variant in _variants(resolutions[:1]):
        _mapper(variant, sim.world, 0, sim.readings[:500])()


def _accuracy_tables(sims: dict[tuple[str, int], Simulation], worlds: Sequence[str],
                     seeds: int, resolutions: Sequence[float], repeats: int) -> None:
    for world in worlds:
        runs = [sims[(world, s)] for s in range(seeds)]
        print(f"\n{world}: scout2 along the tour, seeds 0-{seeds - 1}, "
              f"{np.mean([len(r.readings) for r in runs]):,.0f} readings per run; "
              f"mean over seeds\n")
        print("| map | points | median (m) | p90 (m) | > 0.25 m (%) | covered (%) | "
              "grid array (MiB) | peak traced (MiB) | readings/s |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for variant in _variants(resolutions):
            row = _mean([_measure(sim, variant, seed, repeats)
                         for seed, sim in enumerate(runs)])
            grid = f"{row.grid_mib:.2f}" if variant.resolution is not None else "–"
            print(f"| {variant.label} | {row.points:,.0f} | {row.median:.3f} | {row.p90:.3f} | "
                  f"{row.phantom:.1f} | {row.covered:.1f} | {grid} | {row.peak_mib:.1f} | "
                  f"{row.readings_per_s:,.0f} |")


def _threshold_table(runs: Sequence[Simulation], resolutions: Sequence[float],
                     thresholds: Sequence[float]) -> None:
    print(f"\nthreshold: office, seeds 0-{len(runs) - 1}, grids with ROS fade "
          f"{ROS_FADE_RANGE:g} m and the Elfes cone; mean over seeds "
          f"(default threshold {DEFAULT_OCCUPIED_THRESHOLD:g})\n")
    print("| grid | threshold | points | median (m) | p90 (m) | > 0.25 m (%) | covered (%) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for model, name in ((ROS, f"ROS fade {ROS_FADE_RANGE:g} m"), (ELFES, "Elfes cone")):
        for h in resolutions:
            grids = []
            for seed, sim in enumerate(runs):
                grid = _grid(sim.world, h, model, seed)
                grid.add_many(sim.readings)
                grids.append(grid)
            for threshold in thresholds:
                rows = []
                for sim, grid in zip(runs, grids, strict=True):
                    points = grid.occupied_points(threshold)
                    distance = segment_distance(points, sim.world.segments)[0]
                    patches = patch_index(sim.world.segments, PATCH_LENGTH)
                    seen = _seen_patches(sim, patches)
                    hit = np.isin(seen, _covered_patches(points, sim.world.segments, patches))
                    rows.append((points.shape[0], np.median(distance),
                                 np.percentile(distance, 90.0),
                                 100.0 * np.mean(distance > PHANTOM_DISTANCE),
                                 100.0 * np.mean(hit)))
                n, med, p90, phantom, covered = np.mean(rows, axis=0)
                print(f"| {h:.2f} m, {name} | {threshold:g} | {n:,.0f} | {med:.3f} | "
                      f"{p90:.3f} | {phantom:.1f} | {covered:.1f} |")


def _engine_table(sim: Simulation, resolutions: Sequence[float], repeats: int) -> None:
    """The compiled loop against the numpy version of the same update."""
    batch = sim.readings
    print(f"\ngrid update engines: office seed 0, {len(batch):,} readings, ROS fade model, "
          f"median of {repeats} runs after a warm-up\n")
    print("| resolution (m) | numba loop (readings/s) | numpy per reading (readings/s) | "
          "same grid |")
    print("|---:|---:|---:|---|")
    phi = np.where(np.isnan(batch.beam_width), ROS.beam_width, batch.beam_width)
    for h in resolutions:
        results = []
        for engine in (_update_kernel, _update_numpy):
            grid = _grid(sim.world, h, ROS, 0)

            def run(engine: Callable[..., None] = engine, grid: OccupancyGrid = grid) -> float:
                grid.reset()
                tic = time.perf_counter()
                engine(grid.log_odds, grid.bounds[0], grid.bounds[1], grid.resolution,
                       batch.x, batch.y,
                       batch.theta, batch.range, phi, grid.band, ROS.fade_range,
                       *ROS.log_odds)
                return time.perf_counter() - tic

            run()
            seconds = statistics.median(run() for _ in range(repeats))
            results.append((len(batch) / seconds, grid.log_odds.copy()))
        same = np.allclose(results[0][1], results[1][1], atol=1e-5)
        print(f"| {h:.2f} | {results[0][0]:,.0f} | {results[1][0]:,.0f} | "
              f"{'yes' if same else 'NO'} |")


def _doorway_table(seeds: int, resolutions: Sequence[float]) -> None:
    world = load_world("doorway")
    jamb_a, jamb_b = world.openings[0]
    region = gap_region(jamb_a, jamb_b, GAP_DEPTH)
    robot = load_robot("scout2")
    clearance = passage_clearance(robot.robot_radius)
    print(f"\ndoorway (Fig. 2): a {region.width:.2f} m door, the tour stops 1 m short of it; "
          f"final map; passable = a free stretch ≥ {clearance:.2f} m with no map point within "
          f"{GAP_DEPTH:g} m of the door line; seeds 0-{seeds - 1}\n")
    print("| map | passable (seeds) | free width (m), mean | grid: passable on cell squares | "
          f"grid: door cells free, p < {CLEAR_THRESHOLD:g} (%) |")
    print("|---|---:|---:|---:|---:|")
    sims = [_simulate("doorway", s) for s in range(seeds)]
    for variant in _variants(resolutions):
        widths, square_widths, cleared = [], [], []
        for seed, sim in enumerate(sims):
            batch = sim.readings
            if math.isfinite(variant.max_range):
                batch = batch[np.flatnonzero(batch.range <= variant.max_range)]
            if variant.resolution is None:
                widths.append(free_width(_mapper(variant, world, seed, batch)()[0], region))
                continue
            grid = _grid(world, variant.resolution, variant.model, seed)
            grid.add_many(batch)
            widths.append(free_width(grid.occupied_points(), region))
            square_widths.append(free_width(_cell_squares(grid), region))
            cleared.append(_door_cleared(grid, region))
        passable = sum(w >= clearance for w in widths)
        squares = (f"{sum(w >= clearance for w in square_widths)}/{seeds}"
                   if square_widths else "–")
        share = f"{np.mean(cleared):.0f}" if cleared else "–"
        print(f"| {variant.label} | {passable}/{seeds} | {np.mean(widths):.2f} | {squares} | "
              f"{share} |")


def _cell_squares(grid: OccupancyGrid, samples: int = 5) -> FloatArray:
    """Each occupied cell as a ``samples`` x ``samples`` lattice of points over its square."""
    centres = grid.occupied_points()
    offsets = (np.linspace(-0.5, 0.5, samples) * grid.resolution)
    dx, dy = np.meshgrid(offsets, offsets)
    lattice = np.column_stack((dx.ravel(), dy.ravel()))
    return np.asarray((centres[:, None, :] + lattice[None, :, :]).reshape(-1, 2))


def _door_cleared(grid: OccupancyGrid, region: GapRegion) -> float:
    """Share of the cells whose centre lies in the door region that the grid calls free."""
    xs, ys = grid.cell_centers()
    cx, cy = np.meshgrid(xs, ys)
    p = np.column_stack((cx.ravel(), cy.ravel())) - region.a
    s, h = p @ region.u, p @ region.n
    inside = (s >= 0) & (s <= region.width) & (np.abs(h) <= region.depth)
    return 100.0 * float(np.mean(grid.probabilities().ravel()[inside] < CLEAR_THRESHOLD))


def main(argv: list[str] | None = None) -> int:
    """Simulate, measure and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=["office", "t-junction", "doorway"])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.05, 0.10, 0.20],
                        help="grid cell sizes, metres")
    parser.add_argument("--thresholds", type=float, nargs="+", default=[0.5, 0.65, 0.8])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per cell (median)")
    args = parser.parse_args(argv)
    tic = time.perf_counter()

    sims = {(w, s): _simulate(w, s) for w in args.worlds for s in range(args.seeds)}
    _warm_up(next(iter(sims.values())), args.resolutions)
    _accuracy_tables(sims, args.worlds, args.seeds, args.resolutions, args.repeats)
    if "office" in args.worlds:
        office = [sims[("office", s)] for s in range(args.seeds)]
        _threshold_table(office, args.resolutions, args.thresholds)
        _engine_table(office[0], args.resolutions, args.repeats)
    _doorway_table(args.seeds, args.resolutions)
    print(f"\nruntime: {time.perf_counter() - tic:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
