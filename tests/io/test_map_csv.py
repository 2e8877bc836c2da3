"""The map CSV (design contract): ``id,t,sensor,x,y,source,width,max_error``."""

from __future__ import annotations

import csv
import itertools
import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.io import MAP_COLUMNS, read_map_csv, write_map_csv
from sonarcarve.io.errors import InputError
from sonarcarve.io.map_csv import APPENDED_COLUMNS, BLOCK_ROWS, map_csv_sink
from sonarcarve.maps import GlobalMap, PointSource

HEADER = "id,t,sensor,x,y,source,width,max_error"
#: What is written since the confidence column was appended (issue 9).
WRITTEN_HEADER = HEADER + ",confidence"


def _map() -> GlobalMap:
    return GlobalMap(
        reading_id=np.array([0, 3, 7], dtype=np.int64),
        t=np.array([0.0, 0.25, 1.5]),
        sensor=np.array([2, 0, 15], dtype=np.int64),
        xy=np.array([[1.0, -2.5], [0.125, 3.0], [-4.0, 0.5]]),
        source=np.array([PointSource.CENTERLINE, PointSource.CARVED, PointSource.ATM],
                        dtype=np.int8),
        width=np.array([0.5, 0.25, 0.0]),
        max_error=np.array([0.75, 0.0625, math.inf]),
        range=np.array([3.0, 2.0, 1.0]),
    )


def test_header_is_the_contract() -> None:
    # The first eight columns keep their names, order and meaning for ever (design.md).
    assert ",".join(MAP_COLUMNS) == HEADER


def test_written_text_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "map.csv"
    write_map_csv(_map(), path)
    assert path.read_text(encoding="utf-8") == (
        "id,t,sensor,x,y,source,width,max_error,confidence\n"
        "0,0.0,2,1.0,-2.5,centerline,0.5,0.75,\n"
        "3,0.25,0,0.125,3.0,carved,0.25,0.0625,\n"
        "7,1.5,15,-4.0,0.5,atm,0.0,inf,\n"
    )


def test_confidence_is_appended_and_read_back(tmp_path: Path) -> None:
    path = tmp_path / "map.csv"
    base = _map()
    sure = GlobalMap(**{**{name: getattr(base, name) for name in (
        "reading_id", "t", "sensor", "xy", "source", "width", "max_error", "range")},
        "confidence": np.array([0.5, 1.0, np.nan])})
    write_map_csv(sure, path)
    lines = path.read_text(encoding="utf-8").splitlines()
    assert lines[1] == "0,0.0,2,1.0,-2.5,centerline,0.5,0.75,0.5"
    assert lines[3].endswith(",inf,")  # not modelled: an empty cell
    back = read_map_csv(path)
    np.testing.assert_array_equal(back.confidence, [0.5, 1.0, np.nan])
    path.write_text(WRITTEN_HEADER + "\n0,0.0,2,1.0,-2.5,centerline,0.5,0.75,1.5\n")
    with pytest.raises(InputError, match=r"line 2, column 'confidence' must lie in \[0, 1\]"):
        read_map_csv(path)


def test_empty_map_is_just_the_header(tmp_path: Path) -> None:
    path = tmp_path / "empty.csv"
    write_map_csv(GlobalMap.empty(), path)
    assert path.read_text(encoding="utf-8") == WRITTEN_HEADER + "\n"
    back = read_map_csv(path)
    assert len(back) == 0
    assert back.xy.shape == (0, 2)


def test_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "map.csv"
    original = _map()
    write_map_csv(original, path)
    back = read_map_csv(path)
    assert type(back) is GlobalMap
    assert back.reading_id.tolist() == [0, 3, 7]
    assert back.reading_id.dtype == np.int64
    assert back.t.tolist() == [0.0, 0.25, 1.5]
    assert back.sensor.tolist() == [2, 0, 15]
    assert back.xy.tolist() == [[1.0, -2.5], [0.125, 3.0], [-4.0, 0.5]]
    assert back.source_labels() == ["centerline", "carved", "atm"]
    assert back.source.dtype == np.int8
    assert back.width.tolist() == [0.5, 0.25, 0.0]
    assert back.max_error.tolist() == [0.75, 0.0625, math.inf]
    assert np.isnan(back.range).all()  # not in the file


def test_floats_round_trip_exactly(tmp_path: Path) -> None:
    # Values with no short decimal form, the extremes of float64 and negative zero.
    values = np.array([0.1, 1 / 3, math.pi, -math.e * 1e-300, 5e-324, 1.7976931348623157e308,
                       -0.0, 2.0**-52 + 1.0])
    n = len(values)
    pts = GlobalMap(reading_id=np.arange(n, dtype=np.int64), t=np.abs(values[::-1]),
                    sensor=np.zeros(n, np.int64), xy=np.column_stack((values, values[::-1])),
                    source=np.zeros(n, np.int8), width=np.abs(values), max_error=np.abs(values),
                    range=np.ones(n))
    path = tmp_path / "floats.csv"
    write_map_csv(pts, path)
    back = read_map_csv(path)
    for field in ("t", "xy", "width", "max_error"):
        got, want = getattr(back, field), getattr(pts, field)
        assert got.tobytes() == want.tobytes(), field  # bit for bit, signed zero included


def test_appended_columns_are_ignored(tmp_path: Path) -> None:
    # "New columns are only ever appended": a reader of today must read tomorrow's file.
    path = tmp_path / "newer.csv"
    path.write_text(HEADER + ",confidence\n5,1.0,1,2.0,3.0,carved,0.5,0.25,0.9\n")
    back = read_map_csv(path)
    assert back.reading_id.tolist() == [5]
    assert back.xy.tolist() == [[2.0, 3.0]]
    assert back.max_error.tolist() == [0.25]


GOOD = "0,0.0,2,1.0,-2.5,centerline,0.5,0.75\n"


@pytest.mark.parametrize(("text", "where", "problem"), [
    ("id,t,sensor,x,y,source,width\n0,0.0,2,1.0,-2.5,centerline,0.5\n", "line 1", "header"),
    ("id,t,sensor,y,x,source,width,max_error\n" + GOOD, "line 1", "header"),
    ("", "line 1", "header"),
    (HEADER + "\n" + GOOD + "1,0.0,2,1.0,-2.5,wall,0.5,0.75\n", "line 3", "'wall'"),
    (HEADER + "\n" + GOOD + GOOD + "2,0.0,2,nan,-2.5,carved,0.5,0.75\n", "line 4", "'x' is NaN"),
    (HEADER + "\n" + "0,0.0,2,1.0,-2.5,atm,0.5,nan\n", "line 2", "'max_error' is NaN"),
    (HEADER + "\n" + "0,inf,2,1.0,-2.5,atm,0.5,0.1\n", "line 2", "'t' is not finite"),
    (HEADER + "\n" + "0,0.0,2,1.0,-2.5,atm,0.5,-inf\n", "line 2", "'max_error' is not finite"),
    (HEADER + "\n" + "0,0.0,2,1.0,-2.5\n", "line 2", "5 fields"),
    (HEADER + "\n" + "0,0.0,2,one,-2.5,atm,0.5,0.1\n", "line 2", "'x' is not a number"),
    (HEADER + "\n" + "1.5,0.0,2,1.0,-2.5,atm,0.5,0.1\n", "line 2", "'id' is not a whole number"),
    (HEADER + "\n" + "1,0.0,-2,1.0,-2.5,atm,0.5,0.1\n", "line 2", "'sensor' is not a whole"),
    # UX review, finding 12: a negative bound or width passed.
    (HEADER + "\n" + GOOD + "0,0,0,0,0,carved,0.1,-1,\n", "line 3",
     "column 'max_error' must be >= 0 metres, got '-1'"),
    (HEADER + "\n" + "0,0,0,0,0,carved,-0.1,1\n", "line 2",
     "column 'width' must be >= 0 radians, got '-0.1'"),
    # User review: `plot readings.csv` said only "expected header id,t,...".
    ("t,sensor,x,y,theta,range,beam_width\n0,0,0,0,0,1,0.39\n", "line 1",
     "it is a readings CSV (t,sensor,x,y,theta,range,beam_width): a map CSV is what "
     "sonarcarve process writes"),
])
def test_bad_files_fail_with_one_line_naming_file_and_line(
    tmp_path: Path, text: str, where: str, problem: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(SonarcarveError) as info:
        read_map_csv(path)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: {where}")
    assert problem in message


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SonarcarveError, match=r"absent\.csv"):
        read_map_csv(tmp_path / "absent.csv")


def test_trailing_blank_lines_are_harmless(tmp_path: Path) -> None:
    path = tmp_path / "map.csv"
    path.write_text(HEADER + "\n" + GOOD + "\n\n")
    assert read_map_csv(path).reading_id.tolist() == [0]


# -- the block-wise writer against the row-by-row writer it replaced ---------------------------


def _reference_write(points: GlobalMap, path: Path) -> None:
    """The writer before issue 11: csv.writer, one row at a time, repr of every float."""
    labels = points.source_labels()
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(MAP_COLUMNS + APPENDED_COLUMNS)
        for i in range(len(points)):
            confidence = float(points.confidence[i])
            writer.writerow([
                int(points.reading_id[i]), repr(float(points.t[i])), int(points.sensor[i]),
                repr(float(points.xy[i, 0])), repr(float(points.xy[i, 1])), labels[i],
                repr(float(points.width[i])), repr(float(points.max_error[i])),
                "" if math.isnan(confidence) else repr(confidence),
            ])


AWKWARD = np.array([0.0, -0.0, math.inf, 5e-324, -5e-324, 1.7976931348623157e308, 1e16, 1e-5,
                    1e-4, 9999999999999998.0, 0.1, 1 / 3, 123456789012345678.0, 1e22, 2.5e-7,
                    100.0, 1e15, 2.0**-1074 * 3, 2.0**53 + 2, -1e300, math.pi])


def _random_map(n: int, seed: int) -> GlobalMap:
    rng = np.random.default_rng(seed)

    def floats() -> np.ndarray:
        values = rng.normal(size=n) * 10.0 ** rng.integers(-8, 9, n)
        pick = rng.random(n) < 0.3
        values[pick] = rng.choice(AWKWARD, int(pick.sum()))
        return values

    confidence = rng.random(n)
    confidence[rng.random(n) < 0.4] = np.nan
    confidence[rng.random(n) < 0.1] = rng.choice([0.0, 1.0, -0.0, 5e-324], 1)
    return GlobalMap(
        reading_id=np.sort(rng.choice(10 * n + 10, n, replace=False)).astype(np.int64)
        * rng.choice([1, 2**40]),
        t=floats(), sensor=rng.integers(0, 2**31 - 1, n), xy=np.column_stack((floats(), floats())),
        source=rng.integers(0, len(PointSource), n).astype(np.int8),
        width=floats(), max_error=floats(), range=floats(), confidence=confidence,
    )


@pytest.mark.parametrize("seed", range(4))
def test_written_bytes_are_the_reference_writers(tmp_path: Path, seed: int) -> None:
    points = _random_map(500, seed)
    expected = tmp_path / "reference.csv"
    _reference_write(points, expected)
    for block_rows in (1, 7, 500, BLOCK_ROWS):
        path = tmp_path / f"map-{block_rows}.csv"
        write_map_csv(points, path, block_rows=block_rows)
        assert path.read_bytes() == expected.read_bytes(), block_rows


def test_every_awkward_float_in_every_float_column(tmp_path: Path) -> None:
    n = len(AWKWARD)
    points = GlobalMap(reading_id=np.arange(n, dtype=np.int64), t=AWKWARD,
                       sensor=np.zeros(n, np.int64), xy=np.column_stack((AWKWARD, -AWKWARD)),
                       source=np.zeros(n, np.int8), width=AWKWARD, max_error=-AWKWARD,
                       range=np.ones(n), confidence=np.where(AWKWARD < 1, AWKWARD, np.nan))
    expected, path = tmp_path / "reference.csv", tmp_path / "map.csv"
    _reference_write(points, expected)
    write_map_csv(points, path, block_rows=4)
    assert path.read_bytes() == expected.read_bytes()
    lines = path.read_text().splitlines()
    assert lines[2] == "1,-0.0,0,-0.0,0.0,centerline,-0.0,0.0,-0.0"  # signed zeros kept
    assert lines[4].split(",")[1] == "5e-324"


@pytest.mark.parametrize("seed", range(3))
def test_floats_of_any_bit_pattern_are_written_as_the_reference_writes_them(
    tmp_path: Path, seed: int,
) -> None:
    """The compiled writer against ``repr`` on doubles of every exponent: subnormals, NaNs of
    any sign and payload, infinities, negative zero, huge and tiny values."""
    rng = np.random.default_rng(100 + seed)
    n = 20_000

    def floats() -> np.ndarray:
        return rng.integers(0, 2**64, n, dtype=np.uint64).view(np.float64)

    points = GlobalMap(
        reading_id=rng.integers(0, 2**53, n), t=floats(), sensor=rng.integers(0, 2**31, n),
        xy=np.column_stack((floats(), floats())),
        source=rng.integers(0, len(PointSource), n).astype(np.int8), width=floats(),
        max_error=floats(), range=np.ones(n), confidence=floats(),
    )
    expected, path = tmp_path / "reference.csv", tmp_path / "map.csv"
    _reference_write(points, expected)
    write_map_csv(points, path)
    assert path.read_bytes() == expected.read_bytes()


def test_unknown_source_code_and_bad_block_rows_are_refused(tmp_path: Path) -> None:
    points = _map()
    bad = GlobalMap(**{**{name: getattr(points, name) for name in (
        "reading_id", "t", "sensor", "xy", "width", "max_error", "range")},
        "source": np.array([0, 3, 1], dtype=np.int8)})
    with pytest.raises(ValueError, match="3 is not a valid PointSource"):
        write_map_csv(bad, tmp_path / "bad.csv")
    assert not (tmp_path / "bad.csv").exists()
    with pytest.raises(ConfigError, match="block_rows must be at least 1, got 0"):
        write_map_csv(points, tmp_path / "map.csv", block_rows=0)


# -- the streaming writer (a global-map sink) ----------------------------------------------------


@pytest.mark.parametrize("block_rows", [1, 7, 64, BLOCK_ROWS])
def test_sink_writes_the_same_bytes_in_any_blocks(tmp_path: Path, block_rows: int) -> None:
    points = _random_map(500, 1)
    expected, path = tmp_path / "reference.csv", tmp_path / "map.csv"
    _reference_write(points, expected)
    cuts = [0, 1, 1, 3, 60, 61, 200, 499, 500]  # empty, single-row and uneven pieces
    with map_csv_sink(path, block_rows=block_rows) as sink:
        for start, stop in itertools.pairwise(cuts):
            sink.commit(points.select(np.arange(start, stop)))
            assert not path.exists()  # nothing at the target before the end
    assert sink.points == 500
    assert path.read_bytes() == expected.read_bytes()


def test_sink_with_no_points_writes_the_header(tmp_path: Path) -> None:
    path = tmp_path / "map.csv"
    with map_csv_sink(path):
        pass
    assert path.read_bytes() == (",".join(MAP_COLUMNS + APPENDED_COLUMNS) + "\n").encode()


def test_sink_error_leaves_the_old_file_and_no_temporary(tmp_path: Path) -> None:
    path = tmp_path / "map.csv"
    path.write_text("precious\n")

    def run() -> None:
        with map_csv_sink(path, block_rows=2) as sink:
            sink.commit(_random_map(50, 0))  # several blocks already in the temporary file
            msg = "mid-run"
            raise RuntimeError(msg)

    with pytest.raises(RuntimeError, match="mid-run"):
        run()
    assert path.read_text() == "precious\n"
    assert [p.name for p in tmp_path.iterdir()] == ["map.csv"]


def test_sink_refuses_an_unknown_source_code(tmp_path: Path) -> None:
    points = _map()
    bad = GlobalMap(**{**{name: getattr(points, name) for name in (
        "reading_id", "t", "sensor", "xy", "width", "max_error", "range")},
        "source": np.array([0, 3, 1], dtype=np.int8)})
    with pytest.raises(ValueError, match="3 is not a valid PointSource"), \
            map_csv_sink(tmp_path / "bad.csv") as sink:
        sink.commit(bad)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="block_rows"), \
            map_csv_sink(tmp_path / "map.csv", block_rows=0):
        pass


def test_a_file_that_is_not_utf8_names_its_line(tmp_path: Path) -> None:
    # UX review, finding 11: the codec's own message, with no line.
    path = tmp_path / "binary.csv"
    path.write_bytes((HEADER + "\n" + GOOD).encode() + b"\xbd\xff,1\n")
    with pytest.raises(SonarcarveError) as info:
        read_map_csv(path)
    assert str(info.value) == f"{path}: line 3, cannot read as CSV: not UTF-8 text (byte 0xbd)"


def test_spaces_around_header_names_and_labels_are_read(tmp_path: Path) -> None:
    # A map typed by hand or by a spreadsheet, with a space after every comma.
    path = tmp_path / "map.csv"
    path.write_text("id, t, sensor, x, y, source, width, max_error, confidence\n"
                    "4, 1.5, 2, 0.25, -1.0, carved, 0.125, 0.5, 0.75\n", encoding="utf-8")
    back = read_map_csv(path)
    assert back.reading_id.tolist() == [4]
    assert back.source.tolist() == [PointSource.CARVED]
    assert back.xy.tolist() == [[0.25, -1.0]]
    assert (back.width.tolist(), back.max_error.tolist()) == ([0.125], [0.5])
    assert back.confidence.tolist() == [0.75]


def test_a_row_without_the_appended_confidence_cell_reads_it_as_unknown(tmp_path: Path) -> None:
    # Only the first eight columns are required on a row; a missing confidence is "not modelled".
    path = tmp_path / "map.csv"
    path.write_text(WRITTEN_HEADER + "\n0,0.0,2,1.0,-2.5,atm,0.5,0.75\n"
                    "1,0.1,3,1.0,-2.5,atm,0.5,0.75,0.25\n", encoding="utf-8")
    back = read_map_csv(path)
    np.testing.assert_array_equal(back.confidence, [np.nan, 0.25])
    assert back.sensor.tolist() == [2, 3]
