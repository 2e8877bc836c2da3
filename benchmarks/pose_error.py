"""Maps from readings stamped with wrong poses: localisation noise and odometry drift.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/pose_error.py --physics specular --save /tmp/pose-s.json
    nice .venv/bin/python benchmarks/pose_error.py --physics amplitude --save /tmp/pose-a.json
    nice .venv/bin/python benchmarks/pose_error.py --quick       # office, seed 0, specular

Every other accuracy number of sonarcarve comes from simulated readings stamped with the *true*
robot pose. Here the echoes are the same (they come from the true poses, so the truth of each
reading is unchanged) but the readings carry what the robot *believes*
(:class:`~sonarcarve.lab.scenarios.Scenario`'s ``localisation_noise`` and ``odometry_drift``):

- ``true poses``;
- ``localisation 2 cm / 0.5°`` and ``localisation 5 cm / 2°``: the true path plus the
  Gauss-Markov error of :func:`~sonarcarve.sim.motion.with_localisation_noise` (stationary σ in x
  and in y, σ in heading, correlation time 1 s), a localiser (AMCL, a fused odometry) at two
  qualities;
- ``odometry drift``: dead reckoning, :func:`~sonarcarve.sim.motion.with_odometry_drift` with
  its defaults (the Fig. 7 experiment's condition).

Per method (centerline, paper carving, combined, evidence carving, and evidence with the
occlusion map filter as ``benchmarks/evidence.py`` uses it), on each world's tour, seed and
physics: direct echoes kept and spurious removed (per kind), the median and p90 true error of the
global map's points (distance to the nearest wall) raw and with each point's pose error removed
(moved as :func:`~sonarcarve.lab.experiments.odometry.pose_corrected` does: what the method
itself got wrong), and the median and p90 ratios to centerline's on the same readings
(``benchmarks/evidence.py``'s measure, :func:`evidence.map_row`).

Per grid (the carved grid, the faithful RangeSensorLayer with ROS's defaults, the Elfes/octomap
grid) at 0.10 and 0.05 m, under localisation noise only (dead reckoning puts the walls
themselves in the wrong place after a few metres, so a grid against the true walls measures the
drift, not the grid): occupied precision, recall and phantom share against the true walls
(:mod:`sonarcarve.lab.grid_measures`, filled as ``benchmarks/grids.py`` fills them).

``--pose-sigma`` adds the fix tried for what breaks: evidence carving with its range tolerance
ε widened by 2σ (a newer reading's free space ends 2σ earlier) and the carved grid with
``CarvedGridParams(pose_sigma=σ)``, σ the condition's position σ as a user would set it from
the localiser (0 under true poses and drift, where the rows are the defaults' own).

Worlds: the office, t-junction and doorway tours and the held-out generated floor ``random:1``
(``benchmarks/heldout.py``'s first), the Scout2 ring unless ``--robot`` (``p3dx-front``: the
Pioneer's 8 front sonars). ``--save FILE`` writes every per-run row as JSON (``--load FILE`` to
print the tables again from it). A full run (4 worlds, 3 seeds, one physics) takes about
11 minutes on this machine (the two physics run side by side, load
4-5; 450 MB resident each).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from evidence import KINDS, map_row
from grids import Factory, _carved, _elfes, _fill, _layer
from sonarcarve import MethodConfig, SonarMethod, make_method
from sonarcarve.filters import OCCLUSION_DEPTH, MapFilter
from sonarcarve.grids import CarvedGrid, CarvedGridParams, OccupancyMap, RangeSensorLayerParams
from sonarcarve.grids.carved.params import POSE_MARGIN_SIGMAS
from sonarcarve.lab.experiments.odometry import pose_corrected
from sonarcarve.lab.grid_measures import grid_measures
from sonarcarve.lab.metrics import segment_distance
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.pipeline import process_readings
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import EchoKind

WORLDS = ("office", "t-junction", "doorway", "random:1")
RESOLUTIONS = (0.10, 0.05)
#: Correlation time of the localisation error, seconds (a localiser's estimate wanders).
CORRELATION_TIME = 1.0


@dataclass(frozen=True)
class Condition:
    """How the readings are stamped: a localiser's error (σ m, σ rad, τ s) and/or drift."""

    label: str
    localisation_noise: tuple[float, float, float] | None = None
    odometry_drift: bool = False

    @property
    def position_sigma(self) -> float:
        """σ of the localisation error in x and y, metres (0 without one): the pose
        uncertainty a user would give ``--pose-sigma``'s rows."""
        return 0.0 if self.localisation_noise is None else self.localisation_noise[0]

    @property
    def for_grids(self) -> bool:
        """Grids are measured against the true walls, so not under drift (see the docstring)."""
        return not self.odometry_drift


CONDITIONS = (
    Condition("true poses"),
    Condition("localisation 2 cm / 0.5°", (0.02, math.radians(0.5), CORRELATION_TIME)),
    Condition("localisation 5 cm / 2°", (0.05, math.radians(2.0), CORRELATION_TIME)),
    Condition("odometry drift", odometry_drift=True),
)

MethodFactory = Callable[[MethodConfig], SonarMethod]
#: Rows of the point tables: name, method, map filter (evidence.py's occlusion row).
METHODS: tuple[tuple[str, str, MapFilter | None], ...] = (
    ("centerline", "centerline", None),
    ("carve (paper)", "carve", None),
    ("combined (paper)", "combined", None),
    ("evidence", "evidence", None),
    ("evidence, occluded points dropped", "evidence", MapFilter(occlusion_depth=OCCLUSION_DEPTH)),
)
GRIDS: tuple[tuple[str, Factory], ...] = (
    ("carved grid", _carved),
    ("RangeSensorLayer, ROS defaults", _layer(RangeSensorLayerParams())),
    ("Elfes/octomap grid", _elfes),
)
#: Names of the ``--pose-sigma`` rows: evidence carving with ε + 2σ (its newer readings' free
#: space ending 2σ earlier) and the carved grid with ``pose_sigma`` σ, σ the condition's
#: position σ (0 under true poses and drift: then the default's row, the same bits).
EVIDENCE_SIGMA = "evidence, ε + 2σ_pose"
CARVED_SIGMA = "carved grid, pose_sigma σ"
#: Issue 9's targets (shares) and the error ratio to centerline's.
KEEP, REMOVE, MEDIAN_RATIO = 85.0, 85.0, 0.4
Row = dict[str, float]


def simulate_condition(world: str, seed: int, physics: str, robot: str,
                       condition: Condition) -> Simulation:
    """The world's tour under ``physics``, stamped as ``condition`` says."""
    overrides = () if physics == "specular" else (("echo_model", physics),)
    return run_simulation(Scenario(world, seed, physics=overrides, robot=robot,  # type: ignore[arg-type]
                                   odometry_drift=condition.odometry_drift,
                                   localisation_noise=condition.localisation_noise))


def _corrected_error(sim: Simulation, xy: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Distance to the nearest wall of each point moved by its reading's pose error."""
    if sim.odometry is not None:
        xy = pose_corrected(xy, t, sim.trajectory, sim.odometry)
    return np.asarray(segment_distance(xy, sim.world.segments)[0])


def point_rows(sim: Simulation, pose_sigma: float | None = None) -> dict[str, Row]:
    """Every method's row on one simulation: evidence.py's measures plus absolute errors,
    raw and with the pose error removed, and the corrected ratios to centerline's; with
    ``pose_sigma`` also :data:`EVIDENCE_SIGMA`'s."""
    config = MethodConfig()
    maps = {name: process_readings(sim.readings, make_method(method, config),
                                   map_filter=map_filter)
            for name, method, map_filter in METHODS}
    if pose_sigma:
        wider = replace(config, range_tolerance=config.range_tolerance
                        + POSE_MARGIN_SIGMAS * pose_sigma)
        maps[EVIDENCE_SIGMA] = process_readings(sim.readings, make_method("evidence", wider))
    elif pose_sigma is not None:
        maps[EVIDENCE_SIGMA] = maps["evidence"]
    center = maps["centerline"].global_map
    center_err = np.full(len(sim.readings), np.nan)
    center_err[center.reading_id] = segment_distance(center.xy, sim.world.segments)[0]
    center_fixed = np.full(len(sim.readings), np.nan)
    center_fixed[center.reading_id] = _corrected_error(sim, center.xy, center.t)
    rows = {}
    for name, result in maps.items():
        gmap = result.global_map
        row = map_row(sim, result, center_err, float(np.nanpercentile(center_err, 90.0)))
        err = segment_distance(gmap.xy, sim.world.segments)[0]
        fixed = _corrected_error(sim, gmap.xy, gmap.t)
        row.update({
            "points": float(len(gmap)),
            "median_m": float(np.median(err)), "p90_m": float(np.percentile(err, 90.0)),
            "median_fixed_m": float(np.median(fixed)),
            "p90_fixed_m": float(np.percentile(fixed, 90.0)),
            "median_ratio_fixed": float(np.median(fixed))
            / float(np.median(center_fixed[gmap.reading_id])),
        })
        rows[name] = row
    return rows


def grid_rows(sim: Simulation, seed: int, pose_sigma: float | None = None) -> dict[str, Row]:
    """Every grid at every resolution: occupied precision, recall, phantoms (true walls); with
    ``pose_sigma`` also :data:`CARVED_SIGMA`'s."""
    grids = list(GRIDS)
    if pose_sigma is not None:
        grids.insert(1, (CARVED_SIGMA, _carved_with_pose_sigma(pose_sigma)))
    direct = sim.truth.kind == EchoKind.DIRECT
    true_path = np.column_stack((sim.firings.x[sim.truth.firing],
                                 sim.firings.y[sim.truth.firing]))
    rows = {}
    for h in RESOLUTIONS:
        for name, make in grids:
            grid = _fill(make, h, sim, seed)
            m = grid_measures(grid, sim.world.segments, sim.truth.reflection[direct],
                              sim.world.bounds, path=true_path)
            rows[f"{name} @ {h:.2f}"] = {"precision": m.precision, "recall": m.recall,
                                          "phantoms": m.phantoms, "freed": m.walls_freed}
    return rows


def _carved_with_pose_sigma(sigma: float) -> Factory:
    def make(h: float, b: tuple[float, float, float, float]) -> OccupancyMap:
        return CarvedGrid(h, b, params=CarvedGridParams(pose_sigma=sigma))
    return make


def run(worlds: Sequence[str], seeds: int, physics: str, robot: str,
        conditions: Sequence[Condition], skip_grids: bool,
        with_sigma: bool = False) -> dict[str, Any]:
    """Every (world, seed, condition): its point rows and (not under drift) grid rows."""
    out: dict[str, Any] = {"physics": physics, "robot": robot, "seeds": seeds, "runs": []}
    for world in worlds:
        for seed in range(seeds):
            for condition in conditions:
                tic = time.perf_counter()
                sim = simulate_condition(world, seed, physics, robot, condition)
                sigma = condition.position_sigma if with_sigma else None
                entry = {"world": world, "seed": seed, "condition": condition.label,
                         "points": point_rows(sim, sigma),
                         "grids": grid_rows(sim, seed, sigma)
                         if condition.for_grids and not skip_grids else {}}
                out["runs"].append(entry)
                print(f"  {physics}, {world}, seed {seed}, {condition.label}: "
                      f"{len(sim.readings):,} readings, {time.perf_counter() - tic:.0f} s",
                      flush=True)
    return out


# ============================================================================ tables


def mean_of(rows: Sequence[Row], key: str) -> float:
    """The mean of ``key`` over ``rows``, NaN values (a world without that kind) left out."""
    values = [r[key] for r in rows if not math.isnan(r[key])]
    return float(np.mean(values)) if values else math.nan


def beats_layer(rows: Sequence[Row], layer: Sequence[Row]) -> str:
    """How many runs' grid beats the layer's of the same run on precision and recall."""
    won = sum(c["precision"] > lay["precision"] and c["recall"] > lay["recall"]
              for c, lay in zip(rows, layer, strict=True))
    return f"{won} of {len(rows)}"


def grid_cells(rows: Sequence[Row]) -> str:
    """A grid's mean precision, recall and phantom share (%) over ``rows``, as table cells."""
    return (f"{mean_of(rows, 'precision'):.3f} | {mean_of(rows, 'recall'):.3f} | "
            f"{100 * mean_of(rows, 'phantoms'):.3f}")


def pct(value: float) -> str:
    """A share with one decimal, "–" where there is none."""
    return "–" if math.isnan(value) else f"{value:.1f}"


def _runs(data: dict[str, Any], world: str, condition: str) -> list[dict[str, Any]]:
    return [r for r in data["runs"] if r["world"] == world and r["condition"] == condition]


def points_table(data: dict[str, Any], world: str, conditions: Sequence[str]) -> None:
    print(f"\npoints: {world}, physics {data['physics']}, {data['robot']}, seeds "
          f"0-{data['seeds'] - 1}; mean over seeds\n")
    print("| method | poses | direct kept (%) | spurious removed (%) | crosstalk / floor / "
          "multipath removed (%) | median error (cm) | pose error removed | p90 (cm) | "
          "pose error removed | median / centerline's | pose error removed | "
          "p90 / centerline's |")
    print("|---|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    methods = list(data["runs"][0]["points"])
    for name in methods:
        for condition in conditions:
            rows = [r["points"][name] for r in _runs(data, world, condition)]
            if not rows:
                continue
            kinds = " / ".join(pct(mean_of(rows, k.label)) for k in KINDS)
            print(f"| {name} | {condition} | {mean_of(rows, 'direct_kept'):.1f} | "
                  f"{mean_of(rows, 'spurious'):.1f} | {kinds} | "
                  f"{100 * mean_of(rows, 'median_m'):.1f} | "
                  f"{100 * mean_of(rows, 'median_fixed_m'):.1f} | "
                  f"{100 * mean_of(rows, 'p90_m'):.1f} | "
                  f"{100 * mean_of(rows, 'p90_fixed_m'):.1f} | "
                  f"{mean_of(rows, 'median_ratio'):.2f} | "
                  f"{mean_of(rows, 'median_ratio_fixed'):.2f} | {mean_of(rows, 'p90_ratio'):.2f} |")


def claims_table(data: dict[str, Any], worlds: Sequence[str], conditions: Sequence[str]) -> None:
    """Evidence carving's targets per world and condition: the mean and the seeds meeting it."""
    print(f"\nevidence carving's claims, physics {data['physics']} (mean over seeds; seeds "
          "meeting the target)\n")
    fixed = EVIDENCE_SIGMA in data["runs"][0]["points"]
    extra = " direct kept, ε + 2σ | spurious removed, ε + 2σ | median, ε + 2σ |" if fixed else ""
    print("| world | poses | direct kept ≥ 85 % | spurious removed ≥ 85 % | the same with the "
          f"occlusion filter | median ≤ 0.4x centerline's |{extra}")
    print("|---|---|---|---|---|---|" + ("---|---|---|" if fixed else ""))
    for world in worlds:
        for condition in conditions:
            runs = _runs(data, world, condition)
            if not runs:
                continue
            plain = [r["points"]["evidence"] for r in runs]
            hidden = [r["points"]["evidence, occluded points dropped"] for r in runs]

            def cell(rows: Sequence[Row], key: str, ok: Callable[[float], bool]) -> str:
                mean = mean_of(rows, key)
                met = sum(ok(r[key]) for r in rows if not math.isnan(r[key]))
                fmt = f"{mean:.2f}" if key == "median_ratio" else f"{mean:.1f}"
                return f"{fmt} ({met}/{len(rows)})"

            line = (f"| {world} | {condition} | "
                    f"{cell(plain, 'direct_kept', lambda v: v >= KEEP)} | "
                    f"{cell(plain, 'spurious', lambda v: v >= REMOVE)} | "
                    f"{cell(hidden, 'spurious', lambda v: v >= REMOVE)} | "
                    f"{cell(plain, 'median_ratio', lambda v: v <= MEDIAN_RATIO)} |")
            if fixed:
                wide = [r["points"][EVIDENCE_SIGMA] for r in runs]
                line += (f" {cell(wide, 'direct_kept', lambda v: v >= KEEP)} | "
                         f"{cell(wide, 'spurious', lambda v: v >= REMOVE)} | "
                         f"{cell(wide, 'median_ratio', lambda v: v <= MEDIAN_RATIO)} |")
            print(line)


def grids_table(data: dict[str, Any], world: str, conditions: Sequence[str]) -> None:
    runs_any = [r for r in data["runs"] if r["world"] == world and r["grids"]]
    if not runs_any:
        return
    print(f"\ngrids: {world}, physics {data['physics']}, {data['robot']}, seeds "
          f"0-{data['seeds'] - 1}; mean over seeds (the carved grid's row: seeds where it beats "
          "the layer on precision and recall)\n")
    print("| resolution (m) | grid | poses | precision | recall | phantoms (%) | "
          "seen walls freed (%) | beats the layer |")
    print("|---:|---|---|---:|---:|---:|---:|---|")
    names = list(dict.fromkeys(key.rsplit(" @ ", 1)[0] for key in runs_any[0]["grids"]))
    for h in RESOLUTIONS:
        for name in names:
            for condition in conditions:
                runs = [r for r in _runs(data, world, condition) if r["grids"]]
                if not runs:
                    continue
                rows = [r["grids"][f"{name} @ {h:.2f}"] for r in runs]
                layer = [r["grids"][f"RangeSensorLayer, ROS defaults @ {h:.2f}"] for r in runs]
                wins = beats_layer(rows, layer) if name.startswith("carved grid") else ""
                print(f"| {h:.2f} | {name} | {condition} | {grid_cells(rows)} | "
                      f"{100 * mean_of(rows, 'freed'):.2f} | {wins} |")


def print_tables(data: dict[str, Any]) -> None:
    worlds = list(dict.fromkeys(r["world"] for r in data["runs"]))
    conditions = list(dict.fromkeys(r["condition"] for r in data["runs"]))
    claims_table(data, worlds, conditions)
    for world in worlds:
        points_table(data, world, conditions)
        grids_table(data, world, conditions)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS))
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--physics", nargs="+", default=["specular", "amplitude"],
                        choices=["specular", "amplitude"])
    parser.add_argument("--robot", default="scout2",
                        help="the sonars: a built-in robot (p3dx-front: the Pioneer's 8 front "
                             "sonars) or a robot YAML")
    parser.add_argument("--conditions", nargs="+", choices=[c.label for c in CONDITIONS],
                        metavar="CONDITION", help="only these (default: all four)")
    parser.add_argument("--quick", action="store_true",
                        help="office, seed 0, specular only (a few minutes)")
    parser.add_argument("--skip-grids", action="store_true")
    parser.add_argument("--pose-sigma", action="store_true",
                        help="add rows: evidence carving with ε + 2σ and the carved grid with "
                             "pose_sigma σ, σ the condition's localisation position σ")
    parser.add_argument("--save", type=Path, help="write the per-run rows as JSON")
    parser.add_argument("--load", type=Path, help="print the tables of a --save file and stop")
    args = parser.parse_args(argv)
    if args.load:
        for data in json.loads(args.load.read_text()):
            print_tables(data)
        return 0
    if args.quick:
        args.worlds, args.seeds, args.physics = ["office"], 1, ["specular"]
    conditions = [c for c in CONDITIONS if not args.conditions or c.label in args.conditions]
    everything = []
    for physics in args.physics:
        data = run(args.worlds, args.seeds, physics, args.robot, conditions, args.skip_grids,
                   args.pose_sigma)
        print_tables(data)
        everything.append(data)
    if args.save:
        args.save.write_text(json.dumps(everything))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
