import math

import numpy as np
import pytest

from sonarcarve.readings import (
    DEFAULT_BEAM_WIDTH,
    Reading,
    ReadingBatch,
    ReadingsError,
    check_reading,
)


def _batch(**overrides: object) -> ReadingBatch:
    columns: dict[str, object] = {
        "t": [0.0, 0.1, 0.2], "sensor": [0, 1, 2], "x": [0.0, 0.0, 0.1], "y": [0.0, 0.0, 0.0],
        "theta": [0.0, 1.0, 2.0], "range": [1.0, 2.0, 3.0],
    }
    columns.update(overrides)
    return ReadingBatch.from_arrays(**columns)  # type: ignore[arg-type]


def test_default_beam_width_is_the_polaroid_arc() -> None:
    assert math.degrees(DEFAULT_BEAM_WIDTH) == pytest.approx(22.5)


def test_batch_round_trips_through_readings() -> None:
    batch = _batch()
    again = ReadingBatch.from_readings(list(batch))
    assert len(again) == 3
    np.testing.assert_array_equal(again.range, [1.0, 2.0, 3.0])
    assert batch[1][:6] == Reading(0.1, 1, 0.0, 0.0, 1.0, 2.0)[:6]
    assert math.isnan(batch[1].beam_width)


def test_slicing_and_masks_give_batches() -> None:
    batch = _batch()
    assert len(batch[1:]) == 2
    assert batch[np.array([True, False, True])].sensor.tolist() == [0, 2]


@pytest.mark.parametrize(
    ("overrides", "problem"),
    [
        ({"range": [1.0, 0.0, 3.0]}, "row 1, column 'range' must be > 0"),
        ({"range": [1.0, -2.0, 3.0]}, "row 1, column 'range' must be > 0"),
        ({"range": [1.0, 2.0, math.nan]}, "row 2, column 'range' is NaN or infinite"),
        ({"range": [1.0, 2.0, -math.inf]}, "row 2, column 'range' is NaN or infinite"),
        ({"range": [1.0, math.inf, 3.0]},
         "row 1, column 'range' is infinite but 'max_range' is not given"),
        ({"range": [1.0, 2.0, 3.0], "max_range": [math.nan, 1.5, math.nan]},
         "row 1, column 'range' exceeds 'max_range'"),
        ({"max_range": [math.nan, 0.0, math.nan]}, "row 1, column 'max_range' must be a number"),
        # Huge but finite values: they would overflow the geometry or never leave its loops.
        ({"theta": [0.0, 1e20, 0.0]}, "row 1, column 'theta' must lie within ±1,000,000 rad"),
        ({"theta": [0.0, 0.0, -1.7e308]}, "row 2, column 'theta' must lie within ±1,000,000 rad"),
        ({"x": [0.0, 1e300, 0.0]}, "row 1, column 'x' must lie within ±1,000,000 m"),
        ({"y": [0.0, -1.0000001e6, 0.0]}, "row 1, column 'y' must lie within ±1,000,000 m"),
        ({"t": [0.0, 0.5, 2e12]}, "row 2, column 't' must lie within ±1e12 s"),
        ({"range": [1.0, 1.7e308, 3.0]}, "row 1, column 'range' must be at most 10,000 m"),
        ({"max_range": [math.nan, 2e4, math.nan]},
         "row 1, column 'max_range' must be a number in (0, 10,000] metres"),
        ({"x": [math.inf, 0.0, 0.0]}, "row 0, column 'x' is NaN or infinite"),
        ({"t": [0.0, 0.5, 0.2]}, "row 2, column 't' goes backwards in time"),
        ({"beam_width": [0.3, math.pi, 0.3]}, "row 1, column 'beam_width' must lie in [1e-06, pi)"),
        ({"beam_width": [0.3, 0.0, 0.3]}, "row 1, column 'beam_width' must lie in [1e-06, pi)"),
        ({"beam_width": [0.3, 5e-324, 0.3]}, "row 1, column 'beam_width' must lie in [1e-06, pi)"),
        ({"sensor": [0, -1, 2]}, "row 1, column 'sensor' must be >= 0"),
        ({"sensor": [0, 1.5, 2]}, "row 1, column 'sensor' is not a whole number"),
        ({"sensor": [0, 1, math.nan]}, "row 2, column 'sensor' is not a whole number"),
        ({"sensor": [math.inf, 1, 2]}, "row 0, column 'sensor' is not a whole number"),
        # Huge values: a numpy cast would wrap them (with a RuntimeWarning) to a wrong index.
        ({"sensor": [0, 99999999999999999999, 2]}, "row 1, column 'sensor' must be at most"),
        ({"sensor": [0, 1e20, 2]}, "row 1, column 'sensor' must be at most 2147483647"),
        ({"sensor": np.array([0, 2**40, 2])}, "row 1, column 'sensor' must be at most"),
        ({"sensor": np.array([0, 2**63], dtype=np.uint64)[[0, 0, 1]]},
         "row 2, column 'sensor' must be at most"),
        ({"sensor": ["a", "b", "c"]}, "column 'sensor' is not numeric"),
    ],
)
def test_validation_names_row_and_column(overrides: dict[str, object], problem: str) -> None:
    with pytest.raises(ReadingsError) as caught:
        _batch(**overrides)
    assert problem in str(caught.value)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(("overrides", "hint"), [
    # Times since 1970 in milliseconds, a UTM northing, a beam width in degrees: values a
    # logger writes, refused with the way out named.
    ({"t": [1.7e12, 1.7e12 + 40, 1.7e12 + 80]}, "milli-, micro- or nanoseconds since 1970"),
    ({"t": [1.7e15, 1.7e15 + 4e4, 1.7e15 + 8e4]}, "milli-, micro- or nanoseconds since 1970"),
    ({"t": [1.7e18, 1.7e18 + 4e7, 1.7e18 + 8e7]}, "milli-, micro- or nanoseconds since 1970"),
    ({"y": [5.3e6, 5.3e6, 5.3e6]}, "subtract a local origin"),
    ({"x": [0.0, -2e6, 0.0]}, "subtract a local origin"),
    ({"beam_width": [22.5, 22.5, 22.5]}, "22.5 degrees is 0.39"),
])
def test_values_in_a_likely_other_unit_name_it(overrides: dict[str, object], hint: str) -> None:
    with pytest.raises(ReadingsError, match=hint):
        _batch(**overrides)


def test_unknown_beam_width_becomes_the_default() -> None:
    batch = _batch(beam_width=[0.3, math.nan, 0.2]).with_beam_width(0.5)
    assert batch.beam_width.tolist() == [0.3, 0.5, 0.2]


def test_beam_widths_fill_only_unknown_widths() -> None:
    batch = _batch(beam_width=[0.3, math.nan, 0.2])
    assert batch.beam_widths(0.5).tolist() == [0.3, 0.5, 0.2]
    assert math.isnan(batch.beam_width[1])  # the batch itself is unchanged
    assert [r.width_or(0.5) for r in batch] == [0.3, 0.5, 0.2]


def test_concatenate_keeps_order_and_checks_time() -> None:
    batch = _batch()
    both = ReadingBatch.concatenate([batch[:2], batch[2:]])
    np.testing.assert_array_equal(both.t, batch.t)
    with pytest.raises(ReadingsError, match="backwards"):
        ReadingBatch.concatenate([batch[2:], batch[:2]])


def test_concatenate_unvalidated_joins_without_checking() -> None:
    batch = _batch()
    backwards = ReadingBatch.concatenate([batch[2:], batch[:2]], validate=False)
    np.testing.assert_array_equal(backwards.t, np.concatenate([batch.t[2:], batch.t[:2]]))
    assert ReadingBatch.concatenate([], validate=False).t.shape == (0,)


def test_whole_float_sensors_are_accepted_up_to_the_limit() -> None:
    from sonarcarve.readings import MAX_SENSOR

    batch = _batch(sensor=[0.0, 15.0, float(MAX_SENSOR)])
    assert batch.sensor.dtype == np.int64
    assert batch.sensor.tolist() == [0, 15, MAX_SENSOR]


def test_no_echo_readings_need_a_max_range() -> None:
    batch = _batch(range=[1.0, math.inf, 3.0], max_range=[math.nan, 4.0, math.nan])
    assert batch.no_echo.tolist() == [False, True, False]
    assert batch[1].no_echo
    assert not batch[0].no_echo
    assert batch[1].max_range == 4.0
    assert ReadingBatch.from_readings(list(batch)).max_range.tobytes() == batch.max_range.tobytes()
    filled = _batch(range=[1.0, math.inf, 3.0], max_range=[math.nan, 4.0, math.nan]
                    ).with_max_range(5.0)
    np.testing.assert_array_equal(filled.max_range, [5.0, 4.0, 5.0])


def test_check_reading_speaks_like_the_batch() -> None:
    check_reading(Reading(0.0, 0, 0.0, 0.0, 0.0, math.inf, math.nan, 3.0), 0)
    check_reading(Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0, math.nan, 3.0), 0)
    for reading, problem in [
        (Reading(0.0, 0, 0.0, 0.0, 0.0, math.inf), "is infinite but 'max_range' is not given"),
        (Reading(0.0, 0, 0.0, 0.0, 0.0, 4.0, math.nan, 3.0), "exceeds 'max_range'"),
        (Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0, math.nan, -1.0), "'max_range' must be a number"),
        (Reading(0.0, 0, 0.0, 0.0, 0.0, -math.inf), "'range' is NaN or infinite"),
    ]:
        with pytest.raises(ReadingsError, match=f"reading 7, column .*{problem}"):
            check_reading(reading, 7)


@pytest.mark.parametrize("field", ["t", "x", "y", "theta", "range", "max_range"])
@pytest.mark.parametrize("size", [1e20, 1.7e308, -1e300])
def test_bounds_are_the_same_for_one_reading_and_a_batch(field: str, size: float) -> None:
    fields = {"t": 0.0, "sensor": 0, "x": 0.0, "y": 0.0, "theta": 0.0, "range": 1.0,
              "beam_width": math.nan, "max_range": math.nan, field: size}
    batch = ReadingBatch(**{name: np.array([value]) for name, value in fields.items()})
    with pytest.raises(ReadingsError) as batch_error:
        batch.validate("readings", first_id=7)
    with pytest.raises(ReadingsError) as one_error:
        check_reading(Reading(**fields), 7)
    assert str(one_error.value) == str(batch_error.value)
    assert str(one_error.value).startswith(f"reading 7, column '{field}'")


def test_values_at_the_bounds_are_accepted() -> None:
    batch = _batch(t=[-1e12, 0.0, 1e12], x=[1e6, -1e6, 0.0], theta=[1e6, -1e6, 0.0],
                   range=[1e4, 1.0, math.inf], max_range=[1e4, math.nan, 1e4])
    for k, reading in enumerate(batch):
        check_reading(reading, k)


def test_a_batch_built_directly_has_unknown_max_ranges() -> None:
    batch = _batch()
    direct = ReadingBatch(t=batch.t, sensor=batch.sensor, x=batch.x, y=batch.y,
                          theta=batch.theta, range=batch.range, beam_width=batch.beam_width)
    assert direct.max_range.shape == (len(batch),)
    assert np.isnan(direct.max_range).all()


def test_integer_sensors_are_accepted_up_to_the_limit() -> None:
    from sonarcarve.readings import MAX_SENSOR

    limit = 2**31 - 1  # the documented bound, written out
    assert limit == MAX_SENSOR
    batch = _batch(sensor=np.array([0, 15, limit], dtype=np.int64))
    assert batch.sensor.tolist() == [0, 15, limit]
    with pytest.raises(ReadingsError, match=r"row 2, column 'sensor' must be at most 2147483647"):
        _batch(sensor=np.array([0, 15, limit + 1], dtype=np.int64))


@pytest.mark.parametrize("sensor", [np.int64(3), np.int32(3), 3.0])
def test_a_numpy_or_float_sensor_is_held_to_the_same_edges(sensor: object) -> None:
    # A sensor that is no Python int misses check_reading's fast test and is examined field by
    # field: that path must accept exactly what the fast one does (same time as the previous
    # reading: several sensors fire together; a range at the 10 km bound or at max_range).
    check_reading(Reading(5.0, sensor, 0.0, 0.0, 0.0, 1.0), 0, previous_t=5.0)  # type: ignore[arg-type]
    check_reading(Reading(5.0, sensor, 0.0, 0.0, 0.0, 1e4), 0)  # type: ignore[arg-type]
    check_reading(Reading(5.0, sensor, 0.0, 0.0, 0.0, 2.5, math.nan, 2.5), 0)  # type: ignore[arg-type]
    with pytest.raises(ReadingsError, match="reading 4, column 't' goes backwards in time"):
        check_reading(Reading(4.9, sensor, 0.0, 0.0, 0.0, 1.0), 4, previous_t=5.0)  # type: ignore[arg-type]
    with pytest.raises(ReadingsError, match="reading 4, column 'range' must be at most 10,000 m"):
        check_reading(Reading(5.0, sensor, 0.0, 0.0, 0.0, 10_000.001), 4)  # type: ignore[arg-type]


def test_a_bool_is_refused_as_a_sensor_only() -> None:
    """The one rule everywhere: a sensor given as a bool is refused (a mask or flag in the wrong
    place), by check_reading and by a batch alike; a bool coordinate is the number 0 or 1."""
    import pytest

    from sonarcarve.errors import ReadingsError, ReadingTypeError
    from sonarcarve.readings import Reading, ReadingBatch, check_reading

    with pytest.raises(ReadingTypeError, match="column 'sensor' must be a real number, got bool"):
        check_reading(Reading(0.0, True, 0.0, 0.0, 0.0, 1.0), 0)
    with pytest.raises(ReadingsError, match="column 'sensor' holds booleans"):
        ReadingBatch.from_arrays(t=[0.0], sensor=[True], x=[0.0], y=[0.0], theta=[0.0],
                                 range=[1.0])
    check_reading(Reading(0.0, 0, True, 0.0, 0.0, 1.0), 0)  # x = 1
    # A bool coordinate on a reading with another problem: the message names the problem.
    with pytest.raises(ReadingsError, match="column 'range' must be > 0"):
        check_reading(Reading(0.0, 0, True, 0.0, 0.0, -1.0), 0)
    batch = ReadingBatch.from_arrays(t=[0.0], sensor=[0], x=[True], y=[0.0], theta=[0.0],
                                     range=[1.0])
    assert batch.x.tolist() == [1.0]
