"""Running one job: a method over its simulation, recorded, then analysed.

Module-level functions only, so that :func:`run_job` pickles (by name) to Dask workers; it is a
pure function of the job and its simulation, so it gives the same output on any worker.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt

from sonarcarve.lab.analyses import ANALYSES, OPENING_DISTANCES, first_reading_within
from sonarcarve.lab.instrument import record_run
from sonarcarve.lab.plan import Job
from sonarcarve.methods import make_method
from sonarcarve.sim.simulate import Simulation
from sonarcarve.typing import JsonDict

__all__ = ["run_job"]


def run_job(job: Job, sim: Simulation) -> JsonDict:
    """Run ``job`` on its simulation and return the analysis' output (small, picklable), with
    the method's wall time (``seconds``) and the number of readings (``readings``)."""
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
