"""Measure specular-aware carving (``max_incidence``, beyond the paper) on the simulator.

Run from the repository root::

    .venv/bin/python benchmarks/specular.py

The simulator's walls are specular: a beam meeting a wall more than 17.5° off its normal hears no
echo from it (``SonarPhysics.critical_angle``). Paper-exact carving then lets a newer reading
that looked past a wall at a glancing angle carve away older, correct arcs of that wall. With a
critical angle β, carving skips the points of an older arc whose implied surface the newer
reading would see at an incidence above β (:mod:`sonarcarve.geometry`).

For each world and seed the script simulates the Scout2 ring along the world's tour once, then
maps it with ``carve`` and ``combined`` (library defaults, only ``max_incidence`` varied) and
prints a markdown table, averaged over seeds, of:

* points in the global map, and their median / 90th-percentile distance to the true walls;
* direct readings lost: share of direct echoes (truth kind ``direct``) with no point in the
  global map, and how they were lost: fully carved / split;
* the same when only the direct readings are fed in (``carve`` only): what carving loses on
  correct data alone;
* spurious readings removed: share of the other readings (crosstalk, floor, multipath) with no
  point in the global map;
* the mean unprocessed share of the history (Table I) and the throughput of the method
  (``process_readings``; one core, numba kernels compiled by a warm-up run first; these logs are
  short, so the figure is noisy).

A last table times ``carve`` at history 250 for each β on the ring-corridor stream of
``throughput.py`` (20,000 readings, median of 3 runs after a warm-up), whose requirement is at
least 20,000 readings/s.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve import MethodConfig, ReadingBatch, make_method
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.history import SonarHistory
from sonarcarve.lab.metrics import segment_distance
from sonarcarve.methods.base import ArcFate, Estimates, SlotArray
from sonarcarve.pipeline import process_readings
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.sim.world import load_world
from synthetic import corridor_stream

METHODS = ("carve", "combined")
COLUMNS = ("points", "median", "p90", "direct_lost", "direct_fully", "direct_split",
           "direct_only_lost", "spurious_removed", "unprocessed", "readings_per_s")


@dataclass(frozen=True)
class Row:
    """Measures of one method, one β, one simulation (shares in percent, distances in m)."""

    points: float
    median: float
    p90: float
    direct_lost: float
    direct_fully: float
    direct_split: float
    direct_only_lost: float
    spurious_removed: float
    unprocessed: float
    readings_per_s: float


def _simulate(world_name: str, seed: int) -> Simulation:
    world = load_world(world_name)
    if world.tour is None:
        msg = f"world {world_name!r} has no tour"
        raise SystemExit(msg)
    return simulate(world, load_robot("scout2"), follow_waypoints(world.tour), seed)


def _lost(batch: ReadingBatch, name: str, config: MethodConfig) -> npt.NDArray[np.bool_]:
    """Whether each reading of ``batch`` has no point in the method's global map."""
    result = process_readings(batch, make_method(name, config))
    lost = np.ones(len(batch), dtype=bool)
    lost[result.global_map.reading_id] = False
    return lost


def _measure(sim: Simulation, name: str, beta: float) -> Row:
    config = MethodConfig(max_incidence=beta)
    method = make_method(name, config)
    removal = np.zeros(len(sim.readings), dtype=np.int8)

    def record(history: SonarHistory, slots: SlotArray, est: Estimates) -> None:
        if est.fate is not None:
            removal[history.reading_id[slots]] = est.fate

    method.add_commit_listener(record)
    result = process_readings(sim.readings, method)
    gmap = result.global_map
    distance = segment_distance(gmap.xy, sim.world.segments)[0]
    direct = sim.truth.kind == EchoKind.DIRECT
    lost = np.ones(len(sim.readings), dtype=bool)
    lost[gmap.reading_id] = False  # reading ids are row positions (process_readings)
    direct_only = math.nan
    if name == "carve":
        direct_only = 100.0 * float(np.mean(_lost(sim.readings[np.flatnonzero(direct)], name,
                                                  config)))
    return Row(
        points=float(len(gmap)),
        median=float(np.median(distance)),
        p90=float(np.percentile(distance, 90.0)),
        direct_lost=100.0 * float(np.mean(lost[direct])),
        direct_fully=100.0 * float(np.mean(removal[direct] == ArcFate.FULLY_CARVED)),
        direct_split=100.0 * float(np.mean(removal[direct] == ArcFate.SPLIT)),
        direct_only_lost=direct_only,
        spurious_removed=100.0 * float(np.mean(lost[~direct])),
        unprocessed=100.0 * result.mean_unprocessed_share,
        readings_per_s=result.readings_per_second,
    )


def _mean(rows: Sequence[Row]) -> Row:
    return Row(**{c: float(np.mean([getattr(r, c) for r in rows])) for c in COLUMNS})


def _label(beta: float) -> str:
    return "off (paper)" if beta >= NO_INCIDENCE_LIMIT else f"{math.degrees(beta):g}°"


def _cell(value: float, digits: int) -> str:
    return "n/a" if math.isnan(value) else f"{value:,.{digits}f}"


def main(argv: list[str] | None = None) -> int:
    """Simulate, measure and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=["office", "t-junction"])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--betas", type=float, nargs="+", default=[90.0, 45.0, 30.0, 20.0, 17.5],
                        help="critical angles β, degrees (90 = off = the paper)")
    args = parser.parse_args(argv)
    betas = [min(math.radians(b), NO_INCIDENCE_LIMIT) for b in args.betas]

    sims = {(w, s): _simulate(w, s) for w in args.worlds for s in range(args.seeds)}
    warm = next(iter(sims.values())).readings[:2000]
    for name in METHODS:  # compile the kernels in both modes before timing anything
        for beta in (NO_INCIDENCE_LIMIT, math.radians(30.0)):
            process_readings(warm, make_method(name, MethodConfig(max_incidence=beta)))

    for world in args.worlds:
        runs = [sims[(world, s)] for s in range(args.seeds)]
        direct = np.mean([np.mean(r.truth.kind == EchoKind.DIRECT) for r in runs])
        print(f"\n{world}: {args.seeds} seeds, {np.mean([len(r.readings) for r in runs]):,.0f} "
              f"readings per run, {100 * direct:.1f} % direct; mean over seeds\n")
        print("| β | method | points | median (m) | p90 (m) | direct lost (%) | "
              "fully carved / split (%) | direct lost, direct-only log (%) | "
              "spurious removed (%) | unprocessed (%) | readings/s |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
        for beta in betas:
            for name in METHODS:
                row = _mean([_measure(sim, name, beta) for sim in runs])
                print(f"| {_label(beta)} | {name} | {row.points:,.0f} | {row.median:.3f} | "
                      f"{row.p90:.3f} | {row.direct_lost:.1f} | "
                      f"{row.direct_fully:.1f} / {row.direct_split:.1f} | "
                      f"{_cell(row.direct_only_lost, 1)} | {row.spurious_removed:.1f} | "
                      f"{row.unprocessed:.1f} | {row.readings_per_s:,.0f} |")
    _throughput(betas)
    return 0


def _throughput(betas: Sequence[float], history: int = 250, repeats: int = 3) -> None:
    """``carve`` readings/s per β on ``throughput.py``'s stream, measured the same way."""
    batch = corridor_stream(20_000, noise=0.01, spurious_share=0.05, seed=0).batch

    def run(beta: float, readings: ReadingBatch) -> float:
        method = make_method("carve", MethodConfig(history_size=history, max_incidence=beta))
        tic = time.perf_counter()
        method.add_many(readings)
        method.finish()
        return time.perf_counter() - tic

    print(f"\nthroughput: carve, history {history}, ring corridor, {len(batch):,} readings "
          f"(benchmarks/synthetic.py, seed 0), median of {repeats} runs\n")
    print("| β | readings/s |")
    print("|---|---:|")
    for beta in betas:
        run(beta, batch[:2000])  # warm-up
        seconds = statistics.median(run(beta, batch) for _ in range(repeats))
        print(f"| {_label(beta)} | {len(batch) / seconds:,.0f} |")


if __name__ == "__main__":
    raise SystemExit(main())
