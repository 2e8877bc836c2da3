"""record_run on tiny hand-made logs whose history contents are known in advance."""

from __future__ import annotations

import math

import numpy as np

from sonarcarve.lab.instrument import (
    full_history_samples,
    record_run,
    sample_points,
    unprocessed_percent,
)
from sonarcarve.methods.base import ArcFate
from sonarcarve.methods.carving import CarvingMethod
from sonarcarve.methods.centerline import CenterlineMethod
from sonarcarve.readings import ReadingBatch


def _straight_log(n: int) -> ReadingBatch:
    """A sensor at (0.1 k, 0) looking along +y at a wall 2 m away."""
    k = np.arange(n)
    return ReadingBatch.from_arrays(t=0.1 * k, sensor=np.zeros(n), x=0.1 * k, y=np.zeros(n),
                                    theta=np.full(n, math.pi / 2), range=np.full(n, 2.0))


def test_snapshots_hold_the_live_history() -> None:
    batch = _straight_log(5)
    rec = record_run(batch, CenterlineMethod(history_size=3), sample_after=[5, 2, 2, 9])
    # Duplicates and counts past the end are dropped; snapshots come in reading order.
    assert rec.sample_readings.tolist() == [2, 5]
    assert rec.snapshot(0).reading_id.tolist() == [0, 1]
    assert rec.snapshot(1).reading_id.tolist() == [2, 3, 4]
    np.testing.assert_allclose(rec.sample_times(batch), [0.1, 0.4])
    # Centerline: every point on the axis at range 2, i.e. at (x, 2).
    pts = sample_points(rec)
    np.testing.assert_allclose(pts.xy[:, 1], 2.0)
    assert pts.processed.all()


def test_final_table_has_every_reading_once() -> None:
    batch = _straight_log(7)
    rec = record_run(batch, CenterlineMethod(history_size=3))
    assert rec.final.reading_id.tolist() == list(range(7))
    assert (rec.final.sample == -1).all()
    assert len(rec.samples) == 0
    assert len(rec.global_map) == 7


def test_fully_carved_arc_is_dead_in_its_final_row() -> None:
    # Reading 1 looks the same way from the same place but 1 m farther: its freespace holds the
    # whole arc of reading 0, which must be fully carved.
    batch = ReadingBatch.from_arrays(t=[0.0, 0.1], sensor=[0, 0], x=[0.0, 0.0], y=[0.0, 0.0],
                                     theta=[0.0, 0.0], range=[1.0, 2.0])
    rec = record_run(batch, CarvingMethod(history_size=10), sample_after=[2])
    first = rec.final.select(rec.final.reading_id == 0)
    assert not first.alive[0]
    assert first.processed[0]
    assert first.removal[0] != ArcFate.ALIVE
    assert rec.counters["fully_carved"] == 1
    assert rec.final.alive.tolist() == [False, True]
    # The snapshot still lists both rows (the dead one included) but one map point.
    assert len(rec.snapshot(0)) == 2
    assert len(sample_points(rec)) == 1


# -- Table I's sampling and measure --------------------------------------------------------------

def test_full_history_samples_and_local_map_by_hand() -> None:
    batch = _straight_log(8)
    rec = record_run(batch, CenterlineMethod(history_size=3), sample_after=[2, 3, 4, 5, 6, 8])
    # Full once 3 readings are in: snapshots after 3, 4, 5, 6 and 8 readings (indices 1-5).
    full = full_history_samples(rec, 3)
    assert sorted(set(full.sample.tolist())) == [1, 2, 3, 4, 5]
    assert len(full) == 5 * 3
    # Regular sampling every 2 readings: after 2, 4, 6 and 8 (indices 0, 2, 4, 5); of those,
    # full: 4, 6, 8.
    assert sorted(set(full_history_samples(rec, 3, every=2).sample.tolist())) == [2, 4, 5]
    # Never full: every (regular) snapshot.
    assert sorted(set(full_history_samples(rec, 100, every=2).sample.tolist())) == [0, 2, 4, 5]
    local = rec.local_map(2)
    assert local.reading_id.tolist() == [1, 2, 3]
    assert local.alive.all()


def test_removed_arcs_count_as_processed_unless_live_only() -> None:
    # Reading 0's arc is fully carved by reading 1 (see above); reading 1 is never carved.
    batch = ReadingBatch.from_arrays(t=[0.0, 0.1], sensor=[0, 0], x=[0.0, 0.0], y=[0.0, 0.0],
                                     theta=[0.0, 0.0], range=[1.0, 2.0])
    rec = record_run(batch, CarvingMethod(history_size=10), sample_after=[2])
    rows = rec.snapshot(0)
    assert unprocessed_percent(rows) == 50.0  # the removed arc counts as processed
    assert unprocessed_percent(rows, live_only=True) == 100.0  # the paper's history drops it
    assert math.isnan(unprocessed_percent(rows.select(np.zeros(2, dtype=bool))))
