"""Likely mistakes named: unit and layout warnings for readings that parse."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.io.sanity import beam_width_mistake, csv_shape_hint, likely_mistakes
from sonarcarve.readings import ReadingBatch


def _batch(theta: float = 0.5, rng: float = 2.0, width: float = 0.39) -> ReadingBatch:
    n = 5
    return ReadingBatch.from_arrays(t=np.arange(n), sensor=np.zeros(n, int), x=np.zeros(n),
                                    y=np.zeros(n), theta=np.full(n, theta),
                                    range=np.full(n, rng), beam_width=np.full(n, width))


def test_a_clean_log_has_no_warning() -> None:
    assert likely_mistakes(_batch()) == []


@pytest.mark.parametrize(
    ("batch", "words"),
    [
        (_batch(theta=90.0), "is it in degrees?"),
        (_batch(theta=-7.0), "is it in degrees?"),
        (_batch(rng=350.0), "is it in centimetres?"),
        (_batch(rng=3500.0), "is it in millimetres?"),
        (_batch(width=math.radians(0.39)), "is it in another unit?"),
    ],
)
def test_each_likely_mistake_is_one_line(batch: ReadingBatch, words: str) -> None:
    (warning,) = likely_mistakes(batch)
    assert words in warning
    assert "\n" not in warning


@pytest.mark.parametrize(("metres", "unit"), [(0.8382, "millimetres"), (0.8382, "centimetres"),
                                              (2.29, "millimetres"), (2.29, "centimetres"),
                                              (0.45, "millimetres"), (3.5, "centimetres")])
def test_short_indoor_ranges_name_their_unit(metres: float, unit: str) -> None:
    # Median ranges of real and simulated logs (the T junction 0.84 m, roboND 2.29 m) written
    # in another unit: 838 mm was called centimetres and 84 cm passed as metres.
    scale = {"millimetres": 1000.0, "centimetres": 100.0}[unit]
    (warning,) = likely_mistakes(_batch(rng=metres * scale))
    assert f"is it in {unit}?" in warning


def test_a_long_sonar_range_in_metres_is_no_mistake() -> None:
    assert likely_mistakes(_batch(rng=10.0)) == []  # sonars reach 3-10 m


def _limited(at_limit: int, echoes: int = 100, limit: float = 6.477) -> ReadingBatch:
    """``echoes`` echoes with a max_range column, ``at_limit`` of them at exactly the limit,
    and three silent firings (inf), which are no echoes."""
    r = np.concatenate([np.full(at_limit, limit), np.full(echoes - at_limit, 2.0),
                        np.full(3, np.inf)])
    n = len(r)
    return ReadingBatch.from_arrays(t=np.arange(n), sensor=np.zeros(n, int), x=np.zeros(n),
                                    y=np.zeros(n), theta=np.zeros(n), range=r,
                                    max_range=np.full(n, limit))


def test_echoes_at_exactly_their_max_range_are_named_from_five_percent() -> None:
    # A Gazebo-style log (max_range for "nothing heard") written to CSV: 5 of 100 is the
    # threshold; 4 of 100 is a real echo's rare landing on the limit.
    (warning,) = likely_mistakes(_limited(5))
    assert warning.startswith("5 of 100 echoes checked read exactly their max_range")
    assert "write those rows as range inf" in warning
    assert likely_mistakes(_limited(4)) == []
    assert likely_mistakes(_limited(0, echoes=0)) == []  # only silences: no echo to judge
    assert likely_mistakes(_batch()) == []  # no max_range column


def test_without_a_max_range_column_a_clamped_longest_range_is_named() -> None:
    # Gazebo's "nothing heard" as 5.0 m in a CSV of t,sensor,x,y,theta,range only: 10 of 100
    # echoes at the longest range, well above the 2 m median. Not: 4 of 100, a longest range
    # near the median (a long hall), or a log of fewer than 100 echoes.
    def log(clamped: int, others: float = 2.0, echoes: int = 100) -> ReadingBatch:
        r = np.concatenate([np.full(clamped, 5.0), np.full(echoes - clamped, others)])
        n = len(r)
        return ReadingBatch.from_arrays(t=np.arange(n), sensor=np.zeros(n, int),
                                        x=np.zeros(n), y=np.zeros(n), theta=np.zeros(n),
                                        range=r)

    (warning,) = likely_mistakes(log(10))
    assert warning.startswith("10 of 100 echoes checked read exactly the log's longest range, "
                              "5 m")
    assert likely_mistakes(log(4)) == []
    assert likely_mistakes(log(10, others=4.0)) == []
    assert likely_mistakes(log(10, echoes=99)) == []


def test_an_echo_written_in_text_beside_a_float32_max_range_is_at_it() -> None:
    # 6.477 as text, max_range kept as float32 (6.47700023651123...): the same limit.
    b = _limited(5, limit=6.477)
    b = ReadingBatch.from_arrays(t=b.t, sensor=b.sensor, x=b.x, y=b.y, theta=b.theta,
                                 range=b.range,
                                 max_range=np.full(len(b), float(np.float32(6.477))))
    (warning,) = likely_mistakes(b)
    assert warning.startswith("5 of 100 echoes checked")


def test_the_unit_warning_starts_at_a_median_of_20_metres() -> None:
    # A 0.3 m median written in centimetres (30) is named; 19 m in metres is a long sonar.
    (warning,) = likely_mistakes(_batch(rng=30.0))
    assert "is it in centimetres?" in warning
    assert likely_mistakes(_batch(rng=19.0)) == []


def test_beam_width_in_radians_given_as_degrees() -> None:
    assert beam_width_mistake(0.39) is not None
    assert beam_width_mistake(15.0) is None


@pytest.mark.parametrize(
    ("line", "words"),
    [
        ("t;sensor;x;y;theta;range;beam_width", "separated by ';'"),
        ("t\tsensor\tx\ty\ttheta\trange", "separated by tabs"),
        ("\ufeffT,SENSOR,X,Y,THETA,RANGE", "case-sensitive"),
        ("t,sensor,x,y,theta,range", None),
        ("", None),
        ("1;2", None),
    ],
)
def test_csv_shape_hint(line: str, words: str | None) -> None:
    hint = csv_shape_hint(line)
    assert (hint is None) if words is None else (hint is not None and words in hint)


def _driving(speed: float, scale: float = 1.0) -> ReadingBatch:
    """Two sensors on a robot driving along x at ``speed`` m/s, positions times ``scale``."""
    n = 40
    t = 0.1 * np.arange(n)
    return ReadingBatch.from_arrays(t=t, sensor=np.arange(n) % 2, x=scale * speed * t,
                                    y=np.zeros(n), theta=np.full(n, 0.5), range=np.full(n, 2.0))


def test_positions_in_millimetres_beside_ranges_in_metres_are_named() -> None:
    # User review: x, y in millimetres and ranges in metres mapped without a word.
    (warning,) = likely_mistakes(_driving(0.4, scale=1000.0))
    assert warning == ("the sensors move at 400 m/s between readings (median): are x and y in "
                       "millimetres? (readings CSV x, y are metres and t seconds)")


@pytest.mark.parametrize("speed", [0.0, 0.4, 2.0, 15.0])
def test_robots_and_cars_in_metres_are_no_mistake(speed: float) -> None:
    assert likely_mistakes(_driving(speed)) == []
