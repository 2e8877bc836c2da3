import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.filters import MapFilter, ReadingFilter
from sonarcarve.io import MAP_COLUMNS, read_map_csv, write_map_csv, write_readings_csv
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch


def _write_ring_readings(path: Path, n: int = 120) -> ReadingBatch:
    """A robot driving along +x between two walls at y = +-1.5, ranges from the true geometry."""
    k = np.arange(n)
    theta = np.where(k % 2 == 0, math.pi / 2, -math.pi / 2)
    batch = ReadingBatch.from_arrays(t=0.1 * k, sensor=k % 2, x=0.05 * k, y=np.zeros(n),
                                     theta=theta, range=np.full(n, 1.5))
    write_readings_csv(batch, path)
    return batch


def test_process_writes_the_contract_map(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    readings = tmp_path / "r.csv"
    batch = _write_ring_readings(readings)
    out = tmp_path / "map.csv"
    assert main(["process", str(readings), "--method", "centerline", "--out", str(out)]) == 0
    assert out.read_text().splitlines()[0] == ",".join(MAP_COLUMNS) + ",confidence"
    points = read_map_csv(out)
    assert points.reading_id.tolist() == list(range(len(batch)))
    # Centerline points sit on the axis at range r: here exactly on the walls y = +-1.5.
    np.testing.assert_allclose(np.abs(points.xy[:, 1]), 1.5)
    np.testing.assert_allclose(points.xy[:, 0], batch.x, atol=1e-12)
    assert set(points.source_labels()) == {"centerline"}
    assert "readings in" in capsys.readouterr().out


def _bad_cases(tmp_path: Path) -> list[tuple[list[str], str]]:
    good = tmp_path / "good.csv"
    _write_ring_readings(good)
    nan_file = tmp_path / "nan.csv"
    nan_file.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,nan\n")
    missing_col = tmp_path / "cols.csv"
    missing_col.write_text("t,sensor,x,y,theta\n0,0,0,0,0\n")
    unsorted = tmp_path / "unsorted.csv"
    unsorted.write_text("t,sensor,x,y,theta,range\n1,0,0,0,0,1\n0,0,0,0,0,1\n")
    negative = tmp_path / "neg.csv"
    negative.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,-3\n")
    corrupt = tmp_path / "corrupt.csv"
    corrupt.write_bytes(b"\x00\xff\xfe garbage \x89PNG")
    semicolons = tmp_path / "semicolons.csv"
    semicolons.write_text("t;sensor;x;y;theta;range\n0;0;0;0;0;1\n")
    huge_theta = tmp_path / "huge_theta.csv"
    huge_theta.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,1\n0.1,0,0,0,1e20,1\n")
    degrees_then_bad = tmp_path / "degrees_then_bad.csv"  # no warning before the error line
    degrees_then_bad.write_text("t,sensor,x,y,theta,range\n0,0,0,0,90,1\n0.1,0,0,0,180,-1\n")
    needle_beam = tmp_path / "needle_beam.csv"  # evidence carving corrupted memory on this
    needle_beam.write_text("t,sensor,x,y,theta,range,beam_width\n0,0,0,0,0,1,0.3\n"
                           "0.1,1,0,0,0,1,1e-40\n")
    return [
        ([str(needle_beam), "--method", "evidence"],
         "line 3, column 'beam_width' must lie in [1e-06, pi) radians"),
        ([str(semicolons)], "line 1, missing column(s) t, sensor, x, y, theta, range (header: "
                            "t;sensor;x;y;theta;range); the file looks separated by ';'"),
        ([str(huge_theta)], "line 3, column 'theta' must lie within ±1,000,000 rad"),
        ([str(degrees_then_bad)], "line 3, column 'range' must be > 0"),
        ([str(degrees_then_bad), "--beam-width", "0.39"], "line 3, column 'range' must be > 0"),
        (["/dev/zero"], "/dev/zero: not text (NUL byte at line 1)"),
        ([str(nan_file)], "NaN or infinite"),
        ([str(missing_col)], "missing column"),
        ([str(unsorted)], "backwards in time"),
        ([str(negative)], "must be > 0"),
        ([str(corrupt)], str(corrupt)),
        ([str(tmp_path / "absent.csv")], "no such file"),
        ([str(good), "--method", "nonsense"], "--method must be one of"),
        ([str(good), "--history", "0"], "error: --history must be a whole number of arcs in [1, "),
        ([str(good), "--history", "100001"], "error: --history must be a whole number of arcs"),
        ([str(good), "--beam-width", "200"], "error: --beam-width must lie in (0, 180) degrees, "
                                             "got 200"),
        ([str(good), "--beam-width", "0"], "error: --beam-width must lie in (0, 180) degrees"),
        ([str(good), "--range-tolerance", "-1"], "error: --range-tolerance must lie in [0, 1] "
                                                 "metres, got -1"),
        ([str(good), "--range-tolerance", "2"], "error: --range-tolerance must lie in [0, 1] "
                                                "metres, got 2"),
        ([str(good), "--min-transversal", "91"], "error: --min-transversal must lie in (0, 90] "
                                                 "degrees, got 91"),
        ([str(good), "--min-transversal", "0"], "error: --min-transversal must lie in (0, 90] "
                                                "degrees, got 0"),
        ([str(good), "--max-incidence", "-5"], "error: --max-incidence must lie in [0, 90] "
                                               "degrees, got -5"),
    ]


def test_bad_input_is_one_line_exit_2_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for args, message in _bad_cases(tmp_path):
        out = tmp_path / "map.csv"
        out.write_text("precious\n")
        code = main(["process", *args, "--out", str(out)])
        err = capsys.readouterr().err
        assert code == 2, args
        assert message in err, (args, err)
        assert err.count("\n") == 1, err
        assert "Traceback" not in err
        assert out.read_text() == "precious\n", "an existing output must be left untouched"
        assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".map.csv")) == []


@pytest.mark.parametrize("ending", [".csv", ".rrd"])
def test_likely_unit_mistakes_warn_one_line_each_and_exit_0(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], ending: str
) -> None:
    if ending == ".rrd":
        pytest.importorskip("rerun")
    batch = _write_ring_readings(tmp_path / "radians.csv")
    degrees = tmp_path / "degrees.csv"
    write_readings_csv(ReadingBatch.from_arrays(
        t=batch.t, sensor=batch.sensor, x=batch.x, y=batch.y, theta=np.degrees(batch.theta),
        range=batch.range), degrees)
    out = tmp_path / f"map{ending}"
    assert main(["process", str(degrees), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert err.splitlines() == ["sonarcarve: warning: theta reaches 90 rad, beyond ±2π: is it "
                                "in degrees? (readings CSV theta is radians)"]
    assert main(["process", str(tmp_path / "radians.csv"), "--out", str(out),
                 "--beam-width", "0.39"]) == 0
    assert capsys.readouterr().err.splitlines() == [
        "sonarcarve: warning: --beam-width 0.39 is in degrees: did you mean 22.3 (0.39 "
        "radians)?"]
    assert main(["process", str(tmp_path / "radians.csv"), "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""
    unwrapped = tmp_path / "unwrapped.csv"  # radians beyond 2π by small steps: no mistake
    write_readings_csv(ReadingBatch.from_arrays(
        t=batch.t, sensor=batch.sensor, x=batch.x, y=batch.y,
        theta=batch.theta + np.linspace(0.0, 12.0, len(batch)), range=batch.range), unwrapped)
    assert main(["process", str(unwrapped), "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""


def test_version_and_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert "sonarcarve" in capsys.readouterr().out
    assert main(["process", "--help"]) == 0
    assert "--method" in capsys.readouterr().out


def _long_log(path: Path, n: int = 25_000) -> ReadingBatch:
    """Longer than the progress bar's threshold: the file is read in several blocks."""
    return _write_ring_readings(path, n)


def test_long_log_streams_to_the_same_map_as_the_library(tmp_path: Path) -> None:
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    batch = _long_log(readings)
    assert main(["process", str(readings), "--method", "centerline", "--history", "30",
                 "--jump-threshold", "5", "--out", str(out)]) == 0
    expected = process_readings(batch, make_method("centerline", MethodConfig(history_size=30)),
                                reading_filter=ReadingFilter(jump_threshold=5.0))
    write_map_csv(expected.global_map, tmp_path / "expected.csv")
    assert out.read_bytes() == (tmp_path / "expected.csv").read_bytes()


def test_bad_line_late_in_a_long_log_is_one_line_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    _long_log(readings)
    lines = readings.read_text().splitlines()
    lines[24_321] = lines[24_321].rsplit(",", 1)[0] + ",-1.5"
    readings.write_text("\n".join(lines) + "\n")
    out.write_text("precious\n")
    assert main(["process", str(readings), "--method", "centerline", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == (f"sonarcarve: error: {readings}: line 24322, column 'range' must be > 0\n")
    assert out.read_text() == "precious\n"
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".map.csv")] == []


@pytest.mark.parametrize(("method", "options"), [
    ("carve", []),
    ("atm", ["--max-range", "1.6", "--jump-threshold", "0.5"]),
    ("combined", ["--min-range", "0.3"]),
    ("evidence", []),
])
def test_streamed_map_is_byte_identical_to_the_in_memory_one(
    tmp_path: Path, method: str, options: list[str]
) -> None:
    # Without map filters the map streams to the file; the bytes are those of the whole map.
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    n = 2_000
    k = np.arange(n)
    rng = np.random.default_rng(5)
    batch = ReadingBatch.from_arrays(
        t=0.05 * k, sensor=k % 4, x=0.01 * k, y=rng.normal(0, 0.05, n),
        theta=np.pi / 2 * (k % 4) + rng.normal(0, 0.1, n),
        range=np.where(rng.random(n) < 0.1, rng.uniform(0.2, 2.0, n), 1.5 + 0.02 * (k % 7)))
    write_readings_csv(batch, readings)
    assert main(["process", str(readings), "--method", method, "--history", "40",
                 *options, "--out", str(out)]) == 0
    spec = ReadingFilter(
        max_range=float(options[1]) if "--max-range" in options else None,
        min_range=float(options[1]) if "--min-range" in options else None,
        jump_threshold=float(options[3]) if "--jump-threshold" in options else None)
    expected = process_readings(batch, make_method(method, MethodConfig(history_size=40)),
                                reading_filter=spec if spec.active else None)
    assert len(expected.global_map) > 0
    write_map_csv(expected.global_map, tmp_path / "expected.csv")
    assert out.read_bytes() == (tmp_path / "expected.csv").read_bytes()
    if spec.active:  # the filters left gaps: ids are still input rows
        assert np.any(np.diff(read_map_csv(out).reading_id) > 1)


def test_a_failed_streamed_run_creates_no_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    _long_log(readings)
    lines = readings.read_text().splitlines()
    lines[20_001] = "oops"  # after many blocks of map rows went to the temporary file
    readings.write_text("\n".join(lines) + "\n")
    assert main(["process", str(readings), "--method", "carve", "--history", "20",
                 "--out", str(out)]) == 2
    assert "line 20002" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


def test_map_filters_keep_the_whole_map_and_still_write_it(tmp_path: Path) -> None:
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    batch = _write_ring_readings(readings, 300)
    assert main(["process", str(readings), "--method", "carve", "--history", "20",
                 "--max-error", "0.2", "--out", str(out)]) == 0
    expected = process_readings(batch, make_method("carve", MethodConfig(history_size=20)),
                                map_filter=MapFilter(max_error=0.2))
    write_map_csv(expected.global_map, tmp_path / "expected.csv")
    assert out.read_bytes() == (tmp_path / "expected.csv").read_bytes()


def test_process_help_lists_every_method(capsys: pytest.CaptureFixture[str]) -> None:
    from sonarcarve.methods import METHODS

    assert main(["process", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.replace("│", " ").split())
    option = text.split("--method -m NAME", 1)[1]  # "centerline | carve | ... . combined ..."
    names = [name.strip() for name in option.split(".", 1)[0].split("|")]
    assert names == list(METHODS)


def test_a_header_only_file_maps_to_an_empty_map_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # UX review: a header-only CSV gave exit 0 and an empty map without a word.
    empty = tmp_path / "empty.csv"
    empty.write_text("t,sensor,x,y,theta,range\n")
    out = tmp_path / "map.csv"
    assert main(["process", str(empty), "--out", str(out)]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"sonarcarve: warning: {empty} has no readings, only a header: the map is empty"]
    assert out.read_text().splitlines() == [",".join((*MAP_COLUMNS, "confidence"))]
    _write_ring_readings(tmp_path / "full.csv")
    assert main(["process", str(tmp_path / "full.csv"), "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("command", ["process", "grid"])
def test_a_last_line_without_a_line_end_is_a_warning(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str) -> None:
    """A logger killed mid-line leaves a number cut short, which still parses: say so."""
    readings = tmp_path / "cut.csv"
    # Line 4, the last, was "0.2,0,0.1,0,0,1.5625\n" before the writer died.
    readings.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,1.5\n0.1,0,0.05,0,0,1.5\n"
                        "0.2,0,0.1,0,0,1.5")
    out = tmp_path / ("map.csv" if command == "process" else "grid.yaml")
    assert main([command, str(readings), "--out", str(out)]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"sonarcarve: warning: {readings}: line 4, the last, has no line end: if the file was "
        "cut short, its last reading may be wrong (a number cut short still reads as a number)"]
    readings.write_text(readings.read_text() + "\n")
    assert main([command, str(readings), "--out", str(out)]) == 0
    assert capsys.readouterr().err == ""


def test_a_header_alone_without_a_line_end_is_warned_of_once(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """No reading to cut short: only the empty map is worth a word."""
    readings = tmp_path / "header.csv"
    readings.write_text("t,sensor,x,y,theta,range")
    assert main(["process", str(readings), "--out", str(tmp_path / "map.csv")]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"sonarcarve: warning: {readings} has no readings, only a header: the map is empty"]


def test_a_cut_log_is_warned_of_in_fleet_mode_too_and_bare_cr_lines_count(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A batch of logs is where a killed logger is likeliest (review rev6: --out-dir said
    nothing); a file whose lines end in a bare CR numbers its last line by the CRs."""
    cut = tmp_path / "cut.csv"
    cut.write_text("t,sensor,x,y,theta,range\r0,0,0,0,0,1.5\r0.1,0,0.05,0,0,1.5\r"
                   "0.2,0,0.1,0,0,1.5", newline="")
    whole = tmp_path / "whole.csv"
    whole.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,1.5\n0.1,0,0.05,0,0,1.5\n")
    assert main(["process", str(cut), str(whole), "--out-dir", str(tmp_path / "maps")]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert warnings == [
        f"sonarcarve: warning: {cut}: line 4, the last, has no line end: if the file was "
        "cut short, its last reading may be wrong (a number cut short still reads as a number)"]
