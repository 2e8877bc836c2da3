"""Maps from sonars unlike the default simulated one: range quantum, beam width, range noise.

Run from the repository root (on a shared machine, the two physics side by side with ``nice``)::

    nice .venv/bin/python benchmarks/sonar_conditions.py --physics specular --save /tmp/cond-s.json
    nice .venv/bin/python benchmarks/sonar_conditions.py --physics amplitude --save /tmp/cond-a.json
    nice .venv/bin/python benchmarks/sonar_conditions.py --quick    # office, seed 0, specular

Every other accuracy number of sonarcarve comes from one sonar: the Scout2 ring's Polaroid
transducers, a 22.5° beam, ranges rounded to one inch, range noise σ 1 cm. Here the same tours
are simulated with one of those changed at a time:

- ``defaults``: that sonar (the rows of ``benchmarks/evidence.py`` and ``pose_error.py``);
- ``quantum 1 mm``: ranges rounded to 1 mm (a modern time-of-flight module) instead of 25.4 mm:
  the robot's ``range_resolution`` (what ``SonarPhysics.quantise`` rounds to) and the methods'
  ``range_resolution`` both 1 mm;
- ``beam 15°`` and ``beam 45°``: every sensor's beam width (``Scenario.beam_width_deg``; the
  readings carry it, and ``MethodConfig.beam_width`` is set to it as a user would with
  ``--beam-width``). The amplitude physics hears through a piston's beam pattern, not the
  robot's nominal width, so there the transducer is resized too (:func:`piston_for_beam`: its
  main lobe's nulls scale with the beam, and its diffuse fan with them);
- ``beam 45°, told 75°``: the 45° sonar, every method told a 75° beam (the readings' beam width
  and ``MethodConfig.beam_width``): under the amplitude physics the small piston's first side
  lobes, about 35° off the axis, hear echoes outside the nominal 45°, and a user who knows the
  pattern would give the width the sensor really hears in; under the specular physics, which has
  no side lobes, the same overstates the beam (what that costs);
- ``noise σ 3 cm`` and ``noise σ 5 cm``: ``SonarPhysics.range_noise`` (still rounded to the inch).

Per method (centerline, paper carving, combined, evidence carving, and evidence with the
occlusion map filter as ``benchmarks/evidence.py`` uses it), on each world's tour, seed and
physics: direct echoes kept and spurious removed (per kind), and the median and p90 ratios to
centerline's error on the same readings (:func:`evidence.map_row`), and the direct echoes split
by where their reflector lies against the beam the methods were told
(:func:`~sonarcarve.lab.metrics.off_beam`: the share from outside it, in-beam kept, off-beam
removed; a wide amplitude beam hears walls through its side lobes). Under the noise conditions
two more rows: the remedy a user would apply, evidence carving with ε = max(default ε, 2σ)
(:func:`remedy_tolerance`, ``process --range-tolerance``; the support tolerance ε_s stays
:class:`~sonarcarve.methods.evidence.SensorModel`'s 5 cm), and the same with ε_s = ε as well
(``SensorModel(support_tolerance=ε)``: the comparison that keeps ε_s fixed).

``--grids`` adds, under the defaults and the noise conditions, the carved grid (and, under
noise, with ``CarvedGridParams(pose_sigma=σ)``, ``sonarcarve grid --pose-sigma σ``: the one
knob of the grid command that moves a reading's free space short of its echo, by 2σ, and
widens its method's ε by 2σ) against the faithful RangeSensorLayer with ROS's defaults at
0.10 m: occupied precision and recall against the true walls (``benchmarks/grids.py``'s
measure).

Worlds: the office, t-junction and doorway tours and the held-out generated floor ``random:1``,
the Scout2 ring; the ``defaults`` rows equal ``pose_error.py``'s true-pose rows. ``--save FILE``
writes every per-run row as JSON (``--load FILE`` prints the tables again). A full run (4 worlds,
3 seeds, 6 sonars, ``--grids``, one physics) takes 5-8 minutes on this machine with the two
physics side by side.

A ratio to centerline's median moves with centerline too: a narrower beam places centerline's
points nearer the walls (office/specular, seed 0: 9.1 cm at 22.5°, 5.1 cm at 15°) while evidence
carving's stay where they were (2.4 cm), so its ratio rises though its error does not.
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from scipy.special import jn_zeros

from evidence import KINDS, map_row
from grids import _carved, _fill, _layer, _measure
from pose_error import KEEP, MEDIAN_RATIO, METHODS, REMOVE, beats_layer, grid_cells, mean_of, pct
from sonarcarve import MethodConfig, make_method
from sonarcarve.constants import DEFAULT_BEAM_WIDTH
from sonarcarve.grids import CarvedGrid, CarvedGridParams, OccupancyMap, RangeSensorLayerParams
from sonarcarve.lab.metrics import segment_distance
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods.config import DEFAULT_RANGE_TOLERANCE
from sonarcarve.methods.evidence import EvidenceMethod, SensorModel
from sonarcarve.pipeline import ProcessResult, process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.amplitude import AmplitudeModel
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import SonarPhysics

WORLDS = ("office", "t-junction", "doorway", "random:1")
#: How many σ of range noise the remedy's ε covers (two: 95 % of a Gaussian's draws).
NOISE_SIGMAS = 2.0
GRID_RESOLUTION = 0.10
#: First zero of J1: the circular piston's first null lies at sin α = J1_ZERO / (k a).
J1_ZERO = float(jn_zeros(1, 1)[0])


@dataclass(frozen=True)
class Condition:
    """One way the sonar differs from the default: beam width (degrees), range noise σ
    (metres), range quantum (metres); None keeps the default. ``told_deg``: the beam width the
    methods are told, when not ``beam_deg`` (None: the simulated one)."""

    label: str
    beam_deg: float | None = None
    range_noise: float | None = None
    quantum: float | None = None
    told_deg: float | None = None

    @property
    def remedy(self) -> float | None:
        """The remedy's ε under range noise (None without a noise override)."""
        return None if self.range_noise is None else remedy_tolerance(self.range_noise)


CONDITIONS = (
    Condition("defaults"),
    Condition("quantum 1 mm", quantum=0.001),
    Condition("beam 15°", beam_deg=15.0),
    Condition("beam 45°", beam_deg=45.0),
    Condition("beam 45°, told 75°", beam_deg=45.0, told_deg=75.0),
    Condition("noise σ 3 cm", range_noise=0.03),
    Condition("noise σ 5 cm", range_noise=0.05),
)
REMEDY = "evidence, ε = max(5 cm, 2σ)"
REMEDY_WIDE = "evidence, ε = max(5 cm, 2σ), ε_s = ε"
Row = dict[str, float]


def remedy_tolerance(range_noise: float) -> float:
    """ε = max(default ε, 2σ): a newer reading's free space stops short of an echo that noise
    moved nearer by up to 2σ.

    >>> remedy_tolerance(0.01), remedy_tolerance(0.05)
    (0.05, 0.1)
    """
    return max(DEFAULT_RANGE_TOLERANCE, NOISE_SIGMAS * range_noise)


def piston_for_beam(beam_deg: float, model: AmplitudeModel | None = None,
                    sound_speed: float = SonarPhysics().sound_speed) -> AmplitudeModel:
    """The amplitude model with its transducer resized for a ``beam_deg`` beam: the main lobe's
    first null at the default's null angle times ``beam_deg / 22.5°`` (a smaller piston, a wider
    beam), the diffuse fan widened by the same factor (at most 90°, rays about 1° apart) so it
    still covers the first side lobes."""
    model = AmplitudeModel() if model is None else model
    null = math.asin(J1_ZERO / model.ka(sound_speed))
    scale = math.radians(beam_deg) / DEFAULT_BEAM_WIDTH
    wanted = min(null * scale, 0.5 * math.pi)
    fan = min(model.fan_half_angle * scale, 0.5 * math.pi)
    return replace(model, transducer_radius=model.transducer_radius * math.sin(null)
                   / math.sin(wanted), fan_half_angle=fan,
                   fan_rays=2 * round(math.degrees(fan)) + 1)


def robot_with_quantum(quantum: float, folder: Path, robot: str = "scout2") -> str:
    """A copy of a built-in robot's YAML in ``folder`` with range_resolution ``quantum``
    metres; returns its path (a :attr:`Scenario.robot`)."""
    text = resources.files("sonarcarve").joinpath("robots", f"{robot}.yaml").read_text("utf-8")
    lines = [f"range_resolution: {quantum}" if line.startswith("range_resolution:") else line
             for line in text.splitlines()]
    path = folder / f"{robot}-quantum-{quantum:g}.yaml"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(path)


def scenario(world: str, seed: int, physics: str, condition: Condition, folder: Path) -> Scenario:
    """The world's tour under ``physics`` with ``condition``'s sonar."""
    overrides: list[tuple[str, Any]] = [] if physics == "specular" else [("echo_model", physics)]
    if condition.range_noise is not None:
        overrides.append(("range_noise", condition.range_noise))
    if condition.beam_deg is not None and physics == "amplitude":
        overrides.append(("amplitude", piston_for_beam(condition.beam_deg)))
    robot = "scout2" if condition.quantum is None else robot_with_quantum(condition.quantum,
                                                                          folder)
    return Scenario(world, seed, physics=tuple(overrides), robot=robot,
                    beam_width_deg=condition.beam_deg)


def method_config(condition: Condition) -> MethodConfig:
    """What a user would tell the methods about this sonar: its beam width and range quantum
    (the range tolerance stays the default: the remedy rows widen it)."""
    config = MethodConfig()
    told = condition.beam_deg if condition.told_deg is None else condition.told_deg
    if told is not None:
        config = replace(config, beam_width=math.radians(told))
    if condition.quantum is not None:
        config = replace(config, range_resolution=condition.quantum)
    return config


def _evidence(config: MethodConfig, support: float) -> EvidenceMethod:
    """Evidence carving as ``make_method`` builds it, its support tolerance ``support``."""
    c = config
    return EvidenceMethod(c.history_size, c.beam_width, c.range_tolerance, c.min_transversal,
                          c.range_resolution, c.evidence_bins, c.carve_probability,
                          c.min_confidence, c.stamp_error, c.stamp_heading_error,
                          sensor=SensorModel(support_tolerance=support))


def told_readings(readings: ReadingBatch, condition: Condition) -> ReadingBatch:
    """The readings as the methods get them: their beam width ``told_deg`` where set."""
    if condition.told_deg is None:
        return readings
    return replace(readings, beam_width=np.full(len(readings), math.radians(condition.told_deg)))


def point_rows(sim: Simulation, condition: Condition) -> dict[str, Row]:
    """Every method's :func:`evidence.map_row` on one simulation (and the remedy's rows)."""
    config = method_config(condition)
    readings = told_readings(sim.readings, condition)
    maps: dict[str, ProcessResult] = {
        name: process_readings(readings, make_method(method, config), map_filter=map_filter)
        for name, method, map_filter in METHODS}
    if condition.remedy is not None:
        wider = replace(config, range_tolerance=condition.remedy)
        maps[REMEDY] = process_readings(readings, make_method("evidence", wider))
        maps[REMEDY_WIDE] = process_readings(readings, _evidence(wider, condition.remedy))
    center = maps["centerline"].global_map
    center_err = np.full(len(sim.readings), np.nan)
    center_err[center.reading_id] = segment_distance(center.xy, sim.world.segments)[0]
    center_p90 = float(np.nanpercentile(center_err, 90.0))
    return {name: map_row(sim, result, center_err, center_p90, told=readings)
            for name, result in maps.items()}


def grid_rows(sim: Simulation, seed: int, condition: Condition) -> dict[str, Row]:
    """The carved grid (under noise also with ``pose_sigma`` σ, and with the remedy's ε, ``grid
    --range-tolerance``) and the RangeSensorLayer at 0.10 m."""
    grids: list[tuple[str, Callable[[float, Any], OccupancyMap]]] = [
        ("carved grid", _carved),
        ("RangeSensorLayer, ROS defaults", _layer(RangeSensorLayerParams()))]
    if condition.range_noise is not None and condition.remedy is not None:
        sigma = CarvedGridParams(pose_sigma=condition.range_noise)
        wider = CarvedGridParams(range_tolerance=condition.remedy)
        grids[1:1] = [("carved grid, pose_sigma σ", lambda h, b: CarvedGrid(h, b, params=sigma)),
                      ("carved grid, ε = max(5 cm, 2σ)",
                       lambda h, b: CarvedGrid(h, b, params=wider))]
    rows = {}
    for name, make in grids:
        m = _measure(_fill(make, GRID_RESOLUTION, sim, seed), sim)
        rows[name] = {"precision": m.precision, "recall": m.recall, "phantoms": m.phantoms}
    return rows


def run(worlds: Sequence[str], seeds: int, physics: str, conditions: Sequence[Condition],
        with_grids: bool) -> dict[str, Any]:
    """Every (world, seed, condition): its point rows and (``with_grids``) grid rows."""
    out: dict[str, Any] = {"physics": physics, "seeds": seeds, "runs": []}
    with tempfile.TemporaryDirectory(prefix="sonar-conditions-") as folder:
        for world in worlds:
            for seed in range(seeds):
                for condition in conditions:
                    tic = time.perf_counter()
                    sim = run_simulation(scenario(world, seed, physics, condition, Path(folder)))
                    grids = with_grids and (condition.remedy is not None
                                            or condition.label == "defaults")
                    out["runs"].append({
                        "world": world, "seed": seed, "condition": condition.label,
                        "points": point_rows(sim, condition),
                        "grids": grid_rows(sim, seed, condition) if grids else {}})
                    print(f"  {physics}, {world}, seed {seed}, {condition.label}: "
                          f"{len(sim.readings):,} readings, {time.perf_counter() - tic:.0f} s",
                          flush=True)
    return out


# ============================================================================ tables


def _runs(data: dict[str, Any], condition: str, world: str | None = None) -> list[Any]:
    return [r for r in data["runs"] if r["condition"] == condition
            and (world is None or r["world"] == world)]


def _cell(rows: Sequence[Row], key: str, ok: Callable[[float], bool]) -> str:
    """The mean over runs and how many runs meet the target."""
    values = [r[key] for r in rows if not math.isnan(r[key])]
    fmt = f"{mean_of(rows, key):.2f}" if key.endswith("ratio") else f"{mean_of(rows, key):.1f}"
    return f"{fmt} ({sum(ok(v) for v in values)}/{len(values)})"


def summary_table(data: dict[str, Any], conditions: Sequence[str]) -> None:
    """Per condition and method, the mean over every world and seed."""
    worlds = list(dict.fromkeys(r["world"] for r in data["runs"]))
    print(f"\nall worlds ({', '.join(worlds)}), physics {data['physics']}, seeds "
          f"0-{data['seeds'] - 1}: mean over runs (runs meeting issue 9's target)\n")
    print("| sonar | method | direct kept (%) | spurious removed (%) | crosstalk / floor / "
          "multipath removed (%) | median / centerline's | p90 / centerline's |")
    print("|---|---|---:|---:|---|---:|---:|")
    for condition in conditions:
        runs = _runs(data, condition)
        for name in runs[0]["points"]:
            rows = [r["points"][name] for r in runs]
            kinds = " / ".join(pct(mean_of(rows, k.label)) for k in KINDS)
            evidence = name.startswith("evidence")
            kept = (_cell(rows, "direct_kept", lambda v: v >= KEEP) if evidence
                    else f"{mean_of(rows, 'direct_kept'):.1f}")
            removed = (_cell(rows, "spurious", lambda v: v >= REMOVE) if evidence
                       else f"{mean_of(rows, 'spurious'):.1f}")
            median = (_cell(rows, "median_ratio", lambda v: v <= MEDIAN_RATIO) if evidence
                      else f"{mean_of(rows, 'median_ratio'):.2f}")
            p90 = (_cell(rows, "p90_ratio", lambda v: v <= 0.5) if evidence
                   else f"{mean_of(rows, 'p90_ratio'):.2f}")
            print(f"| {condition} | {name} | {kept} | {removed} | {kinds} | {median} | {p90} |")


def claims_table(data: dict[str, Any], conditions: Sequence[str]) -> None:
    """Evidence carving's targets per world and condition (mean over seeds; seeds meeting)."""
    worlds = list(dict.fromkeys(r["world"] for r in data["runs"]))
    print(f"\nevidence carving per world, physics {data['physics']} (mean over seeds; seeds "
          "meeting the target)\n")
    print("| world | sonar | direct kept ≥ 85 % | spurious removed ≥ 85 % | crosstalk / floor / "
          "multipath removed (%) | median ≤ 0.4x | p90 ≤ 0.5x | remedy ε = max(5 cm, 2σ): "
          "kept / removed / median | the same with ε_s = ε |")
    print("|---|---|---|---|---|---|---|---|---|")
    for world in worlds:
        for condition in conditions:
            runs = _runs(data, condition, world)
            if not runs:
                continue
            plain = [r["points"]["evidence"] for r in runs]
            kinds = " / ".join(pct(mean_of(plain, k.label)) for k in KINDS)
            line = (f"| {world} | {condition} | {_cell(plain, 'direct_kept', lambda v: v >= KEEP)}"
                    f" | {_cell(plain, 'spurious', lambda v: v >= REMOVE)} | {kinds} | "
                    f"{_cell(plain, 'median_ratio', lambda v: v <= MEDIAN_RATIO)} | "
                    f"{_cell(plain, 'p90_ratio', lambda v: v <= 0.5)} |")
            for remedy in (REMEDY, REMEDY_WIDE):
                if remedy not in runs[0]["points"]:
                    line += " |"
                    continue
                wide = [r["points"][remedy] for r in runs]
                line += (f" {_cell(wide, 'direct_kept', lambda v: v >= KEEP)} / "
                         f"{_cell(wide, 'spurious', lambda v: v >= REMOVE)} / "
                         f"{_cell(wide, 'median_ratio', lambda v: v <= MEDIAN_RATIO)} |")
            print(line)


def beam_table(data: dict[str, Any], conditions: Sequence[str]) -> None:
    """Direct echoes by where their reflector lies against the beam the methods were told
    (:func:`~sonarcarve.lab.metrics.off_beam`): the share from outside it, and per method the
    in-beam ones kept and the off-beam ones removed (mean over runs)."""
    if "off_beam" not in data["runs"][0]["points"]["evidence"]:
        return  # a --save file from before the split
    print(f"\ndirect echoes inside and outside the told beam, physics {data['physics']} (mean "
          "over runs): off-beam share; in-beam kept (runs ≥ 85 %) / off-beam removed, %\n")
    names = list(data["runs"][0]["points"])
    print("| sonar | direct echoes off the told beam (%) | "
          + " | ".join(names) + " |")
    print("|---|---:|" + "---|" * len(names))
    for condition in conditions:
        runs = _runs(data, condition)
        cells = []
        for name in names:
            rows = [r["points"][name] for r in runs]
            cells.append(f"{_cell(rows, 'in_beam_kept', lambda v: v >= KEEP)} / "
                         f"{pct(mean_of(rows, 'off_beam_removed'))}")
        share = mean_of([r["points"]["evidence"] for r in runs], "off_beam")
        print(f"| {condition} | {share:.1f} | " + " | ".join(cells) + " |")


def grids_table(data: dict[str, Any], conditions: Sequence[str]) -> None:
    runs_any = [r for r in data["runs"] if r["grids"]]
    if not runs_any:
        return
    print(f"\ngrids at {GRID_RESOLUTION:.2f} m, physics {data['physics']}: mean over worlds and "
          "seeds (the carved rows: runs beating the layer on precision and recall)\n")
    print("| sonar | grid | precision | recall | phantoms (%) | beats the layer |")
    print("|---|---|---:|---:|---:|---|")
    for condition in conditions:
        runs = [r for r in _runs(data, condition) if r["grids"]]
        if not runs:
            continue
        for name in runs[0]["grids"]:
            rows = [r["grids"][name] for r in runs]
            layer = [r["grids"]["RangeSensorLayer, ROS defaults"] for r in runs]
            wins = beats_layer(rows, layer) if name.startswith("carved") else ""
            print(f"| {condition} | {name} | {grid_cells(rows)} | {wins} |")


def print_tables(data: dict[str, Any]) -> None:
    conditions = list(dict.fromkeys(r["condition"] for r in data["runs"]))
    summary_table(data, conditions)
    claims_table(data, conditions)
    beam_table(data, conditions)
    grids_table(data, conditions)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=list(WORLDS))
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--physics", nargs="+", default=["specular", "amplitude"],
                        choices=["specular", "amplitude"])
    parser.add_argument("--conditions", nargs="+", choices=[c.label for c in CONDITIONS],
                        metavar="CONDITION", help="only these (default: all six)")
    parser.add_argument("--quick", action="store_true",
                        help="office, seed 0, specular only (a few minutes)")
    parser.add_argument("--grids", action="store_true",
                        help="add the grids under the defaults and the noise conditions")
    parser.add_argument("--save", type=Path, help="write the per-run rows as JSON")
    parser.add_argument("--load", type=Path, nargs="+",
                        help="print the tables of --save files and stop")
    args = parser.parse_args(argv)
    if args.load:
        for path in args.load:
            for data in json.loads(path.read_text()):
                print_tables(data)
        return 0
    if args.quick:
        args.worlds, args.seeds, args.physics = ["office"], 1, ["specular"]
    conditions = [c for c in CONDITIONS if not args.conditions or c.label in args.conditions]
    everything = []
    for physics in args.physics:
        data = run(args.worlds, args.seeds, physics, conditions, args.grids)
        print_tables(data)
        everything.append(data)
        if args.save:  # after each physics: a long run keeps what it has
            args.save.write_text(json.dumps(everything))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
