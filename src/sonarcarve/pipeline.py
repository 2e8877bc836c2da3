"""Run a method over a whole log: the library call behind ``sonarcarve process``."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from sonarcarve.errors import SonarcarveError
from sonarcarve.filters import (
    MapFilter,
    MapFilterReport,
    ReadingFilter,
    ReadingFilterReport,
    filter_map,
    filter_readings,
)
from sonarcarve.maps import GlobalMap
from sonarcarve.methods.base import SonarMethod
from sonarcarve.readings import ReadingBatch

__all__ = ["ProcessError", "ProcessResult", "process_readings"]


class ProcessError(SonarcarveError, ValueError):
    """A bad argument to :func:`process_readings` (a sampling step < 1, a used method)."""


@dataclass(frozen=True)
class ProcessResult:
    """What a whole-log run produced and measured.

    Attributes
    ----------
    global_map : GlobalMap
        One point per surviving reading (the ``process`` output).
    readings : int
        Readings processed (after the reading filters, if any).
    mean_unprocessed_share : float
        Mean over the run of the share of history arcs still unprocessed (Table I), sampled
        every ``sample_every`` readings once the history is full.
    fully_carved, split : int
        Arcs removed by carving, by cause.
    seconds : float
        Wall time spent in the method (sampling for the measures excluded).
    reading_filter : ReadingFilterReport or None
        What the reading filters dropped (None if none ran).
    map_filter : MapFilterReport or None
        What the map filters dropped from the global map (None if none ran).
    """

    global_map: GlobalMap
    readings: int
    mean_unprocessed_share: float
    fully_carved: int
    split: int
    seconds: float
    reading_filter: ReadingFilterReport | None = None
    map_filter: MapFilterReport | None = None

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
    reading_filter: ReadingFilter | None = None,
    map_filter: MapFilter | None = None,
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
        Called with the number of input rows done after each chunk.
    reading_filter : ReadingFilter, optional
        Reading filters applied before the method; kept readings keep their input row as id.
    map_filter : MapFilter, optional
        Map filters applied to the finished global map.

    Raises
    ------
    ProcessError
        ``sample_every`` < 1, or a method that has already been fed readings.
    """
    if sample_every is not None and sample_every < 1:
        # 0 would silently mean the default, and a negative step would process nothing.
        msg = f"sample_every must be at least 1 reading, got {sample_every}"
        raise ProcessError(msg)
    if method.readings:
        msg = (f"process_readings needs a fresh method; this {method.name} method has "
               f"already been fed {method.readings} readings")
        raise ProcessError(msg)
    ids = None
    filter_report = None
    if reading_filter is not None:
        filtered = filter_readings(batch, reading_filter)
        ids, filter_report = filtered.ids, filtered.report
        batch = filtered.batch
    every = max(1, method.history.capacity // 10) if sample_every is None else sample_every
    shares: list[float] = []
    seconds = 0.0
    for start in range(0, len(batch), every):
        chunk = batch[start : start + every]
        tic = time.perf_counter()
        if ids is None:
            method.add_many(chunk, first_id=start)
        else:
            for reading, reading_id in zip(chunk, ids[start : start + every].tolist(), strict=True):
                method.add(reading, reading_id)
        seconds += time.perf_counter() - tic
        if start + len(chunk) >= method.history.capacity:
            shares.append(method.measures().unprocessed_share)
        if on_progress is not None:  # progress counts input rows, dropped ones included
            done = start + len(chunk)
            on_progress(done if ids is None else int(ids[done - 1]) + 1)
    if on_progress is not None and filter_report is not None:
        on_progress(filter_report.total)
    measures = method.measures()
    if not shares:
        shares.append(measures.unprocessed_share)
    tic = time.perf_counter()
    global_map = method.finish()
    seconds += time.perf_counter() - tic
    map_report = None
    if map_filter is not None:
        kept = filter_map(global_map, map_filter)
        global_map, map_report = kept.points, kept.report
    return ProcessResult(
        global_map=global_map,
        readings=len(batch),
        mean_unprocessed_share=float(np.mean(shares)),
        fully_carved=measures.fully_carved,
        split=measures.split,
        seconds=seconds,
        reading_filter=filter_report,
        map_filter=map_report,
    )
