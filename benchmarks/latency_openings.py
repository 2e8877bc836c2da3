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
"""

from __future__ import annotations

import argparse
import dataclasses
from collections import defaultdict
from collections.abc import Sequence

import numpy as np

from sonarcarve.lab.experiments import office, openings
from sonarcarve.lab.experiments.jobs import run_job
from sonarcarve.lab.plan import Job, Settings
from sonarcarve.lab.scenarios import run_simulation


def _jobs(plan: list[Job], methods: Sequence[str], physics: str) -> list[Job]:
    chosen = [j for j in plan if j.method in methods]
    if physics == "specular":
        return chosen
    amplitude = (("echo_model", physics),)
    return [dataclasses.replace(j, scenario=dataclasses.replace(j.scenario, physics=amplitude))
            for j in chosen]


def latency(methods: Sequence[str], physics: str) -> None:
    """Print the office latency-accuracy and local-map error of each method."""
    curves: dict[str, list[dict[str, dict[str, float]]]] = defaultdict(list)
    errors: dict[str, list[tuple[float, float]]] = defaultdict(list)
    for job in _jobs(office.plan(Settings.make()), methods, physics):
        out = run_job(job, run_simulation(job.scenario))
        curves[job.method].append(out["latency_accuracy"])
        errors[job.method].append((out["true_error"]["median"], out["true_error"]["p90"]))
    print("| method | within | right (%) | median s | median m |\n|---|---|---:|---:|---:|")
    for method, per_seed in curves.items():
        for tol in ("0.05", "0.1"):
            share = np.mean([p[tol]["resolved_share"] for p in per_seed])
            seconds = np.mean([p[tol]["median_s"] for p in per_seed])
            metres = np.mean([p[tol]["median_m"] for p in per_seed])
            print(f"| {method} | {float(tol) * 100:.0f} cm | {share:.1f} | {seconds:.2f} | "
                  f"{metres:.2f} |")
    for method, pairs in errors.items():
        median, p90 = np.mean(np.asarray(pairs), axis=0) * 100
        print(f"{method}: local-map true error, mean over seeds: median {median:.2f} cm, "
              f"p90 {p90:.2f} cm")


def passable(methods: Sequence[str], physics: str) -> None:
    """Print the share of approaches passable at 1, 2 and 3 m, overall and per opening."""
    overall: dict[str, dict[str, list[bool]]] = defaultdict(lambda: defaultdict(list))
    per_opening: dict[tuple[str, str, str, str], list[bool]] = defaultdict(list)
    for job in _jobs(openings.plan(Settings.make()), methods, physics):
        out = run_job(job, run_simulation(job.scenario))
        for distance in ("1", "2", "3"):
            if out[distance] is not None:
                overall[job.method][distance].append(out[distance])
                per_opening[(job.method, job.key[1], job.key[2], distance)].append(out[distance])
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
    args = parser.parse_args(argv)
    if not args.skip_latency:
        latency(args.methods, args.physics)
    if not args.skip_openings:
        passable(args.methods, args.physics)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
