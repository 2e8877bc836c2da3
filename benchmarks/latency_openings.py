"""Evidence carving's latency and openings targets (issue 9): registry jobs for some methods.

Run from the repository root (on a shared machine, with ``nice``; tens of minutes)::

    nice .venv/bin/python benchmarks/latency_openings.py --methods carve evidence
    nice .venv/bin/python benchmarks/latency_openings.py --physics amplitude

Runs, through :func:`~sonarcarve.lab.experiments.jobs.run_job` with the full settings, the jobs
of two experiments of the registry for ``--methods`` only: the office plan's latency-accuracy
measure (3 seeds; share of wall patches whose point is right within 5 and 10 cm, and the median
seconds and metres until it is) with the local map's true error, and the Fig. 2/9 openings plan
(share of approaches passable at 1, 2 and 3 m, and per opening kind and width). ``--physics
amplitude`` runs the same jobs under the second echo model. The tables of RESULTS' evidence
section ("latency no worse than carving's", "narrow openings") come from this script run on the
trees compared.

``--hold-back M [M ...]`` adds, for ``evidence``, rows of its live view with the points of uncut
beams whose bound exceeds ``M`` metres held back
(:func:`live_held_back`; ``fig13`` names Fig. 13's threshold, ATM's
bound, and ``robot`` the simulated robot's radius), measured on the SAME runs as the base rows
(the hold-back changes no state, so the live view with it is the base run's view filtered);
``any:M`` holds back every point over the bound, cut or not (Fig. 13's rule as the paper applies
it to the global map). ``--variant P[:JSON]`` adds rows of evidence carving with P_carve ``P``
(and the confidence model ``fit_confidence.py --save`` wrote), run on the same simulations.
With ``--per-seed`` each seed's numbers are printed too.
The latency table also gives the live view's own kept / removed shares (over every snapshot,
direct echoes shown and spurious echoes hidden; RESULTS' "direct kept" and "spurious removed"
are of the global map, which no hold-back changes).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from sonarcarve.lab.analyses import ANALYSES, fig13_threshold
from sonarcarve.lab.experiments import office, openings
from sonarcarve.lab.experiments.jobs import _sample_stops
from sonarcarve.lab.instrument import RunRecord, record_run
from sonarcarve.lab.plan import Job, Settings
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import PointSource
from sonarcarve.methods import MethodConfig, SonarMethod, make_method
from sonarcarve.methods.evidence import CONFIDENCE_FEATURES, ConfidenceModel, EvidenceMethod
from sonarcarve.sim.motion import ROBOT_RADIUS
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import NO_ECHO, EchoKind
from sonarcarve.typing import JsonDict

#: A view of a run's record: (row label, hold-back bound or None for the record itself, uncut
#: only).
View = tuple[str, float | None, bool]
#: A hold-back asked for: (bound, metres; uncut only).
Hold = tuple[float, bool]
#: An evidence variant asked for: (row label, P_carve, confidence model or None: the default).
Variant = tuple[str, float, ConfidenceModel | None]


def parse_variant(text: str) -> Variant:
    """``P`` or ``P:FILE`` (P_carve; a confidence model's fields as JSON, as
    ``fit_confidence.py --save`` writes them) as a :data:`Variant`."""
    probability, _, path = text.partition(":")
    model = None
    if path:
        fields = json.loads(Path(path).read_text(encoding="utf-8"))
        # A file fitted before a feature existed has no weight for it: 0, not today's default.
        absent = {name: 0.0 for name in CONFIDENCE_FEATURES if name not in fields}
        model = ConfidenceModel(**absent, **fields)
    label = f"evidence, P_carve {float(probability):g}" + (f", fit {path}" if path else "")
    return label, float(probability), model


def variant_method(config: MethodConfig, variant: Variant) -> SonarMethod:
    _, probability, model = variant
    c = dataclasses.replace(config, carve_probability=probability)
    return EvidenceMethod(c.history_size, c.beam_width, c.range_tolerance, c.min_transversal,
                          c.range_resolution, c.evidence_bins, c.carve_probability,
                          c.min_confidence, c.stamp_error, c.stamp_heading_error,
                          confidence_model=model)


def _jobs(plan: list[Job], methods: Sequence[str], physics: str) -> list[Job]:
    chosen = [j for j in plan if j.method in methods]
    if physics == "specular":
        return chosen
    amplitude = (("echo_model", physics),)
    return [dataclasses.replace(j, scenario=dataclasses.replace(j.scenario, physics=amplitude))
            for j in chosen]


def live_held_back(source: npt.ArrayLike, max_error: npt.ArrayLike, bound: float, *,
                   uncut_only: bool = True) -> npt.NDArray[np.bool_]:
    """Points a live view would hold back: bound (``max_error``, eq. 5.3) over ``bound``
    metres, and, with ``uncut_only``, placed at the middle of a beam nothing has cut nor
    localised (source ``centerline``: no ATM median, no kept run narrower than the beam).
    Fig. 13's max-error thresholding, applied to the local map.

    >>> live_held_back([0, 0, 1, 2], [0.3, 0.1, 0.3, 0.3], 0.2).tolist()
    [True, False, False, False]
    >>> live_held_back([0, 0, 1, 2], [0.3, 0.1, 0.3, 0.3], 0.2, uncut_only=False).tolist()
    [True, False, True, True]
    """
    over = np.asarray(max_error, dtype=np.float64) > bound
    if uncut_only:
        over &= np.asarray(source) == int(PointSource.CENTERLINE)
    return np.asarray(over)


def _held(record: RunRecord, bound: float, uncut_only: bool) -> RunRecord:
    """``record`` with its snapshots' points held back as a live view would hold them
    (:func:`live_held_back`); the global map is the same. (Built in the method as
    ``EvidenceMethod(live_max_error=...)`` at ed3d534, measured, reverted: it loses latency.)"""
    s = record.samples
    held = live_held_back(s.source, s.max_error, bound, uncut_only=uncut_only)
    return dataclasses.replace(record, samples=dataclasses.replace(s, alive=s.alive & ~held))


def _views(method: str, holds: Sequence[Hold]) -> list[View]:
    views: list[View] = [(method, None, True)]
    if method == "evidence":
        views += [(f"evidence, live holds {'uncut' if uncut else 'any'} > {100 * b:.1f} cm",
                   b, uncut) for b, uncut in holds]
    return views


def _run(job: Job, sim: Simulation, views: list[View], method: SonarMethod | None = None,
         ) -> list[tuple[str, RunRecord, JsonDict]]:
    """Run ``job`` once (as :func:`~sonarcarve.lab.experiments.jobs.run_job`; ``method``
    instead of the job's own) and analyse each view of its record."""
    stops = _sample_stops(len(sim.readings), job.sample_every, job.analysis, sim,
                          dict(job.options))
    method = make_method(job.method, job.config) if method is None else method
    record = record_run(sim.readings, method, stops)
    out = []
    for label, bound, uncut_only in views:
        rec = record if bound is None else _held(record, bound, uncut_only)
        out.append((label, rec, ANALYSES[job.analysis](sim, rec, job, **dict(job.options))))
    return out


def _live_shares(sim: Simulation, record: RunRecord) -> tuple[float, float]:
    """The live view's kept / removed: over every snapshot row, the share of direct echoes
    shown and of spurious echoes not shown, percent."""
    kind = sim.truth.kind[record.samples.reading_id]
    alive = record.samples.alive
    direct = kind == EchoKind.DIRECT
    spurious = ~direct & (kind != NO_ECHO)  # a no-echo reading (--no-echo) is neither
    return 100.0 * float(np.mean(alive[direct])), 100.0 * float(np.mean(~alive[spurious]))


def _all_runs(job: Job, sim: Simulation, holds: Sequence[Hold],
              variants: Sequence[Variant]) -> list[tuple[str, RunRecord, JsonDict]]:
    """The job's own run (with its hold-back views) and, for evidence, each variant's run on
    the same simulation."""
    out = _run(job, sim, _views(job.method, holds))
    if job.method == "evidence":
        for variant in variants:
            out += _run(job, sim, [(variant[0], None, True)],
                        variant_method(job.config, variant))
    return out


def _simulation(scenario: Scenario, no_echo: bool) -> Simulation:
    """The scenario's simulation; with ``no_echo``, the same run with a no-echo reading for
    every firing that heard nothing (the echoes, and so their truth, unchanged)."""
    sim = run_simulation(scenario)
    if not no_echo:
        return sim
    return simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics, sim.odometry,
                    scene=sim.scene, no_echo=True)


def latency(methods: Sequence[str], physics: str, holds: Sequence[Hold] = (),
            per_seed: bool = False, settings: Settings | None = None,
            variants: Sequence[Variant] = (), no_echo: bool = False) -> None:
    """Print the office latency-accuracy and local-map error of each method (and view)."""
    settings = Settings.make() if settings is None else settings
    curves: dict[str, list[dict[str, dict[str, float]]]] = defaultdict(list)
    errors: dict[str, list[tuple[float, float]]] = defaultdict(list)
    shares: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for job in _jobs(office.plan(settings), methods, physics):
        sim = _simulation(job.scenario, no_echo)
        for label, rec, out in _all_runs(job, sim, holds, variants):
            curves[label].append(out["latency_accuracy"])
            errors[label].append((out["true_error"]["median"], out["true_error"]["p90"]))
            shares[label].append(_live_shares(sim, rec))
    print("| method | within | right (%) | median s | median m |\n|---|---|---:|---:|---:|")
    for method, seeds in curves.items():
        for tol in ("0.05", "0.1"):
            share = np.mean([p[tol]["resolved_share"] for p in seeds])
            seconds = np.mean([p[tol]["median_s"] for p in seeds])
            metres = np.mean([p[tol]["median_m"] for p in seeds])
            print(f"| {method} | {float(tol) * 100:.0f} cm | {share:.1f} | {seconds:.2f} | "
                  f"{metres:.2f} |")
    if per_seed:
        print("\nper seed, within 5 cm: right (%) / median s\n")
        for method, seeds in curves.items():
            print(f"  {method}: " + "; ".join(
                f"{p['0.05']['resolved_share']:.1f} / {p['0.05']['median_s']:.2f}"
                for p in seeds))
    for method, pairs in errors.items():
        median, p90 = np.mean(np.asarray(pairs), axis=0) * 100
        print(f"{method}: local-map true error, mean over seeds: median {median:.2f} cm, "
              f"p90 {p90:.2f} cm")
    for method, pairs in shares.items():
        kept, removed = np.mean(np.asarray(pairs), axis=0)
        seeds_text = "; ".join(f"{k:.1f} / {r:.1f}" for k, r in pairs)
        print(f"{method}: live view, direct shown {kept:.1f} %, spurious hidden {removed:.1f} % "
              f"(per seed {seeds_text})")


def passable(methods: Sequence[str], physics: str, holds: Sequence[Hold] = (),
             settings: Settings | None = None, variants: Sequence[Variant] = (),
             no_echo: bool = False) -> None:
    """Print the share of approaches passable at 1, 2 and 3 m, overall and per opening."""
    settings = Settings.make() if settings is None else settings
    overall: dict[str, dict[str, list[bool]]] = defaultdict(lambda: defaultdict(list))
    per_opening: dict[tuple[str, str, str, str], list[bool]] = defaultdict(list)
    for job in _jobs(openings.plan(settings), methods, physics):
        sim = _simulation(job.scenario, no_echo)
        for label, _, out in _all_runs(job, sim, holds, variants):
            for distance in ("1", "2", "3"):
                if out[distance] is not None:
                    overall[label][distance].append(out[distance])
                    per_opening[(label, job.key[1], job.key[2], distance)].append(
                        out[distance])
    for method, by_distance in overall.items():
        print(method, ", ".join(f"{d} m: {100 * np.mean(v):.1f} % of {len(v)}"
                                for d, v in sorted(by_distance.items())))
    for (method, kind, width, distance), values in sorted(per_opening.items()):
        print(f"  {method} {kind} {width} at {distance} m: {100 * np.mean(values):.0f} %")


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--methods", nargs="+", default=["carve", "evidence"])
    parser.add_argument("--physics", choices=("specular", "amplitude"), default="specular")
    parser.add_argument("--skip-latency", action="store_true")
    parser.add_argument("--skip-openings", action="store_true")
    parser.add_argument("--hold-back", nargs="+", default=[], metavar="M",
                        help="live-view hold-back bounds for evidence: metres, 'fig13' (ATM's "
                             "bound) or 'robot' (the robot's radius); prefixed 'any:', cut "
                             "points over the bound are held back too")
    parser.add_argument("--variant", nargs="+", default=[], type=parse_variant,
                        metavar="P[:JSON]",
                        help="evidence with P_carve P (and the confidence model of JSON, as "
                             "fit_confidence.py --save writes it), run on the same simulations")
    parser.add_argument("--per-seed", action="store_true")
    parser.add_argument("--no-echo", action="store_true",
                        help="feed every method the simulations' silent firings too (a reading "
                             "with range +inf for each firing that heard nothing)")
    parser.add_argument("--quick", action="store_true",
                        help="the registry's quick settings (a smoke test, not a measure)")
    args = parser.parse_args(argv)
    settings = Settings.make(quick=args.quick)
    named = {"fig13": fig13_threshold(Settings.make().method_config()), "robot": ROBOT_RADIUS}
    holds: list[Hold] = []
    for item in args.hold_back:
        uncut = not item.startswith("any:")
        value = item.removeprefix("any:")
        holds.append((named[value] if value in named else float(value), uncut))
    if not args.skip_latency:
        latency(args.methods, args.physics, holds, args.per_seed, settings, args.variant,
                args.no_echo)
    if not args.skip_openings:
        passable(args.methods, args.physics, holds, settings, args.variant, args.no_echo)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
