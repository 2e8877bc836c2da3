"""What the driven-through map filter (``MapFilter(driven_through=...)``, ``process
--driven-through``) keeps and removes, beside the same map unfiltered, in the same run.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/driven_through.py                  # every group, ~25 min
    nice .venv/bin/python benchmarks/driven_through.py --groups car --seeds 1

The filter drops the map points that the robot's body covered at a later pose
(:func:`sonarcarve.filters.driven_through_mask`). Groups of simulations (``--groups``):

- ``car``: ``car-parking-12`` along the car park of :mod:`car_park` (as :mod:`parking`), under
  the specular, amplitude and "amplitude, car transducer" physics, with the parking question
  (the free length of the 6.0 m slot, the 4.5 m gap and the 3.2 m bay read from each map,
  and in how many runs a slot was judged present, :func:`parking.read_gap`);
- ``scout1`` and ``scout2``: the one-sonar and two-sonar Scout2 robots
  (``benchmarks/robots/scout2-front-1.yaml``, ``scout2-front-back.yaml``) on the held-out
  floors of :mod:`heldout` (``random:1``, ``random:2``, ``random:3:40x30``), specular and
  amplitude;
- ``dev``: the Scout2 ring on the development worlds (office, t-junction, doorway), specular and
  amplitude;
- ``pose``: the Scout2 ring on the office under the localisation error and odometry drift of
  :mod:`pose_error` (specular), where a revisit may put the body over a wall mapped from a
  pose that was wrong;
- ``scenes``: the changing scenes of :mod:`changing_scenes` (person, door, box; Scout2 ring),
  specular and amplitude: the final global map's echoes of the obstacle (the person, the shut
  door, the box) are counted apart from the static walls' direct echoes. The door shut while
  the robot approached and open when it drove through: its points are stale, dropping them is
  right for a map of the present.

For evidence carving's default map and paper carving's (``carve``), each row pools the runs
of its group (seeds 0..``--seeds``-1): the direct echoes kept, the spurious ones removed per
kind (crosstalk, floor, multipath; a reading counts once, kept if its point is in the map), the
median and p90 distance of the map's points to the true walls (mean over runs), the direct
points the filter dropped (and their median true error: a misplaced point in free space is
dropped rightly), and the filter's seconds against the method's. Filters: ``body``, the
robot's own footprint (:meth:`~sonarcarve.filters.BodyFootprint.of_robot`: mounts and
``robot_radius``), and ``sensors 0.05 m`` and ``sensors 0.1 m``
(:meth:`~sonarcarve.filters.BodyFootprint.around_sensors`, the fallback without a robot
description: a disc around each sensor's origin). The filter's CPU is given in milliseconds a
run beside the method's: on logs of 1,000-5,000 readings both are a few milliseconds, and
``--timing`` measures the ratio on a long log.

``--timing N``: instead, the CPU seconds of the filter against the method's (``process``'s
default ``combined`` and ``evidence``), best of 3 after a warm-up, on ``synthetic.py``'s
corridor loop of N readings (a 16-sensor ring driven round and round a 2 m wide corridor: the
true walls close beside a path driven again and again, where the filter should drop no true
echo), with the share of its true and spurious echoes dropped.

With the late-echo filter, in one run (neither / late echoes / driven through / both, as
``process`` runs them): ``benchmarks/late_echoes.py --both``.
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import car_park
from heldout import PHYSICS, WORLDS
from parking import CAR_PHYSICS, ROBOT, all_gaps, read_gap, slot_needed
from pose_error import CONDITIONS, simulate_condition
from sonarcarve import make_method
from sonarcarve.filters import BodyFootprint, driven_through_mask
from sonarcarve.lab.changing_scenes import simulate_changing_scene
from sonarcarve.lab.metrics import segment_distance
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import MethodConfig
from sonarcarve.pipeline import process_readings
from sonarcarve.robot import RobotDescription, load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.sim.world import load_world
from synthetic import RING_RADIUS, SENSORS, corridor_stream
from timing import best_seconds

METHODS = ("evidence", "carve")
ROBOTS = {"scout1": str(Path(__file__).resolve().parent / "robots" / "scout2-front-1.yaml"),
          "scout2": str(Path(__file__).resolve().parent / "robots" / "scout2-front-back.yaml")}
DEV_WORLDS = ("office", "t-junction", "doorway")
SENSOR_CLEARANCES = (0.05, 0.1)
SPURIOUS = (EchoKind.CROSSTALK, EchoKind.FLOOR, EchoKind.MULTIPATH)
SCENES = ("person", "door", "box")
#: The car park's gaps wider than 2 m: the 6.0 m slot, the 4.5 m gap, the 3.2 m bay.
SLOTS = [g for g in all_gaps() if g.length > 2.0]
GROUPS = ("car", "scout1", "scout2", "dev", "pose", "scenes")


def bodies(robot: RobotDescription) -> dict[str, BodyFootprint | None]:
    """The filter variants: none, the robot's body, small discs around each sensor."""
    return {"unfiltered": None,
            "body": BodyFootprint.of_robot(robot.mount_x, robot.mount_y, robot.bearing,
                                           robot.robot_radius),
            **{f"sensors {r} m": BodyFootprint.around_sensors(r) for r in SENSOR_CLEARANCES}}


@dataclass
class Tally:
    """Counts pooled over the runs of one (group, method, filter) row."""

    direct: int = 0
    direct_kept: int = 0
    kinds: dict[int, list[int]] = field(default_factory=dict)  # kind -> [readings, removed]
    medians: list[float] = field(default_factory=list)
    p90s: list[float] = field(default_factory=list)
    obstacle: int = 0
    obstacle_kept: int = 0
    dropped_direct: int = 0
    dropped_direct_error: list[float] = field(default_factory=list)
    dropped_spurious: int = 0
    gaps: list[list[float]] = field(default_factory=list)  # car park: read length a gap a run
    method_s: float = 0.0
    filter_s: float = 0.0
    losses: list[str] = field(default_factory=list)


def _score(tally: Tally, sim: Simulation, in_map: np.ndarray, err: np.ndarray) -> None:
    kind = sim.truth.kind
    obstacle = sim.truth.obstacle >= 0  # a changing scene's obstacle: counted apart
    direct = (kind == EchoKind.DIRECT) & ~obstacle
    tally.obstacle += int(obstacle.sum())
    tally.obstacle_kept += int(in_map[obstacle].sum())
    tally.direct += int(direct.sum())
    tally.direct_kept += int(in_map[direct].sum())
    for k in SPURIOUS:
        counts = tally.kinds.setdefault(int(k), [0, 0])
        counts[0] += int(np.sum(kind == k))
        counts[1] += int(np.sum((kind == k) & ~in_map))
    tally.medians.append(float(np.median(err)) if err.size else math.nan)
    tally.p90s.append(float(np.percentile(err, 90.0)) if err.size else math.nan)


def measure(sim: Simulation, robot: RobotDescription, label: str,
            rows: dict[tuple[str, str], Tally]) -> None:
    """Add one simulation's measures to ``rows`` (keyed by method and filter)."""
    kind = sim.truth.kind
    for method in METHODS:
        tic = time.process_time()
        gmap = process_readings(sim.readings, make_method(method, MethodConfig())).global_map
        method_s = time.process_time() - tic
        err = segment_distance(gmap.xy, sim.world.segments)[0]
        point_direct = ((kind[gmap.reading_id] == EchoKind.DIRECT)
                        & (sim.truth.obstacle[gmap.reading_id] < 0))
        for name, body in bodies(robot).items():
            tally = rows.setdefault((method, name), Tally())
            keep = np.ones(len(gmap), dtype=bool)
            if body is not None:
                tic = time.process_time()
                keep = ~driven_through_mask(gmap.xy, gmap.t, sim.readings, body)
                tally.filter_s += time.process_time() - tic
                dropped = ~keep & point_direct
                tally.dropped_direct += int(dropped.sum())
                tally.dropped_direct_error += err[dropped].tolist()
                tally.dropped_spurious += int(np.sum(
                    ~keep & (kind[gmap.reading_id] != EchoKind.DIRECT)))
                if dropped.any():
                    tally.losses.append(f"{label}: {int(dropped.sum())} direct (true error "
                                        f"median {np.median(err[dropped]):.2f} m)")
            tally.method_s += method_s
            if sim.world.name == "car-park":
                tally.gaps.append([read_gap(g, points=gmap.xy[keep]) for g in SLOTS])
            in_map = np.zeros(len(kind), dtype=bool)
            in_map[gmap.reading_id[keep]] = True
            _score(tally, sim, in_map, err[keep])


def _pct(part: int, whole: int) -> str:
    return f"{100 * part / whole:.1f} ({part}/{whole})" if whole else "–"


def print_table(title: str, rows: dict[tuple[str, str], Tally]) -> None:
    print(f"\n{title}\n")
    print("| method | filter | direct kept (%) | crosstalk removed (%) | floor removed (%) | "
          "multipath removed (%) | median / p90 error (m) | direct dropped by the filter "
          "(median true error, m) | spurious dropped by the filter | filter CPU ms a run "
          "(method's) | "
          "changing obstacle's echoes in the map |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for (method, name), t in rows.items():
        kinds = [_pct(t.kinds[int(k)][1], t.kinds[int(k)][0]) for k in SPURIOUS]
        dropped = "" if name == "unfiltered" else (
            f"{t.dropped_direct} ({np.median(t.dropped_direct_error):.2f})"
            if t.dropped_direct else "0")
        spurious = "" if name == "unfiltered" else str(t.dropped_spurious)
        runs = max(len(t.medians), 1)
        cpu = ("" if name == "unfiltered" else
               f"{1e3 * t.filter_s / runs:.1f} ({1e3 * t.method_s / runs:.0f})")
        print(f"| {method} | {name} | {_pct(t.direct_kept, t.direct)} | {' | '.join(kinds)} | "
              f"{np.nanmean(t.medians):.3f} / {np.nanmean(t.p90s):.3f} | {dropped} | {spurious} "
              f"| {cpu} | {_pct(t.obstacle_kept, t.obstacle)} |")
    if any(t.gaps for t in rows.values()):
        _print_gaps(rows)
    for (method, name), t in rows.items():
        for loss in t.losses:
            print(f"- loss, {method}, {name}: {loss}")


def _print_gaps(rows: dict[tuple[str, str], Tally]) -> None:
    """The car park's parking question (:mod:`parking`) read from each map."""
    head = " | ".join(f"{g.length:.1f} m {g.row.kind}: read (m), judged present" for g in SLOTS)
    print(f"\n| method | filter | {head} |")
    print("|---|---|" + "---:|" * len(SLOTS))
    for (method, name), t in rows.items():
        cells = []
        for i, gap in enumerate(SLOTS):
            read = [run[i] for run in t.gaps]
            judged = sum(r >= slot_needed(gap) for r in read)
            cells.append(f"{np.mean(read):.2f}, {judged} of {len(read)}")
        print(f"| {method} | {name} | " + " | ".join(cells) + " |")


Run = tuple[str, Callable[[], Simulation], RobotDescription]


def car_runs(seeds: int) -> Iterator[tuple[str, list[Run]]]:
    world = load_world(car_park.WORLD_FILE)
    assert world.tour is not None
    trajectory = follow_waypoints(world.tour, speed=car_park.SPEED,
                                  corner_radius=car_park.CORNER_RADIUS)
    robot = load_robot(ROBOT)
    for physics_name, physics in CAR_PHYSICS.items():
        yield f"car park, {ROBOT}, {physics_name}", [
            (f"seed {seed}", lambda s=seed, p=physics: simulate(world, robot, trajectory, s,
                                                                physics=p), robot)
            for seed in range(seeds)]


def ring_runs(robot_spec: str, worlds: tuple[str, ...], seeds: int,
              ) -> Iterator[tuple[str, list[Run]]]:
    robot = load_robot(robot_spec)
    for physics_name in ("specular", "amplitude"):
        overrides = () if physics_name == "specular" else (("echo_model", "amplitude"),)
        assert physics_name in PHYSICS
        yield f"{robot.name}, {', '.join(worlds)}, {physics_name}", [
            (f"{world} seed {seed}",
             lambda w=world, s=seed, o=overrides: run_simulation(
                 Scenario(w, s, physics=o, robot=robot_spec)), robot)  # type: ignore[arg-type]
            for world in worlds for seed in range(seeds)]


def pose_runs(seeds: int) -> Iterator[tuple[str, list[Run]]]:
    robot = load_robot("scout2")
    for condition in CONDITIONS:
        yield f"scout2, office, specular, {condition.label}", [
            (f"office seed {seed}",
             lambda s=seed, c=condition: simulate_condition("office", s, "specular", "scout2", c),
             robot) for seed in range(seeds)]


def scene_runs(seeds: int) -> Iterator[tuple[str, list[Run]]]:
    robot = load_robot("scout2")
    for physics_name in ("specular", "amplitude"):
        for scene in SCENES:
            yield f"changing scene {scene}, scout2, {physics_name}", [
                (f"seed {seed}", lambda n=scene, s=seed, p=PHYSICS[physics_name]:
                 simulate_changing_scene(n, s, physics=p)[1], robot) for seed in range(seeds)]


def groups(names: list[str], seeds: int) -> Iterator[tuple[str, list[Run]]]:
    for name in names:
        if name == "car":
            yield from car_runs(seeds)
        elif name in ROBOTS:
            yield from ring_runs(ROBOTS[name], WORLDS, seeds)
        elif name == "dev":
            yield from ring_runs("scout2", DEV_WORLDS, seeds)
        elif name == "pose":
            yield from pose_runs(seeds)
        elif name == "scenes":
            yield from scene_runs(seeds)


def timing(readings: int) -> None:
    """The ``--timing`` table (module docstring)."""
    stream = corridor_stream(readings, noise=0.01, spurious_share=0.05, seed=0)
    batch, spurious = stream.batch, np.asarray(stream.spurious)
    mount = 2.0 * math.pi * np.arange(SENSORS) / SENSORS
    ring = BodyFootprint.of_robot(RING_RADIUS * np.cos(mount), RING_RADIUS * np.sin(mount),
                                  mount, RING_RADIUS)
    print("\n| method | readings | points | filter | method CPU s | filter CPU s | filter / "
          "method (%) | true echoes dropped (%) | spurious dropped (%) |")
    print("|---|---:|---:|---|---:|---:|---:|---:|---:|")
    for method in ("combined", "evidence"):
        def make(m: str = method) -> object:
            return process_readings(batch, make_method(m, MethodConfig())).global_map
        gmap = process_readings(batch, make_method(method, MethodConfig())).global_map
        method_s = best_seconds(make, 3)
        for name, body in (("body (ring)", ring),
                           *((f"sensors {r} m", BodyFootprint.around_sensors(r))
                              for r in SENSOR_CLEARANCES)):
            filter_s = best_seconds(lambda b=body, g=gmap: driven_through_mask(g.xy, g.t, batch, b),
                                    3)
            gone = driven_through_mask(gmap.xy, gmap.t, batch, body)
            false = spurious[gmap.reading_id]
            print(f"| {method} | {len(batch):,} | {len(gmap):,} | {name} | {method_s:.2f} | "
                  f"{filter_s:.3f} | {100 * filter_s / method_s:.1f} | "
                  f"{100 * np.mean(gone[~false]):.2f} | {100 * np.mean(gone[false]):.2f} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--groups", nargs="+", default=list(GROUPS), choices=list(GROUPS))
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--timing", type=int, metavar="N",
                        help="only the filter's CPU time against the method's, on N readings")
    args = parser.parse_args(argv)
    command = "nice .venv/bin/python benchmarks/driven_through.py " + shlex.join(
        argv if argv is not None else sys.argv[1:])
    print(f"`{command.strip()}`")
    if args.timing is not None:
        timing(args.timing)
        return 0
    for title, runs in groups(args.groups, args.seeds):
        rows: dict[tuple[str, str], Tally] = {}
        for label, make, robot in runs:
            sim = make()
            measure(sim, robot, label, rows)
            print(f"  {title}, {label}: {len(sim.readings):,} readings", flush=True)
        print_table(title, rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
