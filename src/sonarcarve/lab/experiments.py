"""The paper's experiments (section 5) regenerated on the simulator, and the ones it could not run.

Each experiment is a plan of *jobs* (one sonar method on one simulated log, a
:class:`~sonarcarve.lab.scenarios.Scenario`, then one analysis of what it did, see
:mod:`sonarcarve.lab.instrument` and :mod:`sonarcarve.lab.analyses`) and a
summary of the jobs' outputs over seeds:

* ``office``: the paper's Table I, Fig. 10, 11, 12 and 13 and the fully carved share (section
  5-B, 5-C) on the simulated ``office`` tour, several seeds; plus what the paper could not
  measure without ground truth: the true error of every local map point and, per wall patch, how
  long after it came into view the local map had it right (latency against accuracy).
* ``t-junction``: Fig. 4, how far before the facing wall each method's local map first shows it.
* ``openings``: Fig. 2 and 9, whether each local map shows narrow doors and side openings
  passable when the robot is 1, 2 and 3 m away.
* ``sensitivity``: history length, range tolerance ε, beam width φ, minimum transversal angle ψ,
  speed and range noise against error, latency and the fully carved share.

Simulations are made once per distinct scenario and shared by every job that needs them (and
across parameters that do not change the simulation); jobs can run in worker processes.
"""

from __future__ import annotations

import math
import multiprocessing
import time
from collections import defaultdict
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import (
    ANALYSES,
    CLEARANCE_MARGIN,
    GAP_DEPTH,
    LATENCY_GRID_M,
    LATENCY_GRID_S,
    METHOD_LABELS,
    OPENING_DISTANCES,
    PATCH_LENGTH,
    PATCH_TOLERANCES,
    RANGE_EDGES,
    WALL_POINTS,
    WALL_RADIUS,
    fig13_keep,
    fig13_threshold,
    first_reading_within,
    removal_summary,
)
from sonarcarve.lab.appendix import APPENDIX_EXPERIMENTS, experiment_summariser
from sonarcarve.lab.instrument import record_run
from sonarcarve.lab.scenarios import (
    ExperimentError,
    Scenario,
    build_world,
    cut_polyline,
    run_simulation,
)
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.methods.atm import atm_error_bound
from sonarcarve.methods.carving import DEFAULT_RANGE_TOLERANCE
from sonarcarve.sim.motion import DEFAULT_SPEED
from sonarcarve.sim.simulate import Simulation
from sonarcarve.typing import JsonDict

__all__ = [
    "CLEARANCE_MARGIN",
    "EXPERIMENTS",
    "GAP_DEPTH",
    "METHOD_LABELS",
    "RANGE_EDGES",
    "ExperimentError",
    "ExperimentResults",
    "Scenario",
    "Settings",
    "build_world",
    "cut_polyline",
    "fig13_keep",
    "fig13_threshold",
    "removal_summary",
    "run_experiments",
    "run_simulation",
]


#: Every method, in the order tables list them.
ALL_METHODS = ("atm", "carve", "combined", "centerline")

#: The narrow hallway (Fig. 9) needs its narrow part wider than the tour's 0.9 m clearance.
NARROW_MIN_WIDTH = 0.9
#: Width of the example run of each opening world whose local maps the figure shows.
EXAMPLE_WIDTH = {"doorway": 0.8, "corridor-opening": 0.8, "narrow-hallway": 1.0}


# ============================================================================ settings


@dataclass(frozen=True)
class Settings:
    """How big the experiments are. :meth:`full` is what ``make experiments`` runs.

    Attributes
    ----------
    quick : bool
        Small runs (for the test suite): short tours, few openings, short sweeps.
    seeds : int
        Simulation seeds 0..seeds-1 for the office tour, the T junction and the openings.
    jobs : int
        Worker processes (1: everything in this process).
    history_size : int
        History length of the paper-style runs (paper, section 5-C: 250).
    speed : float
        Robot speed, m/s.
    sample_every : int
        Readings between two snapshots of the history (16 = one Scout2 ring cycle, 0.64 s).
    office_length : float or None
        Metres of the office tour to drive (None: all of it).
    sweep_length : float or None
        Metres of the office tour driven by each sensitivity run (None: all of it).
    opening_widths : tuple of float
        Door and side-opening widths, metres.
    """

    quick: bool = False
    seeds: int = 3
    jobs: int = 1
    history_size: int = 250
    speed: float = DEFAULT_SPEED
    sample_every: int = 16
    office_length: float | None = None
    sweep_length: float | None = None
    opening_widths: tuple[float, ...] = (0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2)
    door_headings_deg: tuple[float, ...] = (0.0, 20.0, -35.0, 45.0)
    door_offsets: tuple[float, ...] = (0.0, 0.15, -0.15)
    corridor_offsets: tuple[float, ...] = (-0.4, 0.0, 0.4)
    sweep_sample_every: int = 32
    sweeps: tuple[tuple[str, tuple[float, ...]], ...] = (
        ("history", (50, 100, 250, 500, 1000, 2000)),
        ("range_tolerance", (0.0, 0.01, 0.025, 0.05, 0.1)),
        ("beam_width_deg", (15.0, 22.5, 30.0)),
        ("min_transversal_deg", (10.0, 20.0, 30.0, 45.0, 60.0)),
        ("speed", (0.2, 0.4, 0.8)),
        ("range_noise", (0.0, 0.01, 0.03, 0.05)),
    )

    def __post_init__(self) -> None:
        if self.seeds < 1:
            msg = f"--seeds must be at least 1, got {self.seeds}"
            raise ExperimentError(msg)
        if self.jobs < 1:
            msg = f"--jobs must be at least 1, got {self.jobs}"
            raise ExperimentError(msg)

    @classmethod
    def make(cls, *, quick: bool = False, seeds: int | None = None, jobs: int = 1) -> Settings:
        """The full settings, or the quick ones (small enough for the test suite)."""
        if not quick:
            return cls(seeds=3 if seeds is None else seeds, jobs=jobs)
        return cls(
            quick=True, seeds=1 if seeds is None else seeds, jobs=jobs, office_length=30.0,
            sweep_length=12.0, opening_widths=(0.6, 1.2), door_headings_deg=(0.0,),
            door_offsets=(0.0,), corridor_offsets=(0.0,), sweep_sample_every=32,
            sweeps=(("history", (50, 250)), ("range_tolerance", (0.0, 0.025)),
                    ("beam_width_deg", (22.5, 30.0)), ("min_transversal_deg", (20.0, 30.0)),
                    ("speed", (0.4, 0.8)), ("range_noise", (0.01, 0.03))),
        )

    def method_config(self, **changes: Any) -> MethodConfig:
        """The paper-style configuration: history 250, φ 22.5°, ψ 30°, δ one inch, and carving's
        measured default ε (:data:`~sonarcarve.methods.carving.DEFAULT_RANGE_TOLERANCE`)."""
        base = MethodConfig(history_size=self.history_size,
                            range_tolerance=DEFAULT_RANGE_TOLERANCE)
        return replace(base, **changes)


# ============================================================================ jobs


@dataclass(frozen=True)
class Job:
    """One method on one scenario, then one analysis (a function of :data:`ANALYSES`)."""

    key: tuple[Any, ...]
    scenario: Scenario
    method: str
    config: MethodConfig
    analysis: str
    sample_every: int = 16
    options: tuple[tuple[str, Any], ...] = ()


def run_job(job: Job, sim: Simulation) -> JsonDict:
    """Run ``job`` on its simulation and return the analysis' output (small, picklable)."""
    n = len(sim.readings)
    stops = _sample_stops(n, job.sample_every, job.analysis, sim, dict(job.options))
    record = record_run(sim.readings, make_method(job.method, job.config), stops)
    out = ANALYSES[job.analysis](sim, record, job, **dict(job.options))
    out["seconds"] = record.seconds
    out["readings"] = n
    return out


def _sample_stops(n: int, every: int, analysis: str, sim: Simulation,
                  options: dict[str, Any]) -> npt.NDArray[np.int64]:
    stops = np.arange(every, n + 1, every, dtype=np.int64)
    if analysis == "opening":
        # Snapshot exactly when the robot first comes within each distance of the gap.
        extra = [first_reading_within(sim, options["opening"], d) for d in OPENING_DISTANCES]
        stops = np.concatenate((stops, [e for e in extra if e > 0]))
    return stops


def _run_one(args: tuple[Job, Simulation]) -> JsonDict:
    return run_job(*args)



# ============================================================================ experiments


class Experiment(NamedTuple):
    """A named experiment: its jobs and how to summarise their outputs."""

    name: str
    title: str
    plan: Callable[[Settings], list[Job]]
    summarise: Callable[[Settings, dict[tuple[Any, ...], JsonDict]], tuple[JsonDict, JsonDict]]


# -- office ------------------------------------------------------------------------------------

def _plan_office(s: Settings) -> list[Job]:
    return [Job(("office", seed, m), Scenario("office", seed, max_length=s.office_length,
                                              speed=s.speed),
                m, s.method_config(), "office", s.sample_every,
                (("detail", seed == 0),))
            for seed in range(s.seeds) for m in ALL_METHODS]


def _spread(values: Iterable[float | None]) -> JsonDict:
    v = np.array([np.nan if x is None else x for x in values], dtype=np.float64)
    ok = v[np.isfinite(v)]
    if not ok.size:
        return {"mean": None, "min": None, "max": None, "std": None, "per_seed": []}
    return {"mean": float(ok.mean()), "min": float(ok.min()), "max": float(ok.max()),
            "std": float(ok.std()), "per_seed": [None if not math.isfinite(x) else float(x)
                                                 for x in v]}


def _binned_over_seeds(outs: list[JsonDict], key: str, stat: str = "mean") -> JsonDict:
    return metrics.combine_binned([o[key] for o in outs], stat)


def _summarise_office(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[JsonDict,
                                                                                   JsonDict]:
    by_method = {m: [outs[("office", seed, m)] for seed in range(s.seeds)] for m in ALL_METHODS}
    label = METHOD_LABELS
    res: JsonDict = {}
    res["table1"] = {label[m]: _spread(o["unprocessed"] for o in by_method[m])["mean"]
                     for m in ALL_METHODS}
    res["table1_spread"] = {label[m]: _spread(o["unprocessed"] for o in by_method[m])
                            for m in ALL_METHODS}
    res["table1_alive_only"] = {
        label[m]: _spread(o["unprocessed_alive"] for o in by_method[m])["mean"]
        for m in ALL_METHODS}
    res["fig10"] = {label[m]: _binned_over_seeds(by_method[m], "unprocessed_by_range")
                    for m in ALL_METHODS}
    carve = by_method["carve"]
    res["fig11"] = {
        "all_surviving": {"mean": _binned_over_seeds(carve, "width_by_range", "mean"),
                          "median": _binned_over_seeds(carve, "width_by_range", "median")},
        "carved_only": {"mean": _binned_over_seeds(carve, "carved_width_by_range", "mean"),
                        "median": _binned_over_seeds(carve, "carved_width_by_range", "median")},
    }
    config = s.method_config()
    res["fig12"] = {
        "carving": _binned_over_seeds(carve, "max_error_by_range"),
        "centerline": _binned_over_seeds(by_method["centerline"], "max_error_by_range"),
        "atm_measured": _binned_over_seeds(by_method["atm"], "max_error_by_range"),
        "combined": _binned_over_seeds(by_method["combined"], "max_error_by_range"),
        "atm_bound": atm_error_bound(config.min_transversal, config.range_resolution),
    }
    removal_keys = carve[0]["removal"].keys()
    res["fully_carved"] = {k: _spread(o["removal"][k] for o in carve)["mean"]
                           for k in removal_keys}
    res["fully_carved_spread"] = {k: _spread(o["removal"][k] for o in carve)
                                  for k in ("share", "spurious_removed", "true_lost")}
    res["fully_carved_combined"] = {k: _spread(o["removal"][k] for o in by_method["combined"])
                                    ["mean"] for k in ("share", "spurious_removed", "true_lost")}
    res["true_error"] = {label[m]: {q: _spread(o["true_error"][q] for o in by_method[m])["mean"]
                                    for q in ("median", "p90", "mean")} for m in ALL_METHODS}
    res["true_error_spread"] = {
        label[m]: {q: _spread(o["true_error"][q] for o in by_method[m]) for q in ("median", "p90")}
        for m in ALL_METHODS}
    res["true_error_by_range"] = {
        label[m]: {"median": _binned_over_seeds(by_method[m], "true_error_by_range", "median"),
                   "p90": _binned_over_seeds(by_method[m], "true_error_by_range", "p90")}
        for m in ALL_METHODS}
    res["true_error_global"] = {
        label[m]: {q: _spread(o["global_error"][q] for o in by_method[m])["mean"]
                   for q in ("median", "p90")} for m in ALL_METHODS}
    res["fig13"] = {
        "threshold_m": fig13_threshold(config),
        **{label[m]: {
            "points": _spread(o["global_points"] for o in by_method[m])["mean"],
            "kept": _spread(o["thresholded_points"] for o in by_method[m])["mean"],
            "kept_error_median": _spread(o["thresholded_error"]["median"]
                                         for o in by_method[m])["mean"],
            "kept_error_p90": _spread(o["thresholded_error"]["p90"] for o in by_method[m])["mean"],
        } for m in ALL_METHODS}}
    res["latency_accuracy"] = {"grid_s": list(LATENCY_GRID_S), "grid_m": list(LATENCY_GRID_M),
                               "patch_length_m": PATCH_LENGTH}
    for m in ALL_METHODS:
        entry: JsonDict = {}
        for tol in PATCH_TOLERANCES:
            key = f"{tol:g}"
            per = [o["latency_accuracy"][key] for o in by_method[m]]
            entry[key] = {
                "resolved_share": _spread(p["resolved_share"] for p in per)["mean"],
                "median_s": _spread(p["median_s"] for p in per)["mean"],
                "median_m": _spread(p["median_m"] for p in per)["mean"],
                "curve_s": np.mean([p["curve_s"] for p in per], axis=0).tolist(),
                "curve_m": np.mean([p["curve_m"] for p in per], axis=0).tolist(),
            }
        entry["patches_seen"] = _spread(o["latency_accuracy"]["patches_seen"]
                                        for o in by_method[m])["mean"]
        res["latency_accuracy"][label[m]] = entry
    res["truth_breakdown"] = {}
    for m in ALL_METHODS:
        per = [o["truth_breakdown"] for o in by_method[m]]
        entry = {k: _spread(p[k] for p in per)["mean"] for k in per[0] if k != "direct_error"}
        entry["direct_error"] = {q: _spread(p["direct_error"][q] for p in per)["mean"]
                                 for q in ("median", "p90")}
        res["truth_breakdown"][label[m]] = entry
    first = {m: by_method[m][0] for m in ALL_METHODS}
    res["office_runs"] = {
        "seeds": s.seeds, "readings": _spread(o["readings"] for o in by_method["carve"])["mean"],
        "duration_s": _spread(o["duration"] for o in by_method["carve"])["mean"],
        "method_seconds": {label[m]: _spread(o["seconds"] for o in by_method[m])["mean"]
                           for m in ALL_METHODS}}
    artifacts = {"fig13": {label[m]: first[m].get("global_map") for m in ("atm", "carve")}}
    return res, artifacts


# -- T junction --------------------------------------------------------------------------------

def _t_junction_scenario(s: Settings, seed: int) -> Scenario:
    from sonarcarve.sim.world import load_world

    tour = load_world("t-junction").tour
    assert tour is not None
    # Only the drive up the stem, towards the facing wall (the tour's first leg).
    stem = tuple((float(x), float(y)) for x, y in tour[:2])
    return Scenario("t-junction", seed, path=stem, speed=s.speed)


def _plan_t_junction(s: Settings) -> list[Job]:
    return [Job(("t-junction", seed, m), _t_junction_scenario(s, seed), m, s.method_config(),
                "t-junction", 4, (("detail", seed == 0),))
            for seed in range(s.seeds) for m in ALL_METHODS]


def _summarise_t_junction(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[JsonDict,
                                                                                      JsonDict]:
    res: JsonDict = {"points": WALL_POINTS, "radius_m": WALL_RADIUS, "all": {}, "refined": {},
                     "end_distance_m": outs[("t-junction", 0, "carve")]["end_distance"]}
    for m in ALL_METHODS:
        per = [outs[("t-junction", seed, m)] for seed in range(s.seeds)]
        for kind in ("all", "refined"):
            res[kind][METHOD_LABELS[m]] = _spread(o[kind] for o in per)
    artifacts = {"snapshots": {METHOD_LABELS[m]: outs[("t-junction", 0, m)].get("snapshot")
                               for m in ALL_METHODS}}
    return {"t_junction": res}, artifacts


# -- openings ----------------------------------------------------------------------------------

def _opening_runs(s: Settings) -> list[tuple[str, float, float, float, int]]:
    """(kind, width, heading_deg, offset, seed) of every opening run."""
    runs = []
    for seed in range(s.seeds):
        for w in s.opening_widths:
            runs += [("doorway", w, h, o, seed) for h in s.door_headings_deg
                     for o in s.door_offsets]
            runs += [("corridor-opening", w, 0.0, o, seed) for o in s.corridor_offsets]
            if w > NARROW_MIN_WIDTH:
                runs.append(("narrow-hallway", w, 0.0, 0.0, seed))
    return runs


def _opening_scenario(s: Settings, kind: str, width: float, heading_deg: float,
                      offset: float, seed: int) -> tuple[Scenario, list[list[float]]]:
    world = build_world(f"{kind}:{width:g}")
    # The narrow hallway's second opening is the mouth of its narrow part (paper, Fig. 9).
    gap = world.openings[1 if kind == "narrow-hallway" else 0]
    if kind == "doorway":
        # A straight drive aimed at the door (shifted ``offset`` along the wall), at
        # ``heading_deg`` from the wall's normal, from 4.3 m to 0.8 m short of the aim point.
        aim = 0.5 * (gap[0] + gap[1]) + np.array([offset, 0.0])
        h = math.radians(heading_deg)
        direction = np.array([math.sin(h), math.cos(h)])
        path = (aim - 4.3 * direction, aim - 0.8 * direction)
    else:
        # Along the corridor, ``offset`` metres right of the tour, past or into the opening.
        assert world.tour is not None
        path = (world.tour[0] + [offset, 0.0], world.tour[-1] + [offset, 0.0])
    points = tuple((float(p[0]), float(p[1])) for p in path)
    return Scenario(f"{kind}:{width:g}", seed, path=points, speed=s.speed), gap.tolist()


def _plan_openings(s: Settings) -> list[Job]:
    jobs = []
    for run in _opening_runs(s):
        scenario, gap = _opening_scenario(s, *run)
        # One run per world kind keeps its local maps at 2 m for the figure.
        example = run[1] == EXAMPLE_WIDTH[run[0]] and run[2] == 0.0 and run[3] == 0.0 \
            and run[4] == 0
        jobs += [Job(("opening", *run, m), scenario, m, s.method_config(), "opening", 4,
                     (("opening", tuple(map(tuple, gap))), ("detail", example)))
                 for m in ALL_METHODS]
    return jobs


def _summarise_openings(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[JsonDict,
                                                                                    JsonDict]:
    runs = _opening_runs(s)
    res: JsonDict = {}
    detail: JsonDict = {}
    for m in ALL_METHODS:
        label = METHOD_LABELS[m]
        res[label] = {}
        detail[label] = {}
        for d in OPENING_DISTANCES:
            key = f"{d:g}"
            flags = [outs[("opening", *run, m)][key] for run in runs]
            res[label][key] = metrics.percent([f for f in flags if f is not None])
            by: dict[str, list[bool]] = defaultdict(list)
            for run, f in zip(runs, flags, strict=True):
                if f is not None:
                    by[f"{run[0]} {run[1]:g}"].append(f)
            detail[label][key] = {k: metrics.percent(v) for k, v in sorted(by.items())}
    artifacts: JsonDict = {"snapshots": {}}
    for job_key, out in outs.items():
        if "snapshot" in out:
            world, method = str(job_key[1]), str(job_key[-1])
            artifacts["snapshots"].setdefault(world, {})[METHOD_LABELS[method]] = out["snapshot"]
    definition = {"clearance_m": 0.41 + CLEARANCE_MARGIN, "gap_depth_m": GAP_DEPTH,
                  "distances_m": list(OPENING_DISTANCES), "runs": len(runs),
                  "widths_m": list(s.opening_widths),
                  "door_headings_deg": list(s.door_headings_deg),
                  "door_offsets_m": list(s.door_offsets),
                  "corridor_offsets_m": list(s.corridor_offsets)}
    return {"openings": res, "openings_by_world": detail, "openings_definition": definition}, \
        artifacts


# -- sensitivity -------------------------------------------------------------------------------

#: Sweep parameter -> (methods it matters to, unit).
SWEEP_METHODS = {
    "history": (("carve", "atm", "combined"), "arcs"),
    "range_tolerance": (("carve", "combined"), "m"),
    "beam_width_deg": (("carve", "atm", "combined", "centerline"), "deg"),
    "min_transversal_deg": (("atm", "combined"), "deg"),
    "speed": (("carve", "atm", "combined", "centerline"), "m/s"),
    "range_noise": (("carve", "atm", "combined", "centerline"), "m"),
}

#: What each sensitivity run reports (see :func:`~sonarcarve.lab.analyses.analyse_sweep`).
SWEEP_MEASURES = ("error_median", "error_p90", "unprocessed", "fully_carved", "refined_share",
                  "error_median_refined", "error_median_fallback", "fallback_median_range")


def _sweep_job(s: Settings, param: str, value: float, method: str) -> Job:
    scenario = Scenario("office", 0, max_length=s.sweep_length, speed=s.speed)
    config = s.method_config()
    if param == "history":
        config = replace(config, history_size=int(value))
    elif param == "range_tolerance":
        config = replace(config, range_tolerance=float(value))
    elif param == "beam_width_deg":
        scenario = replace(scenario, beam_width_deg=float(value))
        config = replace(config, beam_width=math.radians(value))
    elif param == "min_transversal_deg":
        config = replace(config, min_transversal=math.radians(value))
    elif param == "speed":
        scenario = replace(scenario, speed=float(value))
    elif param == "range_noise":
        scenario = replace(scenario, physics=(("range_noise", float(value)),))
    return Job(("sweep", param, value, method), scenario, method, config, "sweep",
               s.sweep_sample_every)


def _plan_sensitivity(s: Settings) -> list[Job]:
    return [_sweep_job(s, param, value, m) for param, values in s.sweeps
            for value in values for m in SWEEP_METHODS[param][0]]


def _summarise_sensitivity(s: Settings, outs: dict[tuple[Any, ...], JsonDict]) -> tuple[
        JsonDict, JsonDict]:
    res: JsonDict = {}
    for param, values in s.sweeps:
        methods, unit = SWEEP_METHODS[param]
        entry: JsonDict = {"values": list(values), "unit": unit}
        for m in methods:
            per = [outs[("sweep", param, v, m)] for v in values]
            entry[METHOD_LABELS[m]] = {
                q: [None if p[q] is None or not math.isfinite(p[q]) else float(p[q]) for p in per]
                for q in SWEEP_MEASURES}
        res[param] = entry
    res["scenario"] = {"world": "office", "seed": 0, "length_m": s.sweep_length,
                       "sample_every": s.sweep_sample_every}
    return {"sensitivity": res}, {}


EXPERIMENTS: dict[str, Experiment] = {
    "office": Experiment("office", "Table I, Fig. 10-13, fully carved, true error, latency",
                         _plan_office, _summarise_office),
    "t-junction": Experiment("t-junction", "Fig. 4: when the facing wall appears",
                             _plan_t_junction, _summarise_t_junction),
    "openings": Experiment("openings", "Fig. 2 and 9: narrow openings passable",
                           _plan_openings, _summarise_openings),
    "sensitivity": Experiment("sensitivity", "history, ε, φ, ψ, speed, noise sweeps",
                              _plan_sensitivity, _summarise_sensitivity),
}
# The appendix experiments (polling, real-log, odometry) plan no jobs: they run in summarise.
EXPERIMENTS.update({name: Experiment(name, title, lambda s: [], experiment_summariser(name))
                    for name, (title, _) in APPENDIX_EXPERIMENTS.items()})


# ============================================================================ running


@dataclass
class ExperimentResults:
    """What :func:`run_experiments` produced.

    Attributes
    ----------
    results : dict
        JSON-ready numbers (written to ``results.json``).
    artifacts : dict
        Arrays for the figures (maps), per experiment; not written to JSON.
    """

    results: JsonDict = field(default_factory=dict)
    artifacts: JsonDict = field(default_factory=dict)


ProgressCallback = Callable[[str, int, int], None]


def run_experiments(
    settings: Settings,
    only: Sequence[str] | None = None,
    on_progress: ProgressCallback | None = None,
) -> ExperimentResults:
    """Run the chosen experiments (all by default) and summarise them.

    Parameters
    ----------
    settings : Settings
        Sizes, seeds and worker count.
    only : sequence of str, optional
        Experiment names (keys of :data:`EXPERIMENTS`).
    on_progress : callable, optional
        ``on_progress(stage, done, total)`` with stage ``"simulating"`` or ``"mapping"``.

    Raises
    ------
    ExperimentError
        For an unknown experiment name.
    """
    names = list(EXPERIMENTS) if not only else list(only)
    for name in names:
        if name not in EXPERIMENTS:
            msg = f"unknown experiment {name!r}; choose from {', '.join(EXPERIMENTS)}"
            raise ExperimentError(msg)
    tic = time.perf_counter()
    plans = {name: EXPERIMENTS[name].plan(settings) for name in names}
    jobs = [job for name in names for job in plans[name]]
    scenarios = list(dict.fromkeys(job.scenario for job in jobs))
    report = on_progress or (lambda stage, done, total: None)

    pool = None
    if settings.jobs > 1:
        pool = ProcessPoolExecutor(max_workers=settings.jobs,
                                   mp_context=multiprocessing.get_context("spawn"))
    try:
        sims: dict[Scenario, Simulation] = {}
        report("simulating", 0, len(scenarios))
        sim_list = (pool.map(run_simulation, scenarios, chunksize=1) if pool is not None
                    else map(run_simulation, scenarios))
        for i, (scenario, sim) in enumerate(zip(scenarios, sim_list, strict=True)):
            sims[scenario] = sim
            report("simulating", i + 1, len(scenarios))
        report("mapping", 0, len(jobs))
        args = [(job, sims[job.scenario]) for job in jobs]
        out_list = (pool.map(_run_one, args, chunksize=1) if pool is not None
                    else map(_run_one, args))
        outputs: dict[tuple[Any, ...], JsonDict] = {}
        for i, (job, out) in enumerate(zip(jobs, out_list, strict=True)):
            outputs[job.key] = out
            report("mapping", i + 1, len(jobs))
    finally:
        if pool is not None:
            pool.shutdown()

    results = ExperimentResults()
    for name in names:
        own = {job.key: outputs[job.key] for job in plans[name]}
        res, art = EXPERIMENTS[name].summarise(settings, own)
        results.results.update(res)
        results.artifacts[name] = art
    results.results["meta"] = {
        "experiments": names,
        "settings": _settings_json(settings),
        "seconds": time.perf_counter() - tic,
        "simulations": len(scenarios),
        "jobs": len(jobs),
        "readings_simulated": int(sum(len(sim.readings) for sim in sims.values())),
    }
    return results


def _settings_json(s: Settings) -> JsonDict:
    out = asdict(s)
    out["sweeps"] = {k: list(v) for k, v in s.sweeps}
    config = s.method_config()
    out["method_config"] = {"history_size": config.history_size,
                            "beam_width_deg": math.degrees(config.beam_width),
                            "range_tolerance_m": config.range_tolerance,
                            "min_transversal_deg": math.degrees(config.min_transversal),
                            "range_resolution_m": config.range_resolution}
    return out
