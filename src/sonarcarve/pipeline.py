"""Run a method over a whole log: the library call behind ``sonarcarve process``."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sonarcarve.maps import GlobalMap
from sonarcarve.methods.base import SonarMethod
from sonarcarve.readings import ReadingBatch

__all__ = ["ProcessResult", "process_readings"]


@dataclass(frozen=True)
class ProcessResult:
    """What a whole-log run produced and measured.

    Attributes
    ----------
    global_map : GlobalMap
        One point per surviving reading (the ``process`` output).
    readings : int
        Readings processed.
    mean_unprocessed_share : float
        Mean over the run of the share of history arcs still unprocessed (Table I), sampled
        every ``sample_every`` readings once the history is full.
    fully_carved, split : int
        Arcs removed by carving, by cause.
    seconds : float
        Wall time spent in the method (sampling for the measures excluded).
    """

    global_map: GlobalMap
    readings: int
    mean_unprocessed_share: float
    fully_carved: int
    split: int
    seconds: float

    @property
    def readings_per_second(self) -> float:
        """Throughput of the method on this log."""
        return self.readings / self.seconds if self.seconds > 0 else float("inf")


def process_readings(
    batch: ReadingBatch,
    method: SonarMethod,
    *,
    sample_every: int | None = None,
    on_progress: Callable[[int], None] | None = None,
) -> ProcessResult:
    """Feed ``batch`` to ``method``, finish it, and return the global map with the measures.

    Parameters
    ----------
    batch : ReadingBatch
        The log, in time order; reading ids are row positions.
    method : SonarMethod
        A fresh method.
    sample_every : int, optional
        How often (in readings) to sample the unprocessed share; default a tenth of the history.
    on_progress : callable, optional
        Called with the number of readings done after each chunk.
    """
    every = sample_every or max(1, method.history.capacity // 10)
    shares: list[float] = []
    seconds = 0.0
    for start in range(0, len(batch), every):
        chunk = batch[start : start + every]
        tic = time.perf_counter()
        method.add_many(chunk, first_id=start)
        seconds += time.perf_counter() - tic
        if start + len(chunk) >= method.history.capacity:
            shares.append(method.measures().unprocessed_share)
        if on_progress is not None:
            on_progress(start + len(chunk))
    measures = method.measures()
    if not shares:
        shares.append(measures.unprocessed_share)
    tic = time.perf_counter()
    global_map = method.finish()
    seconds += time.perf_counter() - tic
    return ProcessResult(
        global_map=global_map,
        readings=len(batch),
        mean_unprocessed_share=float(np.mean(shares)),
        fully_carved=measures.fully_carved,
        split=measures.split,
        seconds=seconds,
    )
