from pathlib import Path

import numpy as np
import pytest

from sonarcarve.io import InputError, read_readings_csv, write_readings_csv
from sonarcarve.readings import ReadingBatch

HEADER = "t,sensor,x,y,theta,range\n"


def test_round_trip_is_exact(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    n = 50
    batch = ReadingBatch.from_arrays(
        t=np.sort(rng.uniform(0, 10, n)), sensor=rng.integers(0, 16, n), x=rng.normal(size=n),
        y=rng.normal(size=n), theta=rng.uniform(-3, 3, n), range=rng.uniform(0.2, 5, n),
        beam_width=rng.uniform(0.1, 0.5, n),
    )
    path = tmp_path / "r.csv"
    write_readings_csv(batch, path)
    again = read_readings_csv(path)
    for name in ("t", "sensor", "x", "y", "theta", "range", "beam_width"):
        np.testing.assert_array_equal(getattr(again, name), getattr(batch, name))


def test_beam_width_column_is_optional_and_may_be_blank(tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    path.write_text("range,theta,y,x,sensor,t,beam_width\n2,0,0,0,3,0.5,\n1,0,0,0,3,0.6,0.3\n")
    batch = read_readings_csv(path)
    assert batch.sensor.tolist() == [3, 3]
    assert np.isnan(batch.beam_width[0])
    assert batch.beam_width[1] == 0.3


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("t,sensor,x,y,theta\n0,0,0,0,0\n", "line 1, missing column(s) range"),
        (HEADER + "0,0,0,0,0,abc\n", "line 2, column 'range' is not a number: 'abc'"),
        (HEADER + "0,0,0,0,0,1\n1,0,0,0,0,nan\n", "line 3, column 'range' is NaN or infinite"),
        (HEADER + "0,0,0,0,0,inf\n", "line 2, column 'range' is NaN or infinite"),
        (HEADER + "0,0,0,0,0,-1\n", "line 2, column 'range' must be > 0"),
        (HEADER + "1,0,0,0,0,1\n0.5,0,0,0,0,1\n", "line 3, column 't' goes backwards in time"),
        (HEADER + "0,1.5,0,0,0,1\n", "line 2, column 'sensor' is not a whole number"),
        # A short row used to be reported as its missing value; now as its field count.
        (HEADER + "0,0,0,0,0\n", "line 2 has 5 fields, the header has 6"),
        (HEADER + "0,0,0,0,0,1\n0,0,0,0,0,1,7\n", "line 3 has 7 fields, the header has 6"),
        (HEADER + "0,0,0,0,0,1\n\n1,0,0,0,0,1\n", "line 3 is blank"),
        (HEADER + "0,0,0,0,0,1\n   \n", "line 3 has 1 field, the header has 6"),
        ("t,sensor,x,y,theta,range,x\n0,0,0,0,0,1,2\n", "line 1, column 'x' appears twice"),
        (HEADER + "0,99999999999999999999,0,0,0,1\n",
         "line 2, column 'sensor' must be at most 2147483647"),
        (HEADER + "0,0,0,0,0,1\n0,1e400,0,0,0,1\n", "line 3, column 'sensor' is not a whole"),
        (HEADER + "0,nan,0,0,0,1\n", "line 2, column 'sensor' is not a whole number"),
        (HEADER + "0,-2,0,0,0,1\n", "line 2, column 'sensor' must be >= 0"),
        ("", "empty file"),
        ("\n\n", "empty file"),
    ],
)
def test_bad_input_names_file_line_and_column(tmp_path: Path, body: str, message: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(body)
    with pytest.raises(InputError) as caught:
        read_readings_csv(path)
    text = str(caught.value)
    assert message in text
    assert str(path) in text
    assert "\n" not in text


def test_missing_and_binary_files(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        read_readings_csv(tmp_path / "nope.csv")
    binary = tmp_path / "bin.csv"
    binary.write_bytes(b"\xff\xfe\x00\x01garbage")
    with pytest.raises(InputError, match="cannot read"):
        read_readings_csv(binary)


def test_byte_order_mark_and_trailing_blank_lines_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbf" + (HEADER + "0,3,1,2,0.5,1.5\r\n\r\n\r\n").encode())
    batch = read_readings_csv(path)
    assert batch.sensor.tolist() == [3]
    assert (batch.x[0], batch.y[0], batch.theta[0], batch.range[0]) == (1.0, 2.0, 0.5, 1.5)


def test_extra_columns_are_ignored_but_must_be_on_every_line(tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    path.write_text("t,sensor,x,y,theta,range,note\n0,0,0,0,0,1,hello\n1,0,0,0,0,2,\n")
    assert read_readings_csv(path).range.tolist() == [1.0, 2.0]
