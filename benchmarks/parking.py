"""Held out: a car's parking sensors in a car park, where each method and grid wins and loses.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/parking.py                     # seeds 0-2, 3 physics
    nice .venv/bin/python benchmarks/parking.py --seeds 1 --physics specular
    nice .venv/bin/python benchmarks/parking.py --beam-deg 120 --skip-grids   # diagnostics
    nice .venv/bin/python benchmarks/parking.py --physics specular --speed 0.4

Every default of sonarcarve was chosen with robot sonar rings (22.5°, 15° and 20° beams) in
office-like buildings. This script drives the ``car-parking-12`` robot (a 4.5 x 1.8 m car,
12 sensors of 70° beams, 0.15-5.5 m) along the lane of ``benchmarks/worlds/car-park.json``
(:mod:`car_park`: parked cars, gaps, pillars, a kerb, one turn) at parking speed
(:data:`car_park.SPEED`, 1 m/s), and measures, with nothing tuned on it:

- **points**: for centerline, paper carving (``carve``), ``combined`` (the default) and
  ``evidence``, the direct echoes kept and spurious echoes removed (shares), the median and p90
  distance of the global map's points to the true walls and their ratios to centerline's on
  the same run (as :mod:`heldout`), and the number of readings;
- **costmaps**: the carved grid (default) against ``RangeSensorLayer`` (defaults) at 0.05 and
  0.10 m: occupied precision, recall, phantom share, free floor near the path
  (:func:`sonarcarve.lab.grid_measures.grid_measures`; "near the path" is within 0.75 m of the
  sensors' positions, which for a car are on its body outline);
- **the parking question**: for every gap between two neighbouring parked cars, its free length
  as read from each map, against the truth.

The gap's free length read from a map (:func:`read_gap`): take the gap's stretch of the row,
from :data:`REACH` metres inside the left car (west of its end) to :data:`REACH` metres inside
the right car, and the row's band across it (the first 1.5 m of the cars from their lane side
and 0.3 m into the lane, :class:`car_park.Row`). Every map point in that rectangle (every
occupied cell whose square meets it, for grids) blocks the stretch where it projects on the
lane axis; the read length is the longest unblocked stretch, the rectangle's two ends counting
as blocked (:func:`sonarcarve.lab.metrics.free_width` and
:func:`sonarcarve.lab.grid_measures.grid_free_width` on that rectangle). So a map that sees both
car ends where they are reads the true gap; one that smears echoes into the gap reads it short;
one that misses a car end reads it long, by at most ``REACH`` per end. The error is read minus
true length. A slot is **judged present** when the read length reaches the need of the row:
:data:`PARALLEL_SLOT` (5.2 m: the 4.5 m car plus 0.7 m to manoeuvre) for the parallel row,
:data:`PERPENDICULAR_BAY` (2.4 m: the 1.8 m car plus 0.6 m to open doors; an assumption) for the
perpendicular one. The true slots: the 6.0 m gap (present), the 4.5 m gap (not present: the
car does not fit) and the empty bay (3.2 m between car sides, present); every other gap is two
cars 0.7-1.0 m apart (a "false slot" if judged present).

Physics: ``specular`` and ``amplitude`` as in :mod:`heldout` (both shipped models at their
defaults), and ``amplitude, car transducer``: the amplitude model with a transducer whose beam
matches the car's sensors instead of the Polaroid's (decided before any run, from the robot
file, not tuned): 48 kHz (a production park-assist sensor's 48 ± 5 kHz, see the robot YAML)
and a piston radius for which the 70° beam is the two-way −6 dB width (one-way −3 dB at ±35°:
ka sin 35° = 1.616, a = 3.2 mm), diffuse echoes traced over the whole front half-plane. The
shipped amplitude default models the Polaroid 600 transducer (about 25° between first nulls)
whatever beam width the robot file declares, so its readings are narrower than they say.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import shlex
import sys
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

import car_park
from heldout import GRIDS, MARGIN, METHODS, PHYSICS, RESOLUTIONS
from sonarcarve import make_method
from sonarcarve.grids import OccupancyMap
from sonarcarve.lab.grid_measures import grid_free_width, grid_measures
from sonarcarve.lab.metrics import GapRegion, free_width, gap_region, segment_distance
from sonarcarve.methods import MethodConfig
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import load_robot
from sonarcarve.sim.amplitude import AmplitudeModel
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind, SonarPhysics
from sonarcarve.sim.world import load_world

ROBOT = "car-parking-12"
#: x where the one-way piston directivity |2 J1(x) / x| is 1/√2 (−3 dB).
_MINUS_3DB_X = 1.6163
CAR_BEAM_DEG = 70.0
CAR_FREQUENCY = 48_000.0


def car_transducer_radius(beam_deg: float = CAR_BEAM_DEG, frequency: float = CAR_FREQUENCY,
                          sound_speed: float = 343.0) -> float:
    """Piston radius (m) whose one-way −3 dB (two-way −6 dB) full width is ``beam_deg``."""
    ka = _MINUS_3DB_X / math.sin(math.radians(beam_deg / 2.0))
    return ka * sound_speed / (2.0 * math.pi * frequency)


CAR_PHYSICS: dict[str, SonarPhysics] = {
    "specular": PHYSICS["specular"],
    "amplitude": PHYSICS["amplitude"],
    "amplitude, car transducer": SonarPhysics(
        echo_model="amplitude",
        amplitude=AmplitudeModel(frequency=CAR_FREQUENCY,
                                 transducer_radius=car_transducer_radius(),
                                 fan_half_angle=math.pi / 2, fan_rays=181)),
}
POINT_METHODS = ("centerline", *METHODS)
#: How far past each car end (into the car) the read stretch may reach, metres.
REACH = 1.0
PARALLEL_SLOT, PERPENDICULAR_BAY = 5.2, 2.4
MapKey = tuple[str, float]  # (map name, resolution; 0.0 for point maps)


class Run(NamedTuple):
    """One simulation's measures."""

    readings: int
    outside: float  # share of direct echoes whose true reflector lies outside the declared beam
    points: dict[str, dict[str, float]]
    grids: dict[MapKey, dict[str, float]]
    gaps: dict[MapKey, list[float]]  # read length of every gap, in :func:`all_gaps` order


def all_gaps() -> list[car_park.Gap]:
    """Every gap of both rows, south row first, west to east."""
    return [gap for row in car_park.rows() for gap in car_park.gaps(row)]


def gap_rectangle(gap: car_park.Gap) -> GapRegion:
    """The rectangle whose map points block ``gap`` (module docstring)."""
    low, high = gap.row.band
    middle = (low + high) / 2.0
    return gap_region([gap.left - REACH, middle], [gap.right + REACH, middle],
                      depth=(high - low) / 2.0)


def read_gap(gap: car_park.Gap, points: np.ndarray | None = None,
             grid: OccupancyMap | None = None, cells: np.ndarray | None = None) -> float:
    """The gap's free length read from map ``points`` (shape (n, 2)) or from ``grid`` (its
    trinary ``cells`` if already computed), metres."""
    region = gap_rectangle(gap)
    if grid is not None:
        return grid_free_width(grid, region, cells=cells)
    return free_width(np.zeros((0, 2)) if points is None else points, region)


def slot_needed(gap: car_park.Gap) -> float:
    """The free length that makes ``gap`` a usable slot for the car, metres."""
    return PARALLEL_SLOT if gap.row.kind == "parallel" else PERPENDICULAR_BAY


def _simulate(seed: int, physics: SonarPhysics, speed: float = car_park.SPEED) -> Simulation:
    world = load_world(car_park.WORLD_FILE)
    assert world.tour is not None
    trajectory = follow_waypoints(world.tour, speed=speed,
                                  corner_radius=car_park.CORNER_RADIUS)
    return simulate(world, load_robot(ROBOT), trajectory, seed, physics=physics)


def relabelled(sim: Simulation, beam_deg: float) -> Simulation:
    """``sim`` with every reading declaring a ``beam_deg`` beam (the echoes unchanged): what a
    robot file with another beam width would have told the methods and grids."""
    r = sim.readings
    batch = ReadingBatch.from_arrays(t=r.t, sensor=r.sensor, x=r.x, y=r.y, theta=r.theta,
                                     range=r.range, beam_width=np.full(len(r), math.radians(
                                         beam_deg)), max_range=r.max_range)
    return dataclasses.replace(sim, readings=batch)


def outside_share(sim: Simulation) -> float:
    """Share of the direct echoes whose true reflection point lies outside the beam the reading
    declares (the arc model's assumption broken: no method can place them right)."""
    r, refl = sim.readings, sim.truth.reflection
    direct = sim.truth.kind == EchoKind.DIRECT
    bearing = np.arctan2(refl[:, 1] - r.y, refl[:, 0] - r.x)
    off = np.abs((bearing - r.theta + math.pi) % (2.0 * math.pi) - math.pi)
    return float(np.mean(off[direct] > 0.5 * r.beam_width[direct] + 1e-9))


def _point_maps(sim: Simulation, config: MethodConfig) -> dict[str, dict[str, float] | np.ndarray]:
    """Per method: the measures of the module docstring and (key ``xy``) the map's points."""
    kind = sim.truth.kind
    direct = kind == EchoKind.DIRECT
    out: dict[str, dict[str, float] | np.ndarray] = {}
    center_err = np.full(len(kind), np.nan)
    for name in POINT_METHODS:
        gmap = process_readings(sim.readings, make_method(name, config)).global_map
        err = segment_distance(gmap.xy, sim.world.segments)[0]
        if name == "centerline":
            center_err[gmap.reading_id] = err
        kept = np.zeros(len(kind), dtype=bool)
        kept[gmap.reading_id] = True
        median, p90 = float(np.median(err)), float(np.percentile(err, 90.0))
        out[name] = {
            "kept": float(np.mean(kept[direct])),
            "removed": float(np.mean(~kept[~direct])) if (~direct).any() else math.nan,
            "spurious": float(np.mean(~direct)),
            "median": median, "p90": p90,
            "median ratio": median / float(np.median(center_err[gmap.reading_id])),
            "p90 ratio": p90 / float(np.nanpercentile(center_err, 90.0)),
            "points": float(len(err)),
        }
        out[f"{name} xy"] = np.asarray(gmap.xy)
    return out


def _grids(sim: Simulation) -> dict[MapKey, OccupancyMap]:
    xmin, ymin, xmax, ymax = sim.world.bounds
    bounds = (xmin - MARGIN, ymin - MARGIN, xmax + MARGIN, ymax + MARGIN)
    out: dict[MapKey, OccupancyMap] = {}
    for h in RESOLUTIONS:
        for name, make in GRIDS.items():
            grid = make(h, bounds)
            grid.add_many(sim.readings)
            out[name, h] = grid
    return out


def measure(sim: Simulation, with_grids: bool = True,
            config: MethodConfig | None = None) -> Run:
    """Points, costmaps and gaps of one simulation (the methods with ``config``, default
    :class:`~sonarcarve.methods.MethodConfig`'s defaults)."""
    gaps = all_gaps()
    maps = _point_maps(sim, MethodConfig() if config is None else config)
    points = {name: maps[name] for name in POINT_METHODS}
    read = {(name, 0.0): [read_gap(g, points=maps[f"{name} xy"]) for g in gaps]
            for name in POINT_METHODS}
    grid_rows: dict[MapKey, dict[str, float]] = {}
    if with_grids:
        reflections = sim.truth.reflection[sim.truth.kind == EchoKind.DIRECT]
        path = np.column_stack((sim.readings.x, sim.readings.y))
        for key, grid in _grids(sim).items():
            m = grid_measures(grid, sim.world.segments, reflections, sim.world.bounds, path=path)
            grid_rows[key] = {"precision": m.precision, "recall": m.recall,
                              "phantoms": m.phantoms, "free": m.free_near_path}
            read[key] = [read_gap(g, grid=grid) for g in gaps]
    return Run(len(sim.readings), outside_share(sim), points, grid_rows, read)  # type: ignore[arg-type]


# -- tables ------------------------------------------------------------------------------------

def _mean(values: Sequence[float]) -> float:
    return float(np.nanmean(values))


def _points_table(runs: Sequence[Run]) -> None:
    print("\n| method | readings | spurious share (%) | direct kept (%) | spurious removed (%) | "
          "median error (m) | p90 error (m) | median / centerline's | p90 / centerline's |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name in POINT_METHODS:
        rows = [run.points[name] for run in runs]
        readings = _mean([run.readings for run in runs])
        print(f"| {name} | {readings:,.0f} | {100 * _mean([r['spurious'] for r in rows]):.1f} | "
              f"{100 * _mean([r['kept'] for r in rows]):.1f} | "
              f"{100 * _mean([r['removed'] for r in rows]):.1f} | "
              f"{_mean([r['median'] for r in rows]):.3f} | {_mean([r['p90'] for r in rows]):.3f} "
              f"| {_mean([r['median ratio'] for r in rows]):.2f} | "
              f"{_mean([r['p90 ratio'] for r in rows]):.2f} |")


def _grids_table(runs: Sequence[Run]) -> None:
    print("\n| resolution (m) | grid | precision | recall | phantoms (%) | free near the path (%) "
          "| runs where the carved grid beats the layer on precision and recall |")
    print("|---:|---|---:|---:|---:|---:|---:|")
    for h in RESOLUTIONS:
        wins = sum(run.grids["carved grid", h]["precision"]
                   > run.grids["RangeSensorLayer", h]["precision"]
                   and run.grids["carved grid", h]["recall"]
                   > run.grids["RangeSensorLayer", h]["recall"] for run in runs)
        for name in GRIDS:
            rows = [run.grids[name, h] for run in runs]
            won = f"{wins} of {len(runs)}" if name == "carved grid" else ""
            print(f"| {h:.2f} | {name} | {_mean([r['precision'] for r in rows]):.3f} | "
                  f"{_mean([r['recall'] for r in rows]):.3f} | "
                  f"{100 * _mean([r['phantoms'] for r in rows]):.3f} | "
                  f"{100 * _mean([r['free'] for r in rows]):.1f} | {won} |")


def _map_label(key: MapKey) -> str:
    name, h = key
    return name if h == 0.0 else f"{name} {h:.2f} m"


def _gaps_table(runs: Sequence[Run]) -> None:
    gaps = all_gaps()
    slots = [i for i, g in enumerate(gaps) if g.length > 2.0]  # the 6.0, 4.5 and 3.2 m gaps
    closed = [i for i, g in enumerate(gaps) if g.length <= 2.0]
    truth = {i: "yes" if gaps[i].length >= slot_needed(gaps[i]) else "no" for i in slots}
    head = " | ".join(f"{gaps[i].length:.1f} m {gaps[i].row.kind}: read (m), error (cm), "
                      f"judged present (true: {truth[i]})" for i in slots)
    print(f"\n| map | {head} | {len(closed)} closed gaps (0.7-1.0 m): median error (cm), "
          "max error (cm), false slots |")
    print("|---|" + "---:|" * (len(slots) + 1))
    for key in runs[0].gaps:
        cells = []
        for i in slots:
            read = [run.gaps[key][i] for run in runs]
            judged = sum(r >= slot_needed(gaps[i]) for r in read)
            cells.append(f"{_mean(read):.2f}, {100 * (_mean(read) - gaps[i].length):+.0f}, "
                         f"{judged} of {len(runs)}")
        err = [100 * (run.gaps[key][i] - gaps[i].length) for run in runs for i in closed]
        false = sum(run.gaps[key][i] >= slot_needed(gaps[i]) for run in runs for i in closed)
        cells.append(f"{np.median(err):+.0f}, {max(err, key=abs):+.0f}, {false} of "
                     f"{len(runs) * len(closed)}")
        print(f"| {_map_label(key)} | " + " | ".join(cells) + " |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1")
    parser.add_argument("--physics", nargs="+", default=list(CAR_PHYSICS),
                        choices=list(CAR_PHYSICS))
    parser.add_argument("--skip-grids", action="store_true")
    parser.add_argument("--beam-deg", type=float, metavar="DEG",
                        help="diagnostic: the readings declare DEG-degree beams instead of the "
                             "robot file's (the echoes are the same)")
    parser.add_argument("--speed", type=float, default=car_park.SPEED, metavar="M_PER_S",
                        help="diagnostic: drive at this speed instead of %(default)s m/s")
    parser.add_argument("--evidence-bins", type=int, metavar="K",
                        help="diagnostic: evidence carving with K bins per beam instead of its "
                             "default")
    args = parser.parse_args(argv)
    command = "nice .venv/bin/python benchmarks/parking.py " + shlex.join(
        argv if argv is not None else sys.argv[1:])
    print(f"`{command.strip()}`")
    config = (MethodConfig() if args.evidence_bins is None
              else MethodConfig(evidence_bins=args.evidence_bins))
    for physics_name in args.physics:
        runs = []
        for seed in range(args.seeds):
            sim = _simulate(seed, CAR_PHYSICS[physics_name], args.speed)
            if args.beam_deg is not None:
                sim = relabelled(sim, args.beam_deg)
            runs.append(measure(sim, with_grids=not args.skip_grids, config=config))
            print(f"  {physics_name}, seed {seed}: {len(sim.readings):,} readings", flush=True)
        beam = "" if args.beam_deg is None else f" (readings declare {args.beam_deg:g}° beams)"
        where = (f"car-park.json, {ROBOT}{beam}, {args.speed:g} m/s; seeds "
                 f"0-{args.seeds - 1}; physics: {physics_name}; mean over seeds")
        outside = 100 * _mean([run.outside for run in runs])
        print(f"\n{physics_name}: {outside:.1f} % of the direct echoes came from outside the "
              "beam their reading declares")
        print(f"\npoints, {where}")
        _points_table(runs)
        if not args.skip_grids:
            print(f"\ncostmaps, {where}")
            _grids_table(runs)
        print(f"\ngaps, {where} (read length and error: means over seeds; judged: in how many "
              "seeds)")
        _gaps_table(runs)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
