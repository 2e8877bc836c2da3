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
needs it (in worker processes with ``Settings.jobs > 1``) and summarises each experiment;
:func:`sonarcarve.lab.report.write_outputs` writes ``results.json``, the figures and the
Markdown. ``sonarcarve experiments`` and ``make experiments`` go through :data:`EXPERIMENTS`
alone.
"""

from __future__ import annotations

import multiprocessing
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
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
from sonarcarve.lab.experiments.jobs import run_one
from sonarcarve.lab.plan import Job, Settings
from sonarcarve.lab.scenarios import ExperimentError, Scenario, run_simulation
from sonarcarve.sim.simulate import Simulation
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

#: ``on_progress(stage, done, total)`` with stage ``"simulating"`` or ``"mapping"``.
ProgressCallback = Callable[[str, int, int], None]


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
    sims, outputs = _run_jobs(settings, jobs, on_progress or (lambda stage, done, total: None))
    run = ExperimentResults(settings, simulations=len(sims), jobs=len(jobs),
                            readings_simulated=sum(len(sim.readings) for sim in sims.values()))
    for name in names:
        own = {job.key: outputs[job.key] for job in plans[name]}
        run.results[name], run.artifacts[name] = EXPERIMENTS[name].summarise(settings, own)
    run.seconds = time.perf_counter() - tic
    return run


def _run_jobs(settings: Settings, jobs: list[Job], report: ProgressCallback) -> tuple[
        dict[Scenario, Simulation], dict[tuple[Any, ...], JsonDict]]:
    """Simulate every distinct scenario once, then run every job on its simulation."""
    scenarios = list(dict.fromkeys(job.scenario for job in jobs))
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
        out_list = (pool.map(run_one, args, chunksize=1) if pool is not None
                    else map(run_one, args))
        outputs: dict[tuple[Any, ...], JsonDict] = {}
        for i, (job, out) in enumerate(zip(jobs, out_list, strict=True)):
            outputs[job.key] = out
            report("mapping", i + 1, len(jobs))
    finally:
        if pool is not None:
            pool.shutdown()
    return sims, outputs
