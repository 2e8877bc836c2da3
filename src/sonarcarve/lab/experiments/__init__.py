"""The experiments: one registry, one module per experiment, one runner.

Every experiment (:class:`~sonarcarve.lab.experiments.base.Experiment`) plans method runs
(*jobs*: one sonar method on one simulated log, then one analysis, see
:mod:`sonarcarve.lab.plan` and :mod:`sonarcarve.lab.analyses`), summarises their outputs into
a typed result, draws its figures and writes its part of ``docs/RESULTS.md``:

* ``office`` (:mod:`~sonarcarve.lab.experiments.office`): the paper's Table I, Fig. 10-13 and
  the fully carved share (sections 5-B, 5-C) on the simulated office tour, several seeds; plus
  what the paper could not measure without ground truth: the true error of the maps and, per
  wall patch, how long after it came into view the local map had it right.
* ``t-junction`` (:mod:`~sonarcarve.lab.experiments.t_junction`): Fig. 4, how far before the
  facing wall each method's local map first shows it.
* ``openings`` (:mod:`~sonarcarve.lab.experiments.openings`): Fig. 2 and 9, whether each local
  map shows narrow doors and side openings passable 1, 2 and 3 m before them.
* ``sensitivity`` (:mod:`~sonarcarve.lab.experiments.sensitivity`): history length, ε, φ, ψ,
  speed and range noise against error, latency and the fully carved share.
* ``polling``, ``filters``, ``real-log``, ``odometry`` (the paper's appendices and Fig. 7;
  :mod:`~sonarcarve.lab.experiments.polling` ...): these plan no jobs and run in
  ``summarise``.

:func:`run_experiments` makes each distinct simulation once, shares it between every job that
needs it and summarises each experiment. The simulations and jobs run on a
:class:`~sonarcarve.runner.Runner`: this process, a local Dask cluster of
``Settings.jobs`` workers, or any Dask scheduler; every job is a pure function of its inputs
and its output is keyed by the job, so the numbers are the same on any of them;
:func:`sonarcarve.lab.report.write_outputs` writes ``results.json``, the figures and the
Markdown. ``sonarcarve experiments`` and ``make experiments`` go through :data:`EXPERIMENTS`
alone.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from sonarcarve.lab.experiments import (
    filters,
    odometry,
    office,
    openings,
    polling,
    real_log,
    sensitivity,
    t_junction,
)
from sonarcarve.lab.experiments.base import Artifacts, Experiment
from sonarcarve.lab.experiments.jobs import run_job
from sonarcarve.lab.plan import Job, Settings
from sonarcarve.lab.scenarios import ExperimentError, Scenario, run_simulation
from sonarcarve.runner import ProgressCallback, Ref, Runner, RunnerSpec, Task, open_runner
from sonarcarve.typing import JsonDict

__all__ = [
    "EXPERIMENTS",
    "Experiment",
    "ExperimentError",
    "ExperimentResults",
    "ProgressCallback",
    "Settings",
    "run_experiments",
]

#: Every experiment by name, in the order they run and their results are written.
EXPERIMENTS: dict[str, Experiment[Any]] = {
    e.name: e for e in (office.EXPERIMENT, t_junction.EXPERIMENT, openings.EXPERIMENT,
                        sensitivity.EXPERIMENT, polling.EXPERIMENT, filters.EXPERIMENT,
                        real_log.EXPERIMENT, odometry.EXPERIMENT)
}

@dataclass
class ExperimentResults:
    """What :func:`run_experiments` produced.

    Attributes
    ----------
    settings : Settings
        The run's settings.
    results : dict
        Each experiment's typed result, by experiment name, in run order.
    artifacts : dict
        Each experiment's arrays for its figures, by experiment name (never written to JSON).
    seconds : float
        Wall time of simulating, mapping and summarising (figures excluded).
    simulations : int
        Distinct simulations made.
    jobs : int
        Method runs.
    readings_simulated : int
        Readings over all simulations.
    """

    settings: Settings = field(default_factory=Settings)
    results: dict[str, Any] = field(default_factory=dict)
    artifacts: dict[str, Artifacts] = field(default_factory=dict)
    seconds: float = 0.0
    simulations: int = 0
    jobs: int = 0
    readings_simulated: int = 0


def run_experiments(
    settings: Settings,
    only: Sequence[str] | None = None,
    on_progress: ProgressCallback | None = None,
    runner: Runner | None = None,
) -> ExperimentResults:
    """Run the chosen experiments (all by default) and summarise them.

    Parameters
    ----------
    settings : Settings
        Sizes and seeds; ``settings.jobs`` is the worker count recorded with the results and,
        without ``runner``, the size of the local Dask cluster (1: this process, no Dask).
    only : sequence of str, optional
        Experiment names (keys of :data:`EXPERIMENTS`).
    on_progress : callable, optional
        ``on_progress(stage, done, total)`` with stage ``"simulating"`` or ``"mapping"``.
    runner : Runner, optional
        Where the simulations and method runs go (:func:`~sonarcarve.runner.open_runner`:
        this process, a local cluster or a Dask scheduler); left open. The results do not
        depend on it.

    Raises
    ------
    ExperimentError
        For an unknown experiment name.
    SchedulerUnreachableError
        When the runner's scheduler does not answer.
    """
    names = list(EXPERIMENTS) if not only else list(only)
    for name in names:
        if name not in EXPERIMENTS:
            msg = f"unknown experiment {name!r}; choose from {', '.join(EXPERIMENTS)}"
            raise ExperimentError(msg)
    tic = time.perf_counter()
    plans = {name: EXPERIMENTS[name].plan(settings) for name in names}
    jobs = [job for name in names for job in plans[name]]
    report = on_progress or (lambda stage, done, total: None)
    if runner is None:
        with open_runner(RunnerSpec(workers=settings.jobs)) as own:
            outputs, readings = _run_jobs(own, jobs, report)
    else:
        outputs, readings = _run_jobs(runner, jobs, report)
    run = ExperimentResults(settings, simulations=len(readings), jobs=len(jobs),
                            readings_simulated=sum(readings.values()))
    for name in names:
        own_outputs = {job.key: outputs[job.key] for job in plans[name]}
        run.results[name], run.artifacts[name] = EXPERIMENTS[name].summarise(settings,
                                                                             own_outputs)
    run.seconds = time.perf_counter() - tic
    return run


def _run_jobs(runner: Runner, jobs: list[Job], report: ProgressCallback) -> tuple[
        dict[tuple[Any, ...], JsonDict], dict[Scenario, int]]:
    """Simulate every distinct scenario once, then run every job on its simulation.

    Returns each job's output by job key and each simulation's number of readings; the
    simulations themselves stay where they were made (on the workers, with Dask).
    """
    scenarios = list(dict.fromkeys(job.scenario for job in jobs))
    index = {scenario: i for i, scenario in enumerate(scenarios)}
    tasks = [Task(run_simulation, (scenario,), "simulating", gather=False)
             for scenario in scenarios]
    tasks += [Task(run_job, (job, Ref(index[job.scenario])), "mapping") for job in jobs]
    outputs: dict[tuple[Any, ...], JsonDict] = {}
    readings: dict[Scenario, int] = {}
    first = len(scenarios)
    for i, out in runner.run(tasks, on_progress=report):
        job = jobs[i - first]
        outputs[job.key] = out
        readings[job.scenario] = int(out["readings"])
    return outputs, readings
