import csv
import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.errors import ConfigError
from sonarcarve.io import InputError, read_readings_csv, write_readings_csv
from sonarcarve.io.errors import parse_number
from sonarcarve.io.readings_csv import (
    BLOCK_SIZE,
    MAX_LINE_BYTES,
    READINGS_COLUMNS,
    _check_header,
    count_data_lines,
    iter_readings_csv,
)
from sonarcarve.readings import ReadingBatch, ReadingsError

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
        (HEADER + "0,0,0,0,0,inf\n",
         "line 2, column 'range' is infinite but 'max_range' is not given"),
        (HEADER + "0,0,0,0,0,-inf\n", "line 2, column 'range' is NaN or infinite"),
        (HEADER.rstrip() + ",max_range\n0,0,0,0,0,1,0.5\n",
         "line 2, column 'range' exceeds 'max_range'"),
        (HEADER.rstrip() + ",max_range\n0,0,0,0,0,inf,\n",
         "line 2, column 'range' is infinite but 'max_range' is not given"),
        (HEADER.rstrip() + ",max_range\n0,0,0,0,0,inf,inf\n",
         "line 2, column 'max_range' must be a"),
        (HEADER.rstrip() + ",max_range\n0,0,0,0,0,1,-3\n", "line 2, column 'max_range' must be a"),
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
        # Huge but finite values, which used to hang the methods or give NaN map points.
        (HEADER + "0,0,0,0,1e20,1\n", "line 2, column 'theta' must lie within ±1,000,000 rad"),
        (HEADER + "0,0,0,0,0,1.7e308\n", "line 2, column 'range' must be at most 10,000 m"),
        (HEADER + "0,0,1e300,0,0,1\n", "line 2, column 'x' must lie within ±1,000,000 m"),
        # A header that would parse with another separator or case says so.
        ("t;sensor;x;y;theta;range\n0;0;0;0;0;1\n",
         "(header: t;sensor;x;y;theta;range); the file looks separated by ';'"),
        ("t\tsensor\tx\ty\ttheta\trange\n", "the file looks separated by tabs"),
        ("T,Sensor,X,Y,Theta,Range\n0,0,0,0,0,1\n", "column names are case-sensitive"),
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
    with pytest.raises(InputError, match=r"bin.csv: not text \(NUL byte at line 1\)"):
        read_readings_csv(binary)


@pytest.mark.parametrize("size", [1, 7, 64, BLOCK_SIZE])
def test_a_nul_byte_is_refused_after_the_lines_before_it(tmp_path: Path, size: int) -> None:
    path = tmp_path / "nul.csv"
    path.write_bytes((HEADER + "0,0,0,0,0,1\n" * 3).encode() + b"1,0,0\x00,0,0,1\n" * 9)
    with pytest.raises(InputError, match=r"nul.csv: not text \(NUL byte at line 5\)$"):
        read_readings_csv(path, block_size=size)
    bad_first = tmp_path / "bad_first.csv"  # an earlier bad line is still the one named
    bad_first.write_bytes((HEADER + "0,0,0,0,0,-1\n").encode() + b"\x00\n")
    with pytest.raises(InputError, match="line 2, column 'range' must be > 0"):
        read_readings_csv(bad_first, block_size=size)


@pytest.mark.parametrize("size", [1, 2, 5, BLOCK_SIZE])
def test_a_nul_byte_after_a_byte_order_mark_is_refused(tmp_path: Path, size: int) -> None:
    path = tmp_path / "bom.csv"
    path.write_bytes(b"\xef\xbb\xbf" + HEADER.encode() + b"0,0,0,0,0,1\n\x00\n")
    with pytest.raises(InputError, match=r"not text \(NUL byte at line 3\)$"):
        read_readings_csv(path, block_size=size)


def test_dev_zero_fails_at_once() -> None:
    with pytest.raises(InputError, match=r"^/dev/zero: not text \(NUL byte at line 1\)$"):
        read_readings_csv("/dev/zero")
    assert count_data_lines("/dev/zero") == 0


@pytest.mark.parametrize("size", [4096, BLOCK_SIZE, 3 * BLOCK_SIZE])
def test_a_line_longer_than_the_limit_is_refused(tmp_path: Path, size: int) -> None:
    path = tmp_path / "long.csv"
    path.write_bytes((HEADER + "0,0,0,0,0,1\n").encode() + b"9" * (MAX_LINE_BYTES + 1))
    with pytest.raises(InputError, match=r"long\.csv: line 3 is longer than 1 MiB: not a readings"):
        read_readings_csv(path, block_size=min(size, MAX_LINE_BYTES))
    path.write_bytes(b"t" * (MAX_LINE_BYTES + 1) + b"\n" + b"0,0,0,0,0,1\n")
    with pytest.raises(InputError, match="line 1 is longer than 1 MiB"):
        read_readings_csv(path, block_size=min(size, MAX_LINE_BYTES))
    path.write_bytes(HEADER.encode() + b"0" * (MAX_LINE_BYTES - 1) + b",0,0,0,0,1\n")
    with pytest.raises(InputError, match="line 2 is longer than 1 MiB"):
        read_readings_csv(path, block_size=min(size, MAX_LINE_BYTES))


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


# -- streaming: blocks of any size give the same batch and the same errors ----------------------

BLOCK_SIZES = (1, 2, 17, 64, 1000, BLOCK_SIZE)


def _reference_read(path: Path) -> ReadingBatch:
    """The reader before streaming (issue 11), kept as the reference: the whole file through
    the csv module, one ``parse_number`` per cell, then one validation."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            reader = csv.reader(handle)
            rows = [(reader.line_num, row) for row in reader]
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"{path}: cannot read as CSV ({err})") from None
    while rows and not rows[-1][1]:
        rows.pop()
    if not rows:
        raise InputError(f"{path}: empty file, expected a header")
    header = [name.strip() for name in rows[0][1]]
    _check_header(path, header)
    body = rows[1:]
    for line, row in body:
        if not row:
            raise InputError(f"{path}: line {line} is blank (blank lines are allowed only at "
                             "the end)")
        if len(row) != len(header):
            fields = f"{len(row)} field{'' if len(row) == 1 else 's'}"
            raise InputError(f"{path}: line {line} has {fields}, the header has {len(header)}")
    wanted = [*READINGS_COLUMNS, *(name for name in ("beam_width", "max_range")
                                   if name in header)]
    columns = {}
    for name in wanted:
        values = np.empty(len(body))
        for k, (line, row) in enumerate(body):
            text = row[header.index(name)]
            values[k] = (math.nan if name in ("beam_width", "max_range") and not text.strip()
                         else parse_number(text, f"{path}: line {line}", name, finite=False))
        columns[name] = values
    try:
        return ReadingBatch.from_arrays(**columns, source=str(path), first_line=2)
    except ReadingsError as err:
        raise InputError(str(err)) from None


def _assert_same(a: ReadingBatch, b: ReadingBatch) -> None:
    for name in ("t", "sensor", "x", "y", "theta", "range", "beam_width", "max_range"):
        assert getattr(a, name).tobytes() == getattr(b, name).tobytes(), name


def _log_text(n: int, seed: int, *, width: bool = True) -> list[str]:
    """Data lines of a valid log: awkward floats, blank beam widths, an extra column."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0, 0.1, n))
    lines = []
    for k in range(n):
        cells = [repr(float(t[k])), str(int(rng.integers(0, 16))), repr(float(rng.normal())),
                 f"{rng.normal():.3e}", repr(float(rng.uniform(-3, 3))),
                 repr(float(rng.uniform(0.1, 5)))]
        if width:
            cells.append("" if k % 5 == 0 else repr(float(rng.uniform(0.1, 0.5))))
        cells.append("note")
        lines.append(",".join(cells))
    return lines


def _write(path: Path, header: str, lines: list[str], newline: str = "\n",
           tail: str = "\n") -> Path:
    path.write_bytes((newline.join([header, *lines]) + tail.replace("\n", newline)).encode())
    return path


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
@pytest.mark.parametrize("tail", ["", "\n", "\n\n\n"])
def test_blocks_of_any_size_read_the_same_batch(tmp_path: Path, newline: str, tail: str) -> None:
    path = _write(tmp_path / "r.csv", "t,sensor,x,y,theta,range,beam_width,note",
                  _log_text(120, 3), newline, tail)
    expected = _reference_read(path)
    for size in BLOCK_SIZES:
        _assert_same(read_readings_csv(path, block_size=size), expected)
        batches = list(iter_readings_csv(path, block_size=size))
        assert all(len(b) for b in batches)
        assert sum(len(b) for b in batches) == 120
        if size <= 64:
            assert len(batches) > 10  # really streamed
    assert count_data_lines(path) == 120
    assert count_data_lines(path, block_size=3) == 120


def test_quoted_fields_and_lone_carriage_returns_go_through_the_csv_module(
    tmp_path: Path,
) -> None:
    lines = _log_text(40, 4)
    # Quotes from line 31 on, one with a line break inside (the line count grows by one).
    lines[29] = lines[29].replace(",note", ',"two\nlines"')
    lines[35] = '"' + lines[35].replace(",", '","') + '"'
    path = _write(tmp_path / "quoted.csv", "t,sensor,x,y,theta,range,beam_width,note", lines)
    expected = _reference_read(path)
    for size in BLOCK_SIZES:
        _assert_same(read_readings_csv(path, block_size=size), expected)
    mac = _write(tmp_path / "mac.csv", "t,sensor,x,y,theta,range,beam_width,note", lines[:20],
                 "\r")
    for size in BLOCK_SIZES:
        _assert_same(read_readings_csv(mac, block_size=size), _reference_read(mac))
    # A bad line after the quoted one is named by its line in the file.
    lines[37] = lines[37].replace(",note", ",note,extra")
    path = _write(tmp_path / "quoted.csv", "t,sensor,x,y,theta,range,beam_width,note", lines)
    for size in BLOCK_SIZES:
        with pytest.raises(InputError, match=r"line 40 has 9 fields, the header has 8$"):
            read_readings_csv(path, block_size=size)


def _damage(lines: list[str], kind: str, k: int) -> list[str]:
    """``lines`` with one problem on data line ``k``."""
    cells = lines[k].split(",")
    damaged = list(lines)
    if kind == "blank":
        damaged.insert(k, "")
        return damaged
    if kind == "spaces":
        damaged[k] = "   "
    elif kind == "short":
        damaged[k] = ",".join(cells[:-1])
    elif kind == "long":
        damaged[k] = lines[k] + ",7"
    else:
        column, text = {"t_text": (0, "soon"), "t_nan": (0, "nan"), "backwards": (0, "-1"),
                        "sensor_half": (1, "2.5"), "sensor_huge": (1, "1e12"),
                        "sensor_negative": (1, "-3"), "x_text": (2, "1,5".replace(",", ";")),
                        "y_inf": (3, "-inf"), "range_zero": (5, "0"),
                        "range_text": (5, ""), "width_wide": (6, "3.5"),
                        "width_text": (6, "wide"), "t_exponent_only": (0, "1e"),
                        "x_two_points": (2, "1..2"), "y_sign_only": (3, "-"),
                        "theta_huge": (4, "1e300"), "range_inf": (5, "inf"),
                        "range_overflow": (5, "1e999"), "range_signs": (5, "+-1"),
                        # inf: many leading zeros and a long exponent (a capped exponent read
                        # it as 1e-51, a finite x)
                        "x_huge_exponent": (2, "0." + "0" * 100_100 + "1e1000500")}[kind]
        cells[column] = text
        damaged[k] = ",".join(cells)
    return damaged


KINDS = ("blank", "spaces", "short", "long", "t_text", "t_nan", "backwards", "sensor_half",
         "sensor_huge", "sensor_negative", "x_text", "y_inf", "range_zero", "range_text",
         "width_wide", "width_text")


@pytest.mark.parametrize("kind", KINDS)
def test_one_bad_line_gives_the_reference_message_whatever_the_blocks(
    tmp_path: Path, kind: str,
) -> None:
    rng = np.random.default_rng(len(kind))
    lines = _log_text(60, 5)
    first = 1 if kind == "backwards" else 0  # the first line has no earlier time
    for k in (first, int(rng.integers(1, 59)), 59):
        path = _write(tmp_path / "bad.csv", "t,sensor,x,y,theta,range,beam_width,note",
                      _damage(lines, kind, k))
        with pytest.raises(InputError) as reference:
            _reference_read(path)
        for size in BLOCK_SIZES:
            with pytest.raises(InputError) as caught:
                read_readings_csv(path, block_size=size)
            assert str(caught.value) == str(reference.value), (kind, k, size)
            assert f"line {k + 2}" in str(caught.value)


def _numeric_log_text(n: int, seed: int) -> list[str]:
    """Data lines of a valid log holding only numbers, each one ``repr`` or a short decimal
    wrote (so the compiled parser reads them all)."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0, 0.1, n))
    return [",".join([repr(float(t[k])), str(int(rng.integers(0, 16))),
                      repr(float(rng.normal())), f"{rng.normal():.3e}",
                      repr(float(rng.uniform(-3, 3))), f"{rng.uniform(0.1, 5):+.6f}",
                      repr(float(rng.uniform(0.1, 0.5)))]) for k in range(n)]


NUMERIC_HEADER = "t,sensor,x,y,theta,range,beam_width"
#: Problems whose line holds only the bytes the bulk parsers read (digits, signs, ., e, inf).
NUMERIC_KINDS = ("blank", "short", "long", "backwards", "sensor_half", "sensor_huge",
                 "sensor_negative", "range_zero", "range_text", "width_wide",
                 "t_exponent_only", "x_two_points", "y_sign_only", "theta_huge", "range_inf",
                 "range_overflow", "range_signs", "x_huge_exponent")


@pytest.fixture
def numbers_parsed(monkeypatch: pytest.MonkeyPatch) -> dict[str, int]:
    """Counts the numbers parsed in bulk, by parser (so a test knows which fast path ran):
    ``compiled`` (:func:`~sonarcarve.io.float_text.parse_floats`) and ``numpy`` (blocks the
    compiled parser left undecided)."""
    from sonarcarve.io import float_text, readings_csv

    parsed = {"compiled": 0, "numpy": 0}
    parse_floats = float_text.parse_floats
    parse_numbers = readings_csv._parse_numbers

    def compiled(raw: bytes, count: int, width: int = 0) -> np.ndarray | None:
        values = parse_floats(raw, count, width)
        if values is not None:
            parsed["compiled"] += values.size
        return values

    def bulk(raw: bytes, count: int, width: int = 0) -> np.ndarray | None:
        before = parsed["compiled"]
        values = parse_numbers(raw, count, width)
        if values is not None and parsed["compiled"] == before:
            parsed["numpy"] += values.size
        return values

    monkeypatch.setattr(float_text, "parse_floats", compiled)
    monkeypatch.setattr(readings_csv, "_parse_numbers", bulk)
    return parsed


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_a_log_of_plain_numbers_is_parsed_by_the_compiled_parser_to_the_same_batch(
    tmp_path: Path, newline: str, numbers_parsed: dict[str, int],
) -> None:
    path = _write(tmp_path / "r.csv", NUMERIC_HEADER, _numeric_log_text(300, 7), newline)
    expected = _reference_read(path)
    for size in BLOCK_SIZES:
        numbers_parsed.update(compiled=0, numpy=0)
        _assert_same(read_readings_csv(path, block_size=size), expected)
        assert numbers_parsed == {"compiled": 300 * 7, "numpy": 0}, size  # every row


def test_a_block_the_compiled_parser_leaves_is_parsed_by_numpy_to_the_same_batch(
    tmp_path: Path, numbers_parsed: dict[str, int],
) -> None:
    lines = _numeric_log_text(300, 11)
    cells = lines[150].split(",")
    cells[2] = "-0.1000000000000000000000001"  # 25 digits: more than the compiled parser reads
    lines[150] = ",".join(cells)
    path = _write(tmp_path / "r.csv", NUMERIC_HEADER, lines)
    expected = _reference_read(path)
    for size in BLOCK_SIZES:
        numbers_parsed.update(compiled=0, numpy=0)
        _assert_same(read_readings_csv(path, block_size=size), expected)
        assert numbers_parsed["numpy"] >= 7, size  # the block of line 150, at least
        assert numbers_parsed["compiled"] + numbers_parsed["numpy"] == 300 * 7, size
        assert numbers_parsed["compiled"] > 0 or size == BLOCK_SIZE, size  # the other blocks


def test_spellings_only_float_reads_are_read_as_before(tmp_path: Path) -> None:
    lines = _numeric_log_text(60, 9)
    lines[20] = lines[20].replace(",", ", ", 1)  # a space after a comma
    lines[40] = ",".join([*lines[40].split(",")[:-1], "0_3"])  # an underscore in a number
    path = _write(tmp_path / "r.csv", NUMERIC_HEADER, lines)
    for size in BLOCK_SIZES:
        _assert_same(read_readings_csv(path, block_size=size), _reference_read(path))


@pytest.mark.parametrize("tail", ["", "\n"])
def test_an_empty_last_cell_is_read_as_before(tmp_path: Path, tail: str) -> None:
    # numpy reads "...,5," at the very end of the text as one number short, without an error.
    lines = _numeric_log_text(30, 10)
    lines[-1] = ",".join([*lines[-1].split(",")[:-1], ""])
    path = _write(tmp_path / "r.csv", NUMERIC_HEADER, lines, tail=tail)
    for size in BLOCK_SIZES:
        batch = read_readings_csv(path, block_size=size)
        _assert_same(batch, _reference_read(path))
        assert math.isnan(batch.beam_width[-1])


@pytest.mark.parametrize("kind", NUMERIC_KINDS)
def test_a_bad_line_of_numbers_gives_the_reference_message(
    tmp_path: Path, kind: str, numbers_parsed: dict[str, int],
) -> None:
    lines = _numeric_log_text(60, 8)
    for k in (1, 30, 59):
        path = _write(tmp_path / "bad.csv", NUMERIC_HEADER, _damage(lines, kind, k))
        with pytest.raises(InputError) as reference:
            _reference_read(path)
        for size in (64, 1000, BLOCK_SIZE):
            with pytest.raises(InputError) as caught:
                read_readings_csv(path, block_size=size)
            assert str(caught.value) == str(reference.value), (kind, k, size)
            assert f"line {k + 2}" in str(caught.value)
    assert numbers_parsed["compiled"]  # the good blocks before the bad line were read in bulk


def _number_texts(rng: np.random.Generator, n: int) -> list[str]:
    """Numbers as a log may spell them: shortest reprs of doubles of every size (subnormals,
    huge, negative zero), fixed and exponent notation with many digits, signs, leading zeros,
    overflow and underflow."""
    bits = rng.integers(0, 2**63, n, dtype=np.int64).view(np.float64)
    bits = bits[np.isfinite(bits)] * rng.choice([-1.0, 1.0], bits[np.isfinite(bits)].size)
    texts = [repr(float(v)) for v in bits]
    texts += [repr(float(v)) for v in rng.uniform(0, 5e-308, 200)]  # subnormals
    texts += [f"{v:.{p}e}" for v, p in zip(rng.normal(size=300), rng.integers(0, 25, 300),
                                           strict=True)]
    texts += [f"{v:.{p}f}" for v, p in zip(rng.normal(scale=1e3, size=300),
                                           rng.integers(0, 25, 300), strict=True)]
    texts += [f"{v:+.{p}g}" for v, p in zip(rng.lognormal(0, 30, 300),
                                            rng.integers(1, 30, 300), strict=True)]
    texts += ["0", "-0", "+0", "-0.0", "007", "00.5", ".5", "5.", "-.5e-3", "1E5", "1e+05",
              "1e400", "-1e400", "1e-400", "4.9e-324", "2.4703282292062328e-324",
              "2.4703282292062329e-324", "1.7976931348623157e308",
              "1.7976931348623158e308", "1.7976931348623159e308", "9" * 400,
              "0." + "0" * 400 + "1", "inf", "-inf", "+inf", "123456789012345678901234567890"]
    rng.shuffle(texts)
    return texts


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("compiled", [True, False])
def test_bulk_parsing_reads_numbers_as_float_does(
    seed: int, compiled: bool, monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Both bulk parsers: the compiled one (with numpy for what it leaves), and numpy alone."""
    from sonarcarve.io import float_text
    from sonarcarve.io.readings_csv import _parse_numbers

    if not compiled:
        monkeypatch.setattr(float_text, "parse_floats", lambda raw, count, width=0: None)
    texts = _number_texts(np.random.default_rng(seed), 20_000)
    lines = [",".join(texts[k : k + 5]) for k in range(0, len(texts), 5)]
    values = _parse_numbers("\n".join(lines).encode() + b"\n", len(texts))
    assert values is not None
    expected = np.array([float(text) for text in texts])
    assert values.tobytes() == expected.tobytes()  # bit for bit (signs of zero included)
    assert _parse_numbers("\n".join(lines).encode(), len(texts) + 1) is None  # a count short


@pytest.mark.parametrize("text", ["1_0", " 1", "1 ", "nan", "NaN", "Infinity", "INF", "0x10",
                                  "1e", "--1", "1..2", "+", ".", "e5", "", "1,,2", "1\r2",
                                  "inf5", "\u0661", "1,", ",1", "1\n\n2"])
@pytest.mark.parametrize("compiled", [True, False])
def test_bulk_parsers_leave_other_spellings_to_float(
    text: str, compiled: bool, monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Text the bulk parsers would read differently from ``float`` (or not at all) goes to
    the exact path: the compiled parser (with numpy for what it leaves), and numpy alone. The
    count is the line's true number of fields, so that only the text can be refused."""
    from sonarcarve.io import float_text
    from sonarcarve.io.readings_csv import _parse_numbers

    if not compiled:
        monkeypatch.setattr(float_text, "parse_floats", lambda raw, count, width=0: None)
    line = f"1,{text},3\n"
    fields = line[:-1].replace("\n", ",").count(",") + 1
    assert _parse_numbers(line.encode(), fields) is None
    assert _parse_numbers(b"1,2,3\n", 3) is not None  # the same shape, good fields: read


def test_several_bad_lines_name_the_first(tmp_path: Path) -> None:
    # Line 3 breaks a rule, line 5 has a cell that is no number and line 6 too few fields: the
    # streaming reader names line 3 (the reader before it named line 6, then line 5).
    path = tmp_path / "bad.csv"
    path.write_text(HEADER + "0,0,0,0,0,1\n1,0,0,0,0,-1\n2,0,0,0,0,1\n3,0,x,0,0,1\n4,0\n")
    for size in BLOCK_SIZES:
        with pytest.raises(InputError, match=r"line 3, column 'range' must be > 0$"):
            read_readings_csv(path, block_size=size)
    # On one line, the old order: a cell that is no number (columns in order t, sensor, ...)
    # before a broken rule.
    path.write_text(HEADER + "0,0,0,0,0,1\n1,0.5,y,0,0,-1\n")
    with pytest.raises(InputError, match=r"line 3, column 'x' is not a number: 'y'$"):
        read_readings_csv(path, block_size=8)


def test_time_going_backwards_across_blocks(tmp_path: Path) -> None:
    rows = [f"{k},0,0,0,0,1" for k in range(50)]
    rows[37] = "1,0,0,0,0,1"
    path = tmp_path / "r.csv"
    path.write_text(HEADER + "\n".join(rows) + "\n")
    for size in (1, 30, 100, BLOCK_SIZE):
        batches = iter_readings_csv(path, block_size=size)
        with pytest.raises(InputError, match=r"line 39, column 't' goes backwards in time$"):
            for _ in batches:
                pass


def test_not_utf8_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "latin1.csv"
    path.write_bytes((HEADER + "0,0,0,0,0,1\n").encode() + b"1,0,0,0,0,1 caf\xe9\n")
    for size in BLOCK_SIZES:
        with pytest.raises(InputError) as caught:
            read_readings_csv(path, block_size=size)
        assert str(caught.value) == (f"{path}: line 3, cannot read as CSV: not UTF-8 text "
                                     "(byte 0xe9)")


def test_header_only_and_blank_files(tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    path.write_text(HEADER + "\n\n")
    assert len(read_readings_csv(path)) == 0
    assert list(iter_readings_csv(path)) == []
    assert count_data_lines(path) == 0
    path.write_text("\r\n\n")
    with pytest.raises(InputError, match="empty file"):
        read_readings_csv(path, block_size=1)
    assert count_data_lines(path) == 0
    assert count_data_lines(tmp_path / "absent.csv") == 0
    path.write_bytes(b"\xef\xbb\xbf" + HEADER.encode() + b"0,0,0,0,0,1")  # no final break
    for size in BLOCK_SIZES:
        assert read_readings_csv(path, block_size=size).range.tolist() == [1.0]
    assert count_data_lines(path) == 1
    with pytest.raises(ConfigError, match="block_size must be at least 1 byte, got 0"):
        read_readings_csv(path, block_size=0)


def test_no_echo_rows_round_trip_with_max_range(tmp_path: Path) -> None:
    batch = ReadingBatch.from_arrays(
        t=[0.0, 0.1, 0.2], sensor=[0, 1, 2], x=[0.0, 0.5, 1.0], y=[0.0, 0.0, 0.25],
        theta=[0.0, 1.0, 2.0], range=[1.5, math.inf, 2.0], max_range=[math.nan, 5.0, 6.0])
    path = tmp_path / "run.csv"
    write_readings_csv(batch, path)
    lines = path.read_text().splitlines()
    assert lines[0] == "t,sensor,x,y,theta,range,max_range"  # beam_width unknown: left out
    assert lines[1].endswith(",1.5,")
    assert lines[2].endswith(",inf,5.0")
    _assert_same(read_readings_csv(path), batch)
    _assert_same(read_readings_csv(path, block_size=7), batch)


def test_both_optional_columns_in_any_order(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text("max_range,t,sensor,x,y,theta,range,beam_width\n"
                    "4,0,0,0,0,0,inf,0.3\n,1,0,0,0,0,2,\n")
    batch = read_readings_csv(path)
    assert batch.no_echo.tolist() == [True, False]
    np.testing.assert_array_equal(batch.max_range, [4.0, math.nan])
    np.testing.assert_array_equal(batch.beam_width, [0.3, math.nan])
    write_readings_csv(batch, tmp_path / "out.csv")
    assert (tmp_path / "out.csv").read_text().splitlines()[0] == (
        "t,sensor,x,y,theta,range,beam_width,max_range")


def test_run_wide_max_range_fills_unknown_ones(tmp_path: Path) -> None:
    path = tmp_path / "run.csv"
    path.write_text(HEADER + "0,0,0,0,0,inf\n1,0,0,0,0,2\n")
    with pytest.raises(InputError, match="line 2, column 'range' is infinite but 'max_range'"):
        read_readings_csv(path)
    batch = read_readings_csv(path, max_range=5.0)
    np.testing.assert_array_equal(batch.max_range, [5.0, math.nan])  # no-echo rows only
    path.write_text(HEADER + "0,0,0,0,0,inf\n1,0,0,0,0,7\n")  # an echo beyond it: no error
    np.testing.assert_array_equal(read_readings_csv(path, max_range=5.0).range, [math.inf, 7.0])
    path.write_text(HEADER.rstrip() + ",max_range\n0,0,0,0,0,inf,3\n1,0,0,0,0,inf,\n")
    np.testing.assert_array_equal(read_readings_csv(path, max_range=5.0).max_range, [3.0, 5.0])
    with pytest.raises(ValueError, match="max_range must be a finite number > 0"):
        read_readings_csv(path, max_range=0.0)


def test_spaces_around_header_names_are_read(tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    path.write_text("t, sensor, x, y, theta, range\n0.5, 3, 1.0, -2.0, 0.25, 1.5\n")
    batch = read_readings_csv(path)
    assert (batch.t.tolist(), batch.sensor.tolist(), batch.range.tolist()) == ([0.5], [3], [1.5])
    assert (batch.x.tolist(), batch.y.tolist(), batch.theta.tolist()) == ([1.0], [-2.0], [0.25])


def test_several_unnamed_columns_are_ignored_not_duplicates(tmp_path: Path) -> None:
    # A spreadsheet export with two empty trailing columns: unnamed columns are extra columns.
    path = tmp_path / "r.csv"
    path.write_text("t,sensor,x,y,theta,range,,\n0.0,1,0.0,0.0,0.0,2.0,,\n")
    batch = read_readings_csv(path)
    assert (batch.sensor.tolist(), batch.range.tolist()) == ([1], [2.0])


def test_counting_lines_does_not_consume_a_pipe(tmp_path: Path) -> None:
    # A log given as a pipe (`sonarcarve process <(zcat log.csv.gz)`) can be read only once:
    # counting its lines for a progress bar must not read it (0: unknown).
    import os
    import threading

    fifo = tmp_path / "log.csv"
    os.mkfifo(fifo)

    def write() -> None:
        try:
            with fifo.open("w") as handle:
                handle.write(HEADER + "0.0,1,0.0,0.0,0.0,2.0\n" * 3)
        except BrokenPipeError:
            pass  # the counter closed its end without reading: what it should do

    writer = threading.Thread(target=write)
    writer.start()
    assert count_data_lines(fifo) == 0
    writer.join(timeout=10)
    assert not writer.is_alive()
