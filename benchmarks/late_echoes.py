"""The late-echo (ghost) map filter: what it removes from evidence carving's default map.

Also what the simulator's late echoes are (:mod:`sonarcarve.filters.late_echoes`).

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/late_echoes.py                    # every group below
    nice .venv/bin/python benchmarks/late_echoes.py --groups car-park one-sonar
    nice .venv/bin/python benchmarks/late_echoes.py --trace one-sonar  # the paths, per run
    nice .venv/bin/python benchmarks/late_echoes.py --timing           # cost against process
    nice .venv/bin/python benchmarks/late_echoes.py --both --floor-seeds 3  # with driven-through
    nice .venv/bin/python benchmarks/late_echoes.py --both --physics "amplitude, brick"  # brick

Both simulator models make their crosstalk as late echoes: the specular model's
(``sim.sonar.spurious._crosstalk``) is an earlier firing's echo point heard diffusely, the
amplitude model's (``amplitude_paths._crosstalk_amplitude``) a mirror path off a wall, for lags
1..``crosstalk_lookback`` (2). So every crosstalk reading is a *ghost* here.

For each group of runs (below), evidence carving's global map with its defaults is made once,
then the mask is applied to it in the same run, with the exact schedule (the simulator's
firings: every firing's time and sensor origin), with the robot's ``firing_period`` alone (the
emitter taken at the receiver), and with the distinct reading times for the firings
(``FiringSchedule.from_readings``: the simulator's logs hold no no-echo readings, so this one
misses firings). Per group, means
over runs: direct echoes kept, ghosts (crosstalk), floor and multipath echoes removed (%), median
and p90 true error of the map's points (m), and the direct echoes' points the mask dropped
(count and %: its losses).

One table per group and physics. Groups: ``one-sonar`` and ``two-sonars``
(``benchmarks/robots/scout2-front-1.yaml`` and ``scout2-front-back.yaml``), ``scout2-ring``
and ``pioneer-ring`` (``scout2``, ``p3dx``) on the held-out floors of ``heldout.py`` (seed 0,
amplitude and specular); ``car-park`` (``parking.py``'s car, seeds 0-2, its three physics);
``development`` (office, t-junction, doorway on the Scout2 ring, seeds 0-2, specular and
amplitude). ``--physics NAME ...`` runs every group under the named physics instead of its own:
heldout.py's four (``specular``, ``amplitude``, ``specular, rough``, ``amplitude, brick``), the
car park's ``amplitude, car transducer``, and the simulator's ``amplitude-thin``.

``--trace GROUP`` re-solves each ghost's path (for the amplitude model: the mirror path from
firing ``j``'s sensor via each wall to firing ``k``'s, lags 1-2, as helper late13's one-off
script did), and prints per run: ghosts matched, the share of lag 1 and of the sensor's own
ping, the one-way path P/2 and the reading, and late13's probe (the point at ``r + c Δt / 2`` on
the axis, Δt the lag-1 gap, within 0.1 m of any point of the final map) for ghosts and direct
echoes.

``--both``: the two ghost filters together, as ``process --late-echo-period ROBOT
--driven-through ROBOT`` runs them (:func:`~sonarcarve.filters.filter_map` with
``MapFilter(late_echo_period=firing_period, driven_through=BodyFootprint.of_robot(...))`` of
the group's robot file): evidence carving's default map through neither, each and both, in the
same run. Per group and physics: direct echoes kept, ghosts, floor and multipath echoes removed
(%, mean over runs), median / p90 true error (m), the direct points dropped (count, %, their
median true error pooled over runs: a misplaced point dropped is no loss), the overlap of the
two masks on the ghost and direct points of the map (caught by one only, by each), and for the
car park the parking question of :mod:`parking` read from each map. Each run checks that
"both" drops exactly the union of the two masks, and the first run of each group that
:func:`~sonarcarve.pipeline.process_readings` with both filters gives the same map.
``--floor-seeds`` and ``--dev-seeds`` set the seeds of the held-out floors (default 1) and
of the development worlds (default 3).
"""

from __future__ import annotations

import argparse
import math
import time
from collections.abc import Callable, Iterator
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

import heldout
import parking
from sonarcarve import MethodConfig, make_method
from sonarcarve.filters import BodyFootprint, MapFilter, driven_through_mask, filter_map
from sonarcarve.filters import late_echoes as late_echoes_module
from sonarcarve.filters.late_echoes import SOUND_SPEED, FiringSchedule, late_echo_mask
from sonarcarve.lab.metrics import segment_distance
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import GlobalMap
from sonarcarve.pipeline import process_readings
from sonarcarve.robot import load_robot
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import EchoKind, SonarPhysics, named_physics

ONE_SONAR = "benchmarks/robots/scout2-front-1.yaml"
TWO_SONARS = "benchmarks/robots/scout2-front-back.yaml"
FLOORS = heldout.WORLDS
DEVELOPMENT = ("office", "t-junction", "doorway")
#: The development group's seeds 0..n-1 (``--dev-seeds``) and the floors' (``--floor-seeds``).
SEEDS = [3, 1]
SHIPPED = ("amplitude", "specular")
#: Every physics ``--physics`` may name: heldout.py's four, the car park's car transducer and the
#: simulator's ``amplitude-thin`` (small reflectors on the amplitude model).
ALL_PHYSICS: dict[str, SonarPhysics] = {
    **heldout.PHYSICS, **parking.CAR_PHYSICS,
    "amplitude-thin": named_physics("amplitude-thin", heldout.PHYSICS["amplitude"])}
#: ``--physics``: the physics every group runs under instead of its own (empty: its own).
CHOSEN: list[str] = []


class Setting(NamedTuple):
    """One simulation: a label and how to make it."""

    label: str
    period: float  # the robot's firing period, s
    make: Callable[[], Simulation]
    robot: str  # the robot file or name (``--both``: its body)


def _floor_settings(robot: str) -> Iterator[Setting]:
    period = load_robot(robot).firing_period
    for name in CHOSEN or SHIPPED:
        for world in FLOORS:
            for seed in range(SEEDS[1]):
                label = world if seed == 0 else f"{world} seed {seed}"
                yield Setting(f"{label}, {name}", period,
                              lambda w=world, s=seed, p=name: heldout._simulate(
                                  w, s, ALL_PHYSICS[p], robot), robot)


def _car_settings() -> Iterator[Setting]:
    period = load_robot(parking.ROBOT).firing_period
    for name in CHOSEN or parking.CAR_PHYSICS:
        for seed in range(3):
            yield Setting(f"seed {seed}, {name}", period,
                          lambda s=seed, p=ALL_PHYSICS[name]: parking._simulate(s, p),
                          parking.ROBOT)


def _development_settings() -> Iterator[Setting]:
    period = load_robot("scout2").firing_period
    for name in CHOSEN or SHIPPED:
        for world in DEVELOPMENT:
            for seed in range(SEEDS[0]):
                yield Setting(f"{world} {seed}, {name}", period,
                              lambda w=world, s=seed, p=name: heldout._simulate(
                                  w, s, ALL_PHYSICS[p]), "scout2")


GROUPS: dict[str, Callable[[], Iterator[Setting]]] = {
    "one-sonar": lambda: _floor_settings(ONE_SONAR),
    "two-sonars": lambda: _floor_settings(TWO_SONARS),
    "scout2-ring": lambda: _floor_settings("scout2"),
    "pioneer-ring": lambda: _floor_settings("p3dx"),
    "car-park": _car_settings,
    "development": _development_settings,
}


def schedule(sim: Simulation) -> FiringSchedule:
    """Every firing of the simulation, with its sensor's origin."""
    f = sim.firings
    return FiringSchedule(np.asarray(f.t, float), np.asarray(f.x, float), np.asarray(f.y, float))


def evidence_map(sim: Simulation) -> GlobalMap:
    """Evidence carving's global map with the defaults."""
    return process_readings(sim.readings, make_method("evidence", MethodConfig())).global_map


#: ``late_echo_mask``'s keywords besides the schedule (``--half-width``, ``--surface-error``).
OPTIONS: dict[str, float] = {}


def _late(points: GlobalMap, sim: Simulation, period: float | None,
          from_readings: bool = False) -> npt.NDArray[np.bool_]:
    """The mask with the simulator's firings, the ``period`` alone, or (``from_readings``) the
    distinct reading times of a log without no-echo readings for the firings."""
    options: dict[str, object] = dict(OPTIONS)
    if period is not None:
        options["firing_period"] = period
    else:
        options["firings"] = (FiringSchedule.from_readings(sim.readings) if from_readings
                              else schedule(sim))
    return late_echo_mask(points.xy, points.reading_id, points.max_error, sim.readings,
                          sound_speed=sim.physics.sound_speed, **options)  # type: ignore[arg-type]


def measures(sim: Simulation, points: GlobalMap) -> dict[str, float]:
    """Direct kept, each spurious kind removed (%), median and p90 true error (m)."""
    kind = sim.truth.kind
    kept = np.zeros(len(kind), dtype=bool)
    kept[points.reading_id] = True
    err = segment_distance(points.xy, sim.world.segments)[0]
    out = {"direct": 100 * float(np.mean(kept[kind == EchoKind.DIRECT])),
           "median": float(np.median(err)), "p90": float(np.percentile(err, 90.0))}
    for name, code in (("ghosts", EchoKind.CROSSTALK), ("floor", EchoKind.FLOOR),
                       ("multipath", EchoKind.MULTIPATH)):
        sel = kind == code
        out[name] = 100 * float(np.mean(~kept[sel])) if sel.any() else math.nan
        out[f"{name} n"] = float(sel.sum())
    return out


def run(setting: Setting) -> dict[str, dict[str, float]]:
    """The map without and with the mask (each schedule) of one setting."""
    sim = setting.make()
    points = evidence_map(sim)
    direct_points = sim.truth.kind[points.reading_id] == EchoKind.DIRECT
    rows = {"without": measures(sim, points)}
    for name, period, from_readings in (("exact", None, False), ("period", setting.period, False),
                                        ("readings", None, True)):
        late = _late(points, sim, period, from_readings)
        rows[name] = measures(sim, points.select(~late))
        rows[name]["lost"] = float(np.sum(late & direct_points))
        rows[name]["lost %"] = 100 * float(np.mean(late[direct_points]))
    return rows


def _table(group: str, runs: list[tuple[str, dict[str, dict[str, float]]]]) -> None:
    print(f"\n{group}: {len(runs)} runs; ghosts per run "
          f"{np.mean([r['without']['ghosts n'] for _, r in runs]):.0f} (mean)\n")
    print("| map | direct kept (%) | ghosts removed (%) | floor removed (%) | multipath removed "
          "(%) | median error (m) | p90 error (m) | direct points dropped (n, %) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for name, label in (("without", "evidence, default"), ("exact", "+ mask, every firing"),
                        ("period", "+ mask, firing period"),
                        ("readings", "+ mask, reading times")):
        def mean(key: str, name: str = name) -> float:
            values = np.array([r[name][key] for _, r in runs])
            return float(np.mean(values[np.isfinite(values)])) if np.isfinite(values).any() \
                else math.nan
        lost = (f"{sum(r[name]['lost'] for _, r in runs):.0f}, {mean('lost %'):.2f}"
                if name != "without" else "–")
        print(f"| {label} | {mean('direct'):.1f} | {mean('ghosts'):.1f} | {mean('floor'):.1f} | "
              f"{mean('multipath'):.1f} | {mean('median'):.3f} | {mean('p90'):.3f} | {lost} |")
    print("\nper run, ghosts removed without / every firing / period (%), direct points dropped "
          "(n, exact / period):")
    for label, r in runs:
        print(f"  {label}: {r['without']['ghosts']:.1f} / {r['exact']['ghosts']:.1f} / "
              f"{r['period']['ghosts']:.1f} of {r['without']['ghosts n']:.0f}; "
              f"{r['exact']['lost']:.0f} / {r['period']['lost']:.0f}")


# -- the paths (late13's trace, kept) ------------------------------------------------------------

def mirror_ranges(sim: Simulation, j: int, k: int) -> tuple[npt.NDArray[np.float64], ...]:
    """Firing ``j``'s ping heard by firing ``k`` by a mirror reflection off each wall: the
    apparent range (NaN: no such path) and the one-way path P/2, shape (walls,)."""
    f, seg = sim.firings, sim.world.segments
    a, edge = seg[:, :2], seg[:, 2:] - seg[:, :2]
    normal = np.column_stack((-edge[:, 1], edge[:, 0])) / np.hypot(*edge.T)[:, None]
    emitter, receiver = np.array([f.x[j], f.y[j]]), np.array([f.x[k], f.y[k]])
    side_e = np.einsum("wj,wj->w", emitter - a, normal)
    side_r = np.einsum("wj,wj->w", receiver - a, normal)
    image = emitter - 2 * side_e[:, None] * normal
    line = receiver - image
    across = np.einsum("wj,wj->w", line, normal)
    step = -np.einsum("wj,wj->w", image - a, normal) / np.where(np.abs(across) > 1e-12, across,
                                                                 np.inf)
    hit = image + step[:, None] * line
    along = np.einsum("wj,wj->w", hit - a, edge) / np.sum(edge * edge, axis=1)
    half = np.hypot(line[:, 0], line[:, 1]) / 2
    ok = (side_e * side_r > 0) & (along >= 0) & (along <= 1)
    apparent = half - sim.physics.sound_speed * (f.t[k] - f.t[j]) / 2
    return np.where(ok, apparent, np.nan), np.where(ok, half, np.nan)


def trace(sim: Simulation, points: GlobalMap, label: str) -> None:
    """Print the ghosts' paths and late13's probe for one run (module docstring)."""
    kind, firing = sim.truth.kind, sim.truth.firing
    ghosts = np.flatnonzero(kind == EchoKind.CROSSTALK)
    found = []  # (lag, own sensor, P/2, reading, error)
    for i in ghosts:
        k, best = int(firing[i]), (np.inf, 0, 0.0)
        for lag in (1, 2):
            if k - lag < 0:
                continue
            apparent, half = mirror_ranges(sim, k - lag, k)
            miss = np.abs(apparent - sim.truth.true_range[i])
            if np.isfinite(miss).any() and np.nanmin(miss) < best[0]:
                w = int(np.nanargmin(miss))
                best = (float(miss[w]), lag, float(half[w]))
        if best[0] < 0.01:
            own = sim.firings.sensor[k - best[1]] == sim.firings.sensor[k]
            found.append((best[1], own, best[2], sim.readings.range[i], best[0]))
    m = np.array(found, dtype=float).reshape(-1, 5)
    share = 100 * len(m) / max(len(ghosts), 1)
    print(f"  {label}: {len(ghosts)} ghosts of {len(kind)} readings; a mirror path matched "
          f"{len(m)} ({share:.0f} %)", end="")
    if len(m):
        print(f", lag 1 {100 * np.mean(m[:, 0] == 1):.0f} %, own ping {100 * np.mean(m[:, 1]):.0f}"
              f" %, P/2 median {np.median(m[:, 2]):.2f} m, read median {np.median(m[:, 3]):.2f} m",
              end="")
    direct = kind == EchoKind.DIRECT
    probe = late13_probe(sim, points)
    print(f"; late13's probe flags ghosts {100 * np.mean(probe[ghosts]):.1f} %, direct "
          f"{100 * np.mean(probe[direct]):.1f} %")


def late13_probe(sim: Simulation, points: GlobalMap) -> npt.NDArray[np.bool_]:
    """Per reading: the point at ``r + c Δt / 2`` on its axis (Δt: the gap since the previous
    firing) lies within 0.1 m of the axis point (``r`` along the axis) of a reading that
    ``points`` kept: late13's probe as it was run, not the product's test."""
    from scipy.spatial import cKDTree

    r, f, firing = sim.readings, sim.firings, sim.truth.firing
    gap = np.where(firing >= 1, f.t[firing] - f.t[np.maximum(firing - 1, 0)], np.nan)
    kept_axis = np.column_stack((r.x + r.range * np.cos(r.theta),
                                 r.y + r.range * np.sin(r.theta)))[points.reading_id]
    far = r.range + sim.physics.sound_speed * gap / 2
    x, y = r.x + far * np.cos(r.theta), r.y + far * np.sin(r.theta)
    ok = np.isfinite(x)
    near = np.zeros(len(r), dtype=bool)
    distance = cKDTree(kept_axis).query(np.column_stack((x[ok], y[ok])))[0]
    near[ok] = distance < 0.1
    return near


# -- both ghost filters (--both) ----------------------------------------------------------------

#: ``--both``'s maps: evidence carving's default map through which of the two ghost filters.
COMBINATIONS = ("neither", "late echoes", "driven through", "both")
#: The car park's gaps wider than 2 m: the 6.0 m slot, the 4.5 m gap, the 3.2 m bay.
SLOTS = [g for g in parking.all_gaps() if g.length > 2.0]
#: The true error of each direct point a filter dropped, per (run, combination).
LOST_ERRORS: dict[tuple[str, str], list[float]] = {}


def ghost_specs(setting: Setting) -> dict[str, MapFilter]:
    """The three filtered variants as ``process --late-echo-period ROBOT --driven-through
    ROBOT`` builds them: the robot file's ``firing_period`` and its body."""
    robot = load_robot(setting.robot)
    body = BodyFootprint.of_robot(robot.mount_x, robot.mount_y, robot.bearing,
                                  robot.robot_radius)
    return {"late echoes": MapFilter(late_echo_period=robot.firing_period),
            "driven through": MapFilter(driven_through=body),
            "both": MapFilter(late_echo_period=robot.firing_period, driven_through=body)}


def _same_points(a: GlobalMap, b: GlobalMap) -> bool:
    return len(a) == len(b) and bool(np.array_equal(a.reading_id, b.reading_id)
                                     and np.array_equal(a.xy, b.xy))


def run_both(setting: Setting, check_process: bool = False) -> dict[str, dict[str, float]]:
    """One setting's map through neither, each and both ghost filters (:func:`filter_map`, as
    ``process`` runs them), with the masks' overlap on ghost and direct points.

    Each filtered map is checked against the masks: late echoes run first on the whole map and
    the driven-through test looks at each point alone, so "both" must drop exactly the union of
    the two masks. With ``check_process``, the map of :func:`process_readings` with both
    filters is checked to be the same as :func:`filter_map`'s."""
    sim = setting.make()
    points = evidence_map(sim)
    specs = ghost_specs(setting)
    late = late_echo_mask(points.xy, points.reading_id, points.max_error, sim.readings,
                          firing_period=specs["late echoes"].late_echo_period)
    body = specs["driven through"].driven_through
    assert body is not None
    driven = driven_through_mask(points.xy, points.t, sim.readings, body)
    expected = {"late echoes": late, "driven through": driven, "both": late | driven}
    kind = sim.truth.kind[points.reading_id]
    err = segment_distance(points.xy, sim.world.segments)[0]
    rows = {"neither": measures(sim, points)}
    if sim.world.name == "car-park":
        for i, gap in enumerate(SLOTS):
            rows["neither"][f"gap {i}"] = parking.read_gap(gap, points=points.xy)
    for name, spec in specs.items():
        kept = filter_map(points, spec, readings=sim.readings).points
        if not _same_points(kept, points.select(~expected[name])):
            raise AssertionError(f"{setting.label}, {name}: filter_map is not the masks' union")
        rows[name] = measures(sim, kept)
        if sim.world.name == "car-park":
            for i, gap in enumerate(SLOTS):
                rows[name][f"gap {i}"] = parking.read_gap(gap, points=kept.xy)
        lost = expected[name] & (kind == EchoKind.DIRECT)
        rows[name]["lost"] = float(lost.sum())
        rows[name]["lost %"] = 100 * float(np.mean(lost[kind == EchoKind.DIRECT]))
        LOST_ERRORS[setting.label, name] = err[lost].tolist()
    if check_process:
        both = process_readings(sim.readings, make_method("evidence", MethodConfig()),
                                map_filter=specs["both"]).global_map
        if not _same_points(both, points.select(~expected["both"])):
            raise AssertionError(f"{setting.label}: process_readings differs from filter_map")
    for who, sel in (("ghost", kind == EchoKind.CROSSTALK), ("direct", kind == EchoKind.DIRECT)):
        rows["neither"][f"{who} points"] = float(sel.sum())
        rows["neither"][f"{who} late only"] = float(np.sum(sel & late & ~driven))
        rows["neither"][f"{who} driven only"] = float(np.sum(sel & driven & ~late))
        rows["neither"][f"{who} by each"] = float(np.sum(sel & late & driven))
    return rows


def _both_table(group: str, runs: list[tuple[str, dict[str, dict[str, float]]]]) -> None:
    print(f"\n{group}: {len(runs)} runs; ghosts per run "
          f"{np.mean([r['neither']['ghosts n'] for _, r in runs]):.0f} (mean)\n")
    print("| filters | direct kept (%) | ghosts removed (%) | floor removed (%) | multipath "
          "removed (%) | median / p90 error (m) | direct points dropped (n, %, median true "
          "error m) |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name in COMBINATIONS:
        def mean(key: str, name: str = name) -> float:
            values = np.array([r[name][key] for _, r in runs])
            return float(np.mean(values[np.isfinite(values)])) if np.isfinite(values).any() \
                else math.nan

        errors = [e for label, _ in runs for e in LOST_ERRORS.get((label, name), [])]
        lost = (f"{sum(r[name]['lost'] for _, r in runs):.0f}, {mean('lost %'):.2f}, "
                f"{np.median(errors) if errors else math.nan:.2f}" if name != "neither" else "–")
        print(f"| {name} | {mean('direct'):.1f} | {mean('ghosts'):.1f} | {mean('floor'):.1f} | "
              f"{mean('multipath'):.1f} | {mean('median'):.3f} / {mean('p90'):.3f} | {lost} |")
    for who in ("ghost", "direct"):
        total = {k: sum(r["neither"][f"{who} {k}"] for _, r in runs)
                 for k in ("points", "late only", "driven only", "by each")}
        print(f"\n{who} points in the map: {total['points']:.0f}; dropped by late echoes only "
              f"{total['late only']:.0f}, by driven through only {total['driven only']:.0f}, by "
              f"each {total['by each']:.0f}", end="")
    if "gap 0" in runs[0][1]["neither"]:
        _gap_table(runs)
    print("\n\nper run, ghosts removed neither / late / driven / both (%) of n; direct points "
          "dropped late / driven / both:")
    for label, r in runs:
        print(f"  {label}: " + " / ".join(f"{r[n]['ghosts']:.1f}" for n in COMBINATIONS)
              + f" of {r['neither']['ghosts n']:.0f}; "
              + " / ".join(f"{r[n]['lost']:.0f}" for n in COMBINATIONS[1:]))


def _gap_table(runs: list[tuple[str, dict[str, dict[str, float]]]]) -> None:
    """The car park's parking question (:mod:`parking`) read from each map."""
    head = " | ".join(f"{g.length:.1f} m {g.row.kind}: read (m), judged present" for g in SLOTS)
    print(f"\n\n| filters | {head} |\n|---|" + "---:|" * len(SLOTS))
    for name in COMBINATIONS:
        cells = []
        for i, gap in enumerate(SLOTS):
            read = [r[name][f"gap {i}"] for _, r in runs]
            judged = sum(x >= parking.slot_needed(gap) for x in read)
            cells.append(f"{np.mean(read):.2f}, {judged} of {len(read)}")
        print(f"| {name} | " + " | ".join(cells) + " |", end="\n" if name != "both" else "")


def both(groups: list[str]) -> None:
    """The ``--both`` tables, one per group and physics."""
    print("evidence carving's default map through neither, each and both ghost filters "
          "(filter_map: late_echo_period = the robot's firing_period, driven_through = "
          f"BodyFootprint.of_robot; development seeds 0-{SEEDS[0] - 1}, floors' seeds "
          f"0-{SEEDS[1] - 1})")
    for group in groups:
        runs = []
        for i, setting in enumerate(GROUPS[group]()):
            tic = time.process_time()
            runs.append((setting.label, run_both(setting, check_process=i == 0)))
            print(f"  {group}, {setting.label}: {time.process_time() - tic:.0f} CPU s",
                  flush=True)
        for physics in dict.fromkeys(label.split(", ", 1)[1] for label, _ in runs):
            _both_table(f"{group}, {physics}",
                        [(label, r) for label, r in runs if label.split(", ", 1)[1] == physics])


# -- cost ---------------------------------------------------------------------------------------

def timing() -> None:
    """CPU seconds of evidence carving and of the mask on about 20,000 readings: the office
    tour driven at 0.27 m/s by the Scout2 ring (specular physics, seed 0)."""
    sim = run_simulation(Scenario("office", 0, speed=0.27))
    readings = sim.readings
    process_readings(readings[:2000], make_method("evidence", MethodConfig()))  # warm up
    start = time.process_time()
    points = evidence_map(sim)
    process_s = time.process_time() - start
    best = {}
    for name, period in (("every firing", None), ("firing period", 0.04)):
        laps = []
        for _ in range(3):
            start = time.process_time()
            _late(points, sim, period)
            laps.append(time.process_time() - start)
        best[name] = min(laps)
    print(f"{len(readings):,} readings, {len(points):,} points: process {process_s:.2f} CPU s; "
          + "; ".join(f"mask ({n}) {s:.3f} s = {100 * s / process_s:.1f} %"
                      for n, s in best.items()))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--groups", nargs="+", choices=list(GROUPS), default=list(GROUPS))
    parser.add_argument("--trace", choices=list(GROUPS), help="print the ghosts' paths instead")
    parser.add_argument("--timing", action="store_true", help="time the mask against process")
    parser.add_argument("--both", action="store_true",
                        help="the map through neither, each and both ghost filters instead")
    parser.add_argument("--dev-seeds", type=int, default=3,
                        help="the development group's seeds 0..n-1")
    parser.add_argument("--floor-seeds", type=int, default=1,
                        help="the held-out floors' seeds 0..n-1 (one-sonar, two-sonars, "
                             "scout2-ring, pioneer-ring)")
    parser.add_argument("--physics", nargs="+", choices=list(ALL_PHYSICS), metavar="NAME",
                        help="run every group under these physics instead of its own (floors "
                             "and development: amplitude, specular; car park: its three); one "
                             f"of {', '.join(repr(n) for n in ALL_PHYSICS)}")
    parser.add_argument("--half-width", type=float, help="late_echo_mask's half_width, m")
    parser.add_argument("--surface-error", type=float, help="its surface_error, m")
    parser.add_argument("--agreement", type=float,
                        help="the share of a point's neighbours that must agree (AGREEMENT; 0: "
                             "no vote)")
    args = parser.parse_args(argv)
    if args.agreement is not None:
        late_echoes_module.AGREEMENT = args.agreement
    for option in ("half_width", "surface_error"):
        if getattr(args, option) is not None:
            OPTIONS[option] = getattr(args, option)
    SEEDS[:] = [args.dev_seeds, args.floor_seeds]
    CHOSEN[:] = args.physics or []
    if args.timing:
        timing()
        return 0
    if args.both:
        both(args.groups)
        return 0
    if args.trace:
        for setting in GROUPS[args.trace]():
            sim = setting.make()
            trace(sim, evidence_map(sim), setting.label)
        return 0
    print(f"evidence carving's default map without and with late_echo_mask (c = "
          f"{SOUND_SPEED:g} m/s; the defaults but {OPTIONS}, agreement "
          f"{late_echoes_module.AGREEMENT})")
    for group in args.groups:
        runs = [(s.label, run(s)) for s in GROUPS[group]()]
        for physics in dict.fromkeys(label.split(", ", 1)[1] for label, _ in runs):
            _table(f"{group}, {physics}",
                   [(label, r) for label, r in runs if label.split(", ", 1)[1] == physics])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
