"""How often a map point's error bound covers its true error, on the simulator's ground truth.

Run from the repository root::

    nice .venv/bin/python benchmarks/bound_coverage.py

Every map point carries ``max_error``, an upper bound on its distance from the true reflection
(eq. 5.3, ``2 r sin(E_m/2)`` with ``E_m`` half the carved width; ATM's eq. 5.4 times δ; evidence
carving's bound over every surviving run, ``docs/evidence-carving.md``). For each sonar physics
model (``specular``, ``amplitude``), world (office, t-junction, doorway, their built-in tours),
seed and method (``carve``, ``combined``, ``evidence``, library defaults), the Scout2 ring is
simulated and mapped once; over the *direct* echoes with a point in the global map:

* *covered*: share whose distance from the point to the true reflection point is at most its
  ``max_error``;
* median and 90th percentile of that distance over ``max_error``, and the median ``max_error``;
* hints at why a bound fails: the median bound of the uncovered points; the share of all points
  and of the uncovered ones whose reflector lies at an edge of the beam the method was told
  (within 0.5° inside it: the specular physics' echo of a wall met between the half-beam and the
  critical angle comes from the edge ray, where the point's bound is exact), and of the uncovered
  ones outside it (``lab.metrics.off_beam``: side lobes); the share covered once the bound is
  widened by the reading's own range error (noise and the 1-inch quantum, which eq. 5.3 leaves
  out: it bounds the error along the arc only; a point still uncovered then is on the wrong
  bearing).

The same is given per point source (``centerline``, ``carved``, ``atm``: ``PointSource``) and,
for evidence carving, for points of split arcs (more than one surviving run,
``PieceEstimates.runs``, read through a commit listener) against unsplit ones. Spurious echoes'
points (crosstalk, floor, multipath) are only counted: their "true error" has no meaning.
Tables give means over seeds (a seed where a group is empty does not count); the covered share
is also given per seed.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from sonarcarve import MethodConfig, make_method
from sonarcarve.history import SonarHistory
from sonarcarve.lab.metrics import off_beam
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import PointSource
from sonarcarve.methods.base import Estimates, SonarMethod
from sonarcarve.methods.evidence import EvidenceModel
from sonarcarve.pipeline import process_readings
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import NO_ECHO, EchoKind
from sonarcarve.typing import SlotArray


class Points(NamedTuple):
    """A run's map points of direct echoes, shape (n,) each, and its spurious points."""

    error: np.ndarray  # distance to the true reflection point, metres
    bound: np.ndarray  # max_error, metres
    source: np.ndarray  # PointSource code
    runs: np.ndarray  # surviving runs (evidence carving), NaN for other methods
    at_edge: np.ndarray  # the reflector lies within EDGE of the told beam's edge, inside
    off_beam: np.ndarray  # the reflector lies outside the told beam
    range_error: np.ndarray  # |measured range - true range|, metres
    spurious: int  # points of spurious echoes


def simulate_run(world: str, seed: int, physics: str) -> Simulation:
    """The Scout2 tour of ``world`` under ``physics`` (as ``evidence.py`` simulates it)."""
    overrides = () if physics == "specular" else (("echo_model", physics),)
    return run_simulation(Scenario(world, seed, physics=overrides))


def record_runs(method: SonarMethod, n: int) -> np.ndarray:
    """Per reading, the surviving runs of its arc when it left the history (filled as the
    method commits; NaN for readings never committed or methods without evidence runs)."""
    runs = np.full(n, np.nan)
    model = method.models[0]
    if not isinstance(model, EvidenceModel):
        return runs

    def listener(history: SonarHistory, slots: SlotArray, est: Estimates) -> None:
        runs[history.reading_id[slots]] = model.raw(slots).runs

    method.add_commit_listener(listener)
    return runs


#: How near a beam edge (radians, inside) a reflector counts as at the edge: the specular
#: physics' 31 rays are 0.75° apart, and its edge rays lie on the edges.
EDGE = math.radians(0.5)


def off_axis(sensor_xy: np.ndarray, theta: np.ndarray, reflection: np.ndarray) -> np.ndarray:
    """Angle between each sensor's axis and its true reflector, radians in [0, π]."""
    bearing = np.arctan2(*(reflection - sensor_xy).T[::-1])
    return np.asarray(np.abs((bearing - theta + math.pi) % (2.0 * math.pi) - math.pi))


def map_points(sim: Simulation, name: str) -> Points:
    """Map ``sim`` with method ``name`` and measure its points against the truth."""
    method = make_method(name, MethodConfig())
    runs = record_runs(method, len(sim.readings))
    gmap = process_readings(sim.readings, method).global_map
    rid = gmap.reading_id
    kind = sim.truth.kind[rid]
    direct = kind == EchoKind.DIRECT
    rid = rid[direct]
    reflection = sim.truth.reflection[rid]
    readings = sim.readings
    sensor_xy = np.column_stack([readings.x[rid], readings.y[rid]])
    true_range = np.hypot(*(reflection - sensor_xy).T)
    outside = off_beam(sensor_xy, readings.theta[rid], readings.beam_width[rid], reflection)
    return Points(
        error=np.hypot(*(gmap.xy[direct] - reflection).T),
        bound=gmap.max_error[direct],
        source=gmap.source[direct],
        runs=runs[rid],
        at_edge=~outside & (off_axis(sensor_xy, readings.theta[rid], reflection)
                            >= 0.5 * readings.beam_width[rid] - EDGE),
        off_beam=outside,
        range_error=np.abs(readings.range[rid] - true_range),
        spurious=int(np.count_nonzero(~direct & (kind != NO_ECHO))),
    )


Select = Callable[[Points], np.ndarray]


def _from(source: PointSource) -> Select:
    """The points ``source`` placed."""
    return lambda p: np.asarray(p.source == source)


#: Groups of points a row can be about: name -> which points.
GROUPS: dict[str, Select] = {
    "all": lambda p: np.ones(len(p.error), dtype=bool),
    **{f"source {source.label}": _from(source) for source in PointSource},
    "split (runs > 1)": lambda p: np.asarray(p.runs > 1),
    "unsplit (1 run)": lambda p: np.asarray(p.runs == 1),
}
COLUMNS = ("points", "covered", "median_ratio", "p90_ratio", "median_bound", "at_edge",
           "uncovered_bound", "uncovered_edge", "uncovered_off", "covered_range")


def coverage(p: Points, sel: np.ndarray) -> dict[str, float]:
    """The columns of :data:`COLUMNS` over the points ``sel`` (NaN but ``points`` if none)."""
    if not sel.any():
        return {c: (0.0 if c == "points" else math.nan) for c in COLUMNS}
    error, bound = p.error[sel], p.bound[sel]
    ratio = error / bound
    covered = error <= bound
    return {
        "points": float(np.count_nonzero(sel)),
        "covered": 100.0 * float(np.mean(covered)),
        "median_ratio": float(np.median(ratio)),
        "p90_ratio": float(np.percentile(ratio, 90.0)),
        "median_bound": 100.0 * float(np.median(bound)),
        "at_edge": _share(p.at_edge[sel]),
        "uncovered_bound": (100.0 * float(np.median(bound[~covered]))
                            if not covered.all() else math.nan),
        "uncovered_edge": _share(p.at_edge[sel][~covered]),
        "uncovered_off": _share(p.off_beam[sel][~covered]),
        "covered_range": 100.0 * float(np.mean(error <= bound + p.range_error[sel])),
    }


def _share(mask: np.ndarray) -> float:
    """Percentage of True in ``mask``, NaN when it is empty."""
    return 100.0 * float(np.mean(mask)) if len(mask) else math.nan


def _mean(values: list[float]) -> float:
    """Mean of the values that are not NaN (NaN when none is)."""
    kept = [v for v in values if not math.isnan(v)]
    return float(np.mean(kept)) if kept else math.nan


def _cell(value: float, digits: int) -> str:
    return "–" if math.isnan(value) else f"{value:.{digits}f}"


def print_table(title: str, rows: dict[str, list[dict[str, float]]]) -> None:
    """Means over seeds of each row's runs; a seed whose group is empty is left out."""
    print(f"\n{title}\n")
    print("| method, points | points per run | covered (%) | error / bound median | p90 | "
          "bound median (cm) | at beam edge (%) | uncovered: bound median (cm) | "
          "uncovered at beam edge (%) | uncovered off-beam (%) | "
          "covered, bound + range error (%) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for name, runs in rows.items():
        m = {c: _mean([r[c] for r in runs]) for c in COLUMNS}
        if m["points"] == 0.0:
            continue
        print(f"| {name} | {m['points']:.0f} | {_cell(m['covered'], 1)} | "
              f"{_cell(m['median_ratio'], 2)} | {_cell(m['p90_ratio'], 2)} | "
              f"{_cell(m['median_bound'], 1)} | {_cell(m['at_edge'], 0)} | "
              f"{_cell(m['uncovered_bound'], 1)} | "
              f"{_cell(m['uncovered_edge'], 0)} | {_cell(m['uncovered_off'], 0)} | "
              f"{_cell(m['covered_range'], 1)} |")


def print_per_seed(rows: dict[str, list[dict[str, float]]], spurious: dict[str, list[int]]
                   ) -> None:
    """The covered share of every point, per seed, and the spurious points' counts."""
    print("\n| method | covered per seed (%) | spurious echoes' points per seed |")
    print("|---|---|---|")
    for name, runs in rows.items():
        covered = " / ".join(_cell(r["covered"], 1) for r in runs)
        print(f"| {name} | {covered} | {' / '.join(map(str, spurious[name]))} |")


def measure(world: str, physics: str, seeds: int, methods: list[str]) -> None:
    """Simulate, map and print the tables of one world and physics."""
    rows: dict[str, list[dict[str, float]]] = {}
    spurious: dict[str, list[int]] = {name: [] for name in methods}
    for seed in range(seeds):
        sim = simulate_run(world, seed, physics)
        for name in methods:
            p = map_points(sim, name)
            spurious[name].append(p.spurious)
            for group, select in GROUPS.items():
                rows.setdefault(f"{name}, {group}", []).append(coverage(p, select(p)))
    print_table(f"{world}, physics {physics}: direct echoes' points, {seeds} seeds, mean over "
                "seeds", rows)
    print_per_seed({name: rows[f"{name}, all"] for name in methods}, spurious)


def main(argv: list[str] | None = None) -> int:
    """Parse the options and print every world's and physics' tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--worlds", nargs="+", default=["office", "t-junction", "doorway"])
    parser.add_argument("--seeds", type=int, default=3, help="seeds 0..n-1 per world")
    parser.add_argument("--physics", nargs="+", default=["specular", "amplitude"])
    parser.add_argument("--methods", nargs="+", default=["carve", "combined", "evidence"])
    args = parser.parse_args(argv)
    for physics in args.physics:
        for world in args.worlds:
            measure(world, physics, args.seeds, args.methods)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
