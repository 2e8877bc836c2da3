"""process_readings and process_chunks: the whole-log run behind ``sonarcarve process``.

The centerline method is used wherever points must be known by hand: its point is
``origin + r (cos θ, sin θ)`` (eq. 3.3).
"""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.filters import FilterError, MapFilter, ReadingFilter, filter_readings
from sonarcarve.maps import CallbackSink, GlobalMap, GlobalMapBuilder
from sonarcarve.methods import METHODS, CarvingMethod, CenterlineMethod, Estimates, make_method
from sonarcarve.methods.centerline import CenterlineModel
from sonarcarve.methods.config import MethodConfig
from sonarcarve.pipeline import (
    ProcessError,
    default_sample_every,
    process_chunks,
    process_readings,
)
from sonarcarve.readings import ReadingBatch, ReadingsError
from sonarcarve.typing import SlotArray


def _row(n: int, ranges: list[float] | None = None) -> ReadingBatch:
    """Readings k = 0..n-1: sensor at (0.5 k, 0) looking along +y at range 1 (or ``ranges``)."""
    k = np.arange(n)
    r = np.ones(n) if ranges is None else np.array(ranges)
    return ReadingBatch.from_arrays(t=0.1 * k, sensor=k % 2, x=0.5 * k, y=np.zeros(n),
                                    theta=np.full(n, math.pi / 2), range=r)


def test_global_map_is_every_reading_on_its_axis() -> None:
    result = process_readings(_row(5, [1.0, 2.0, 1.5, 1.0, 3.0]), CenterlineMethod(history_size=2))
    points = result.global_map
    assert type(points) is GlobalMap
    assert points.reading_id.tolist() == [0, 1, 2, 3, 4]
    np.testing.assert_allclose(points.xy, [[0.0, 1.0], [0.5, 2.0], [1.0, 1.5], [1.5, 1.0],
                                           [2.0, 3.0]], atol=1e-12)
    assert points.t.tolist() == pytest.approx([0.0, 0.1, 0.2, 0.3, 0.4])
    assert points.sensor.tolist() == [0, 1, 0, 1, 0]
    assert points.source_labels() == ["centerline"] * 5
    assert result.readings == 5
    assert (result.fully_carved, result.split) == (0, 0)
    assert result.mean_unprocessed_share == 0.0
    assert result.reading_filter is None
    assert result.map_filter is None
    assert result.seconds >= 0.0


def test_global_map_equals_the_method_run_by_hand() -> None:
    rng = np.random.default_rng(5)
    n = 57
    batch = ReadingBatch.from_arrays(t=np.arange(n) * 0.1, sensor=rng.integers(0, 4, n),
                                     x=rng.normal(size=n), y=rng.normal(size=n),
                                     theta=rng.uniform(-3, 3, n), range=rng.uniform(0.2, 5, n))
    result = process_readings(batch, CenterlineMethod(history_size=8), sample_every=5)
    by_hand = CenterlineMethod(history_size=8)
    for reading in batch:
        by_hand.add(reading)
    expected = by_hand.finish()
    for field in ("reading_id", "t", "sensor", "xy", "source", "width", "max_error", "range"):
        np.testing.assert_array_equal(getattr(result.global_map, field), getattr(expected, field))
    # ... and both are eq. 3.3 applied to the input rows.
    np.testing.assert_allclose(result.global_map.xy, np.column_stack(
        (batch.x + batch.range * np.cos(batch.theta), batch.y + batch.range * np.sin(batch.theta))),
        atol=1e-12)
    assert result.global_map.reading_id.tolist() == list(range(n))


def test_fully_carved_arcs_are_counted_and_left_out() -> None:
    # Two echoes from one pose along +x, the second farther: the first arc lies in the second's
    # freespace, so carving removes it (section 3).
    batch = ReadingBatch.from_arrays(t=[0, 1], sensor=[0, 0], x=[0, 0], y=[0, 0], theta=[0, 0],
                                     range=[1.0, 3.0])
    result = process_readings(batch, CarvingMethod(history_size=10))
    assert (result.fully_carved, result.split) == (1, 0)
    assert result.global_map.reading_id.tolist() == [1]
    assert result.readings == 2


def test_empty_log() -> None:
    result = process_readings(ReadingBatch.empty(), CenterlineMethod(history_size=4))
    assert len(result.global_map) == 0
    assert result.readings == 0
    assert result.mean_unprocessed_share == 0.0


# -- sampling the unprocessed share -----------------------------------------------------------


class _FarModel(CenterlineModel):
    """Centerline points, but an arc counts as unprocessed while its range exceeds 2 m."""

    def estimates(self, slots: SlotArray) -> Estimates:
        est = super().estimates(slots)
        return dataclasses.replace(est, processed=self.history.r[slots] <= 2.0)


class _FarMethod(CenterlineMethod):
    name = "far-is-unprocessed"

    def _make_models(self) -> tuple[CenterlineModel]:
        return (_FarModel(self.history),)


# History of 4; "3" marks an unprocessed arc.
RANGES = [1.0, 3.0, 1.0, 1.0, 3.0, 3.0, 1.0, 1.0]


@pytest.mark.parametrize(("every", "expected"), [
    # Samples once the history is full (after reading 4), at the end of each chunk:
    (1, (1 / 4 + 2 / 4 + 2 / 4 + 2 / 4 + 2 / 4) / 5),  # after 4, 5, 6, 7, 8 readings
    (2, (1 / 4 + 2 / 4 + 2 / 4) / 3),  # after 4, 6, 8: rows 0-3, 2-5, 4-7
    (4, (1 / 4 + 2 / 4) / 2),  # after 4, 8
    (3, (2 / 4 + 2 / 4) / 2),  # after 6, 8 (3 < 4: the history is not full yet)
    (None, (1 / 4 + 2 / 4 + 2 / 4 + 2 / 4 + 2 / 4) / 5),  # default: a tenth of 4, so 1
])
def test_unprocessed_share_is_sampled_every_so_many_readings(every: int | None,
                                                              expected: float) -> None:
    result = process_readings(_row(8, RANGES), _FarMethod(history_size=4), sample_every=every)
    assert result.mean_unprocessed_share == pytest.approx(expected, rel=1e-12)
    assert result.readings == 8
    assert len(result.global_map) == 8


def test_default_sampling_is_fine_for_1000_samples_then_every_1009_readings() -> None:
    # History 20: a tenth is 2 readings. The history is full after 20 readings, so the
    # 1,000th sample comes after 20 + 2 * 999 = 2,018; the next step, 1,009 readings, would end
    # past the log, so the last step ends with it.
    calls: list[int] = []
    process_readings(_row(2500), CenterlineMethod(history_size=20), on_progress=calls.append)
    assert calls == [*range(2, 2019, 2), 2500]


def test_coarse_samples_weigh_the_readings_they_stand_for() -> None:
    # History 10: fine step 1 (samples after 10, 11, ..., 1,009 readings: 1,000 of them, share
    # 0 since every range so far is 1), then 1,009 readings a step (after 2,018 and 3,027: the
    # history then holds only far readings, share 1). Weighted: 2 x 1,009 of 3,018 readings.
    n = 3027
    ranges = [1.0 if k < 2008 else 3.0 for k in range(n)]
    result = process_readings(_row(n, ranges), _FarMethod(history_size=10))
    assert result.mean_unprocessed_share == pytest.approx(2018 / 3018, rel=1e-12)


@pytest.mark.parametrize(("history", "every"), [
    (1, 1009), (250, 1009), (10_090, 1009), (10_100, 1013), (100_000, 10_007),
])
def test_default_sample_every_is_the_first_prime_past_a_tenth_of_the_history(
    history: int, every: int,
) -> None:
    assert default_sample_every(history) == every
    assert all(every % k for k in range(2, every))  # prime: every phase of a sensor ring


def test_a_short_log_is_sampled_every_tenth_of_the_history() -> None:
    # History 40: fine step 4; 3,000 readings give fewer than 1,000 samples, so the default
    # is exactly sampling every 4 readings, and differs from sampling every 1,009.
    ranges = [1.0 + (k % 7 == 0) * 2.0 for k in range(3000)]
    batch = _row(3000, ranges)
    default = process_readings(batch, _FarMethod(history_size=40))
    # By hand: after 40, 44, ..., 3,000 readings, the share of the last 40 that read 3.
    far = np.array(ranges) == 3.0
    by_hand = np.mean([np.mean(far[k - 40 : k]) for k in range(40, 3001, 4)])
    assert default.mean_unprocessed_share == by_hand
    fine = process_readings(batch, _FarMethod(history_size=40), sample_every=4)
    assert default.mean_unprocessed_share == fine.mean_unprocessed_share
    coarse = process_readings(batch, _FarMethod(history_size=40), sample_every=1009)
    assert default.mean_unprocessed_share != coarse.mean_unprocessed_share


def test_short_log_samples_the_end() -> None:
    # The history (10) never fills: the share is the one at the end, 2 unprocessed arcs of 3.
    result = process_readings(_row(3, [1.0, 3.0, 3.0]), _FarMethod(history_size=10))
    assert result.mean_unprocessed_share == pytest.approx(2 / 3, rel=1e-12)


# -- progress -----------------------------------------------------------------------------------


def test_progress_counts_input_rows() -> None:
    calls: list[int] = []
    process_readings(_row(10), CenterlineMethod(history_size=4), sample_every=4,
                     on_progress=calls.append)
    assert calls == [4, 8, 10]


def test_progress_counts_dropped_rows_too() -> None:
    # Rows 3 and 7 are beyond max range: the kept rows are 0 1 2 4 5 6 8 9, in chunks of 3:
    # (0 1 2) ends at input row 2, (4 5 6) at row 6, (8 9) at row 9; then the total, 10.
    ranges = [1.0, 1.0, 1.0, 9.0, 1.0, 1.0, 1.0, 9.0, 1.0, 1.0]
    calls: list[int] = []
    result = process_readings(_row(10, ranges), CenterlineMethod(history_size=4), sample_every=3,
                              on_progress=calls.append, reading_filter=ReadingFilter(max_range=5))
    assert calls == [3, 7, 10, 10]
    assert result.global_map.reading_id.tolist() == [0, 1, 2, 4, 5, 6, 8, 9]


# -- filters ------------------------------------------------------------------------------------


def test_reading_filter_report_and_ids() -> None:
    # sensor 0 (even rows): 1.0 1.0 1.0 4.0 4.0; sensor 1 (odd rows): 0.1 1.0 9.0 1.0 1.0
    ranges = [1.0, 0.1, 1.0, 1.0, 1.0, 9.0, 4.0, 1.0, 4.0, 1.0]
    spec = ReadingFilter(max_range=5.0, min_range=0.2, jump_threshold=2.0)
    result = process_readings(_row(10, ranges), CenterlineMethod(history_size=3), sample_every=2,
                              reading_filter=spec)
    report = result.reading_filter
    assert report is not None
    # row 1 too near, row 5 too far, row 6 (1.0 -> 4.0) jumps; row 8 agrees with row 6.
    assert (report.total, report.too_near, report.too_far, report.jumps) == (10, 1, 1, 1)
    assert report.kept == 7
    assert result.readings == 7
    points = result.global_map
    assert points.reading_id.tolist() == [0, 2, 3, 4, 7, 8, 9]  # input rows, not renumbered
    np.testing.assert_allclose(points.xy, [[0.0, 1.0], [1.0, 1.0], [1.5, 1.0], [2.0, 1.0],
                                           [3.5, 1.0], [4.0, 4.0], [4.5, 1.0]], atol=1e-12)


def test_map_filter_report() -> None:
    # A row of points 0.5 m apart at y = 1, but row 3 far away at y = 8 and row 5 inaccurate.
    ranges = [1.0, 1.0, 1.0, 8.0, 1.0, 1.0, 1.0]
    batch = _row(7, ranges)
    width = np.where(np.arange(7) == 5, 3.0, 0.1)  # row 5: a wide beam, a large max_error
    batch = ReadingBatch.from_arrays(t=batch.t, sensor=batch.sensor, x=batch.x, y=batch.y,
                                     theta=batch.theta, range=batch.range, beam_width=width)
    spec = MapFilter(max_error=0.5, outlier_radius=0.6, outlier_neighbours=1)
    result = process_readings(batch, CenterlineMethod(history_size=3), map_filter=spec)
    report = result.map_filter
    assert report is not None
    # Row 5: 2 sin(3/4) = 1.36 > 0.5 dropped first; then row 3 is alone, and rows 4 and 6
    # (1 m apart once row 5 is gone) have no neighbour within 0.6 m.
    assert (report.total, report.max_error, report.outliers, report.kept) == (7, 1, 3, 3)
    assert result.global_map.reading_id.tolist() == [0, 1, 2]
    assert result.readings == 7  # map filters drop points, not readings


# -- bad arguments ------------------------------------------------------------------------------


@pytest.mark.parametrize("every", [0, -1])
def test_bad_sample_every(every: int) -> None:
    with pytest.raises(ProcessError, match="sample_every") as info:
        process_readings(_row(5), CenterlineMethod(history_size=4), sample_every=every)
    assert isinstance(info.value, SonarcarveError)


def test_used_method_is_refused() -> None:
    method = CenterlineMethod(history_size=4)
    process_readings(_row(3), method)
    with pytest.raises(ProcessError, match="fresh method") as info:
        process_readings(_row(3), method)
    assert isinstance(info.value, SonarcarveError)


def test_bad_filter_parameters_are_sonarcarve_errors() -> None:
    with pytest.raises(FilterError) as info:
        ReadingFilter(jump_threshold=-1.0)
    assert isinstance(info.value, SonarcarveError)
    with pytest.raises(FilterError) as info:
        MapFilter(outlier_radius=0.0)
    assert isinstance(info.value, SonarcarveError)


# -- a log in batches ---------------------------------------------------------------------------


def _noisy_log(n: int, seed: int) -> ReadingBatch:
    """Four sensors, ranges with spikes (jumps), some too near or too far."""
    rng = np.random.default_rng(seed)
    r = rng.uniform(0.5, 2.0, n)
    r[rng.random(n) < 0.15] = rng.uniform(0.05, 8.0)
    return ReadingBatch.from_arrays(t=np.arange(n) * 0.05, sensor=rng.integers(0, 4, n),
                                    x=0.02 * np.arange(n), y=rng.normal(0, 0.1, n),
                                    theta=rng.uniform(-3, 3, n), range=r)


def _cuts(n: int, rng: np.random.Generator) -> list[slice]:
    edges = np.unique(np.concatenate(([0, n], rng.integers(0, n + 1, rng.integers(1, 12)))))
    # Empty batches too, first and last.
    return [slice(0, 0), *(slice(a, b) for a, b in itertools.pairwise(edges.tolist())),
            slice(n, n)]


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("spec", [
    None,
    ReadingFilter(jump_threshold=0.4),
    ReadingFilter(max_range=3.0, min_range=0.2, jump_threshold=0.4),
    ReadingFilter(max_range=3.0),
])
def test_batches_give_what_the_whole_log_gives(seed: int, spec: ReadingFilter | None) -> None:
    batch = _noisy_log(131, seed)
    whole_calls: list[int] = []
    whole = process_readings(batch, CarvingMethod(history_size=12), sample_every=5,
                             on_progress=whole_calls.append, reading_filter=spec)
    cut_calls: list[int] = []
    cuts = _cuts(len(batch), np.random.default_rng(seed))
    cut = process_chunks((batch[part] for part in cuts), CarvingMethod(history_size=12),
                         sample_every=5, on_progress=cut_calls.append, reading_filter=spec)
    assert cut_calls == whole_calls
    assert cut.readings == whole.readings
    assert cut.reading_filter == whole.reading_filter
    assert cut.mean_unprocessed_share == whole.mean_unprocessed_share
    assert (cut.fully_carved, cut.split) == (whole.fully_carved, whole.split)
    for field in ("reading_id", "t", "sensor", "xy", "source", "width", "max_error", "range"):
        np.testing.assert_array_equal(getattr(cut.global_map, field),
                                      getattr(whole.global_map, field))
    if spec is not None and spec.jump_threshold is not None:
        assert whole.reading_filter is not None
        assert whole.reading_filter.jumps > 0
    # ... and the whole log is what the library's batch filter and the method make of it.
    by_hand = CarvingMethod(history_size=12)
    ids = np.arange(len(batch))
    if spec is not None:
        kept = filter_readings(batch, spec)
        batch, ids = kept.batch, kept.ids
    for reading, reading_id in zip(batch, ids.tolist(), strict=True):
        by_hand.add(reading, reading_id)
    np.testing.assert_array_equal(whole.global_map.xy, by_hand.finish().xy)


def test_jump_filter_across_a_cut_compares_with_the_sensors_last_reading() -> None:
    # Sensor 0: 1.0 | 3.0 (jumps) 3.0 (agrees with the 3.0 that jumped); sensor 1 starts after
    # the cut; the cut falls between rows 0 and 1, and row 2 of sensor 1 is its first reading.
    batch = ReadingBatch.from_arrays(t=[0, 1, 2, 3], sensor=[0, 0, 1, 0], x=[0] * 4, y=[0] * 4,
                                     theta=[0] * 4, range=[1.0, 3.0, 9.0, 3.0])
    result = process_chunks([batch[:1], batch[1:]], CenterlineMethod(history_size=4),
                            reading_filter=ReadingFilter(jump_threshold=0.5))
    assert result.global_map.reading_id.tolist() == [0, 2, 3]
    assert result.reading_filter is not None
    assert result.reading_filter.jumps == 1


def test_a_bad_batch_names_the_reading_by_its_id() -> None:
    good = _row(6)
    backwards = ReadingBatch(**{**{name: getattr(good, name) for name in (
        "sensor", "x", "y", "theta", "range", "beam_width")}, "t": good.t[::-1].copy()})
    with pytest.raises(ReadingsError, match=r"reading 7, column 't' goes backwards in time"):
        process_chunks([good, backwards], CenterlineMethod(history_size=4), sample_every=2)


def test_process_chunks_checks_its_arguments_as_process_readings_does() -> None:
    with pytest.raises(ProcessError, match="sample_every"):
        process_chunks([_row(3)], CenterlineMethod(history_size=4), sample_every=0)
    method = CenterlineMethod(history_size=4)
    process_chunks(iter([_row(3)]), method)
    with pytest.raises(ProcessError, match="fresh method"):
        process_chunks([_row(3)], method)


# -- the global map to a sink -------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(METHODS))
@pytest.mark.parametrize("spec", [None, ReadingFilter(max_range=3.0, min_range=0.2,
                                                      jump_threshold=0.4)])
def test_a_sink_gets_the_map_the_result_would_hold(name: str, spec: ReadingFilter | None) -> None:
    batch = _noisy_log(157, 3)
    config = MethodConfig(history_size=12)
    whole = process_readings(batch, make_method(name, config), sample_every=5,
                             reading_filter=spec)
    blocks: list[GlobalMap] = []
    cuts = _cuts(len(batch), np.random.default_rng(3))
    streamed = process_chunks((batch[part] for part in cuts), make_method(name, config),
                              sample_every=5, reading_filter=spec,
                              sink=CallbackSink(blocks.append))
    assert len(streamed.global_map) == 0  # the sink has it
    assert streamed.points == whole.points == len(whole.global_map) > 0
    assert (streamed.readings, streamed.reading_filter, streamed.mean_unprocessed_share) == (
        whole.readings, whole.reading_filter, whole.mean_unprocessed_share)
    points = GlobalMap.concatenate(blocks)
    for field in ("reading_id", "t", "sensor", "xy", "source", "width", "max_error", "range",
                  "confidence"):
        np.testing.assert_array_equal(getattr(points, field), getattr(whole.global_map, field))
    if spec is not None:  # ids are input rows, with the gaps the filters left
        assert np.any(np.diff(points.reading_id) > 1)


def test_a_sink_keeps_nothing_in_memory(monkeypatch: pytest.MonkeyPatch) -> None:
    def refuse(self: GlobalMapBuilder, points: GlobalMap) -> None:
        raise AssertionError("the in-memory builder was used")

    monkeypatch.setattr(GlobalMapBuilder, "commit", refuse)
    seen: list[int] = []
    result = process_readings(_row(50), CenterlineMethod(history_size=4),
                              sink=CallbackSink(lambda points: seen.extend(points.reading_id)))
    assert seen == list(range(50))
    assert result.points == 50


def test_a_sink_and_map_filters_do_not_go_together() -> None:
    method = CenterlineMethod(history_size=4)
    with pytest.raises(ProcessError, match="map filters need the whole global map"):
        process_readings(_row(5), method, map_filter=MapFilter(max_error=0.1),
                         sink=CallbackSink(print))
    assert method.readings == 0


def test_points_counts_the_map_after_the_map_filters() -> None:
    result = process_readings(_row(5), CenterlineMethod(history_size=2))
    assert result.points == len(result.global_map) == 5
    result = process_readings(_noisy_log(80, 0), CarvingMethod(history_size=12),
                              map_filter=MapFilter(max_error=0.05))
    assert result.map_filter is not None
    assert result.points == len(result.global_map) == result.map_filter.total - (
        result.map_filter.max_error + result.map_filter.outliers)
