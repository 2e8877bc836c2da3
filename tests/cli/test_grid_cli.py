"""``sonarcarve grid``: map_server files from a readings CSV; one-line errors, exit 2."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import sonarcarve.cli.grid  # noqa: F401  # registers the command on the app
from sonarcarve.cli import main
from sonarcarve.io.map_server import read_map_server
from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.readings import Reading, ReadingBatch


@pytest.fixture
def readings(tmp_path: Path) -> Path:
    """A robot driving along a wall 1 m to its left, its sensor facing the wall."""
    batch = ReadingBatch.from_readings(
        Reading(t=0.1 * k, sensor=0, x=0.05 * k, y=0.0, theta=math.pi / 2, range=1.0)
        for k in range(60))
    path = tmp_path / "readings.csv"
    write_readings_csv(batch, path)
    return path


@pytest.mark.parametrize("model", ["carved", "range-sensor-layer", "elfes"])
def test_writes_a_map_server_map(readings: Path, tmp_path: Path, model: str) -> None:
    out = tmp_path / "grid.yaml"
    assert main(["grid", str(readings), "--model", model, "--resolution", "0.1",
                 "--out", str(out)]) == 0
    m = read_map_server(out)
    assert m.resolution == 0.1
    rows, cols = m.cells.shape
    # The readings' extent (x 0..2.95 plus the arcs' ends, y 0..1) plus the 0.5 m margin.
    assert m.origin[0] < -0.5 + 1e-9
    assert m.origin[1] == pytest.approx(-0.5)
    assert m.origin[1] + rows * 0.1 == pytest.approx(1.5, abs=0.1)
    xs = m.origin[0] + (np.arange(cols) + 0.5) * 0.1
    ys = m.origin[1] + (np.arange(rows) + 0.5) * 0.1
    occupied_y = ys[np.nonzero(m.cells == 100)[0]]
    assert occupied_y.size
    assert np.all(np.abs(occupied_y - 1.0) <= 0.15)  # the wall
    assert np.any(m.cells == 0)
    assert xs.size == cols


@pytest.mark.parametrize(("args", "message"), [
    (["--model", "octomap"], "--model must be one of carved | range-sensor-layer | elfes"),
    (["--resolution", "0"], "--resolution must be a finite number > 0"),
    (["--resolution", "abc"], "'abc' is not a number"),
    (["--margin", "-1"], "--margin must be a finite number >= 0"),
    # UX review, finding 9: a one-cell map was written.
    (["--resolution", "1e9"], "--resolution 1e+09 m is larger than the area mapped ("),
    (["--resolution", "5", "--margin", "0"], "--resolution 5 m is larger than the area mapped"),
    (["--fresh-periods", "0.5"], "--fresh-periods must be a number >= 1 firing period"),
    (["--fresh-periods", "nan"], "--fresh-periods must be a number >= 1 firing period"),
    (["--fresh-periods", "2", "--model", "elfes"], "applies to --model carved only, not elfes"),
    (["--fresh-periods", "inf", "--model", "range-sensor-layer"],
     "applies to --model carved only, not range-sensor-layer"),
    (["--free-below", "0.7"], "--free-below must lie in (0, 0.65), got 0.7"),
    (["--free-below", "0"], "--free-below must lie in (0, 0.65), got 0"),
    (["--free-below", "0.2", "--model", "elfes"], "--free-below applies to --model carved only"),
    (["--pose-sigma", "-0.1"], "--pose-sigma must be a finite number >= 0 metres, got -0.1"),
    (["--pose-sigma", "0.05", "--model", "range-sensor-layer"],
     "--pose-sigma applies to --model carved only, not range-sensor-layer"),
    (["--range-tolerance", "-0.1"], "--range-tolerance must be a number in [0, 1] metres"),
    (["--range-tolerance", "1e9"], "--range-tolerance must be a number in [0, 1] metres"),
    (["--range-tolerance", "0.9", "--pose-sigma", "0.1"],
     "--range-tolerance + 2 --pose-sigma (the ε it carves with) must be at most 1 m, "
     "got 1.1"),
    (["--range-tolerance", "0.1", "--model", "elfes"],
     "--range-tolerance applies to --model carved only, not elfes"),
    (["--mark-length", "-0.1"], "--mark-length must be a finite number >= 0 metres"),
    (["--mark-length", "inf"], "--mark-length must be a finite number >= 0 metres"),
    (["--mark-length", "0.2", "--model", "elfes"],
     "--mark-length applies to --model carved only, not elfes"),
])
def test_bad_options_are_one_line_errors(readings: Path, tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str],
                                         args: list[str], message: str) -> None:
    out = tmp_path / "grid.yaml"
    assert main(["grid", str(readings), "--out", str(out), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("sonarcarve: error: ")
    assert message in err
    assert not out.exists()
    assert not out.with_suffix(".pgm").exists()


def test_bad_paths_are_one_line_errors(readings: Path, tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["grid", str(tmp_path / "none.csv"), "--out", str(tmp_path / "g.yaml")]) == 2
    assert "no such file" in capsys.readouterr().err
    missing = tmp_path / "no" / "g.yaml"
    assert main(["grid", str(readings), "--out", str(missing)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "does not exist" in err
    assert main(["grid", str(readings), "--out", str(tmp_path / "g.txt")]) == 2
    assert ".yaml" in capsys.readouterr().err
    # User review: `--out grid.png` was refused only once the grid was built, and without
    # naming the option; now before anything is read (so not the missing input's error).
    png = tmp_path / "grid.png"
    assert main(["grid", str(tmp_path / "none.csv"), "--out", str(png)]) == 2
    assert capsys.readouterr().err == (f"sonarcarve: error: --out {png}: a map_server map's "
                                       "name must end in .yaml (GRID.pgm goes beside it)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["readings.csv"]


def test_an_empty_csv_names_the_file(tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    csv = tmp_path / "empty.csv"
    csv.write_text("t,sensor,x,y,theta,range\n")
    assert main(["grid", str(csv), "--out", str(tmp_path / "g.yaml")]) == 2
    assert capsys.readouterr().err == f"sonarcarve: error: {csv}: no readings to map\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty.csv"]


def test_ranges_in_millimetres_warn_one_line_and_exit_0(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    batch = ReadingBatch.from_readings(
        Reading(t=0.1 * k, sensor=0, x=0.05 * k, y=0.0, theta=math.pi / 2, range=1000.0)
        for k in range(20))
    path = tmp_path / "millimetres.csv"
    write_readings_csv(batch, path)
    assert main(["grid", str(path), "--resolution", "10", "--out",
                 str(tmp_path / "grid.yaml")]) == 0
    assert capsys.readouterr().err.splitlines() == [
        "sonarcarve: warning: the median range is 1000 m: is it in millimetres? (readings CSV "
        "range is metres)"]


def test_a_semicolon_separated_file_gets_a_hint(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "semicolons.csv"
    path.write_text("t;sensor;x;y;theta;range\n0;0;0;0;0;1\n")
    assert main(["grid", str(path), "--out", str(tmp_path / "grid.yaml")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith("sonarcarve: error: ")
    assert "the file looks separated by ';': the readings CSV is comma-separated" in err


@pytest.mark.parametrize("model", ["carved", "range-sensor-layer", "elfes"])
def test_a_log_with_no_echo_readings_maps_over_their_max_range(tmp_path: Path,
                                                               model: str) -> None:
    # The wall readings of the fixture, then silent firings facing away from it (-y) that
    # listened 2 m: the grid reaches 2 m below the path, plus the 0.5 m margin.
    wall = [Reading(t=0.1 * k, sensor=0, x=0.05 * k, y=0.0, theta=math.pi / 2, range=1.0)
            for k in range(60)]
    silent = [Reading(t=6.0 + 0.1 * k, sensor=1, x=0.05 * k, y=0.0, theta=-math.pi / 2,
                      range=math.inf, max_range=2.0) for k in range(20)]
    path = tmp_path / "readings.csv"
    write_readings_csv(ReadingBatch.from_readings(wall + silent), path)
    out = tmp_path / "grid.yaml"
    assert main(["grid", str(path), "--model", model, "--resolution", "0.1",
                 "--out", str(out)]) == 0
    m = read_map_server(out)
    assert m.origin[1] == pytest.approx(-2.5, abs=1e-9)
    rows, _ = m.cells.shape
    assert m.origin[1] + rows * 0.1 == pytest.approx(1.5, abs=0.1)


def _echoes_then_silence(path: Path) -> None:
    """A turning robot's sensor 0 firing every 0.1 s: six echoes from far walls in other
    directions (its firing period), then one from an obstacle 1 m ahead at 0.6 s, then its
    firings hear nothing and are left out of the log; sensor 1 logs on, away from the obstacle,
    for 0.7 s."""
    turning = [Reading(t=0.1 * k, sensor=0, x=0.0, y=0.0, theta=math.pi / 2 + 0.5 * k,
                       range=3.0) for k in range(6)]
    ahead = [Reading(t=0.6, sensor=0, x=0.0, y=0.0, theta=0.0, range=1.0)]
    later = [Reading(t=0.6 + 0.1 * k, sensor=1, x=0.0, y=0.0, theta=math.pi, range=3.0)
             for k in range(1, 8)]
    write_readings_csv(ReadingBatch.from_readings(turning + ahead + later), path)


@pytest.mark.parametrize(("periods", "marked"), [(None, False), ("inf", True), ("20", True)])
def test_fresh_periods_decides_how_long_the_newest_echo_stays_marked(
        tmp_path: Path, periods: str | None, marked: bool) -> None:
    """0.7 s after the obstacle's echo its sensor has missed 6 firings: by default (1.1
    periods) the mark has ended, and one echo's spread alone does not mark the obstacle; with
    ``inf`` (kept up to 2 s) or 20 periods the mark is still there."""
    log = tmp_path / "log.csv"
    _echoes_then_silence(log)
    out = tmp_path / "grid.yaml"
    extra = [] if periods is None else ["--fresh-periods", periods]
    assert main(["grid", str(log), "--resolution", "0.05", "--out", str(out), *extra]) == 0
    m = read_map_server(out)
    j = int((1.0 - m.origin[0]) / 0.05)
    i = int((0.0 - m.origin[1]) / 0.05)
    ahead = m.cells[max(0, i - 2):i + 3, max(0, j - 2):j + 3]
    assert bool(np.any(ahead == 100)) is marked


def test_free_below_decides_how_much_evidence_frees_a_cell(tmp_path: Path) -> None:
    """Three echoes at 2 m from one pose: the cells before the echo have three misses each,
    between map_saver's 0.196 and the default 0.35 on the beam's axis at 0.65 m (see
    tests/grids/test_carved_free_threshold.py): free by default, unknown with --free-below 0.196,
    and the default's free cells a superset of the stricter map's."""
    log = tmp_path / "log.csv"
    beam = [Reading(t=0.2 * k, sensor=0, x=0.0, y=0.0, theta=0.0, range=2.0) for k in range(3)]
    write_readings_csv(ReadingBatch.from_readings(beam), log)
    maps = {}
    for extra in ([], ["--free-below", "0.196"]):
        out = tmp_path / f"grid{len(extra)}.yaml"
        assert main(["grid", str(log), "--resolution", "0.1", "--out", str(out), *extra]) == 0
        maps[bool(extra)] = read_map_server(out)
    default, strict = maps[False], maps[True]
    j = int((0.65 - default.origin[0]) / 0.1)
    i = int((0.0 - default.origin[1]) / 0.1)
    assert default.cells[i, j] == 0
    assert strict.cells[i, j] == -1
    assert np.all(default.cells[strict.cells == 0] == 0)
    assert np.count_nonzero(default.cells == 0) > np.count_nonzero(strict.cells == 0)


def test_a_stray_position_too_large_a_grid_is_named(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # One pose of a drive along y = 0 glitched to x = 900 km (a GPS jump, a bad odometry
    # sample): the grid would be 18 million cells wide; the error shows where that came from.
    batch = ReadingBatch.from_readings(
        Reading(t=0.1 * k, sensor=0, x=900_000.0 if k == 7 else 0.05 * k, y=0.0,
                theta=math.pi / 2, range=1.0)
        for k in range(20))
    path = tmp_path / "glitch.csv"
    write_readings_csv(batch, path)
    out = tmp_path / "grid.yaml"
    assert main(["grid", str(path), "--resolution", "0.05", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "exceed the limit" in err
    # The readings' extent plus the 0.5 m margin (the first arc's edge reaches sin 11.25° =
    # 0.19509 m left of x = 0): the stray pose stands out.
    assert "over x from -0.69509 to 900001 m and y from -0.5 to 1.5 m" in err
    assert not out.exists()


def _free_reach(tmp_path: Path, extra: list[str]) -> float:
    """How far the free cells on the beam's axis reach, metres (the far edge of the last), in
    the grid of ten echoes at 1 m from one pose (near enough that the fade leaves every beam
    cell free), 0.05 m cells, with the options ``extra``."""
    log = tmp_path / "log.csv"
    beam = [Reading(t=0.2 * k, sensor=0, x=0.0, y=0.0, theta=0.0, range=1.0) for k in range(10)]
    write_readings_csv(ReadingBatch.from_readings(beam), log)
    out = tmp_path / f"grid{len(extra)}.yaml"
    assert main(["grid", str(log), "--resolution", "0.05", "--out", str(out), *extra]) == 0
    m = read_map_server(out)
    i = int((0.0 - m.origin[1]) / 0.05)
    free = np.flatnonzero(m.cells[i] == 0)
    return float(m.origin[0] + (free.max() + 1) * 0.05)


def test_pose_sigma_ends_free_space_two_sigma_before_the_echo(tmp_path: Path) -> None:
    """The free cells reach the echo's band, b = (h + ε) / 2 = 0.05 m, by default, and 2 x
    0.2 m short of it with --pose-sigma 0.2."""
    assert _free_reach(tmp_path, []) == pytest.approx(0.95, abs=0.05 + 1e-9)
    assert _free_reach(tmp_path, ["--pose-sigma", "0.2"]) == pytest.approx(0.55, abs=0.05 + 1e-9)


def test_range_tolerance_thickens_the_echo_band(tmp_path: Path) -> None:
    """The band reaches b = (h + ε) / 2 before the echo: 0.05 m by default (ε 0.05 m, h 0.05 m),
    0.25 m with --range-tolerance 0.45, so the free cells on the axis end 0.2 m sooner."""
    assert _free_reach(tmp_path, ["--range-tolerance", "0.45"]) == pytest.approx(
        0.75, abs=0.05 + 1e-9)


def test_mark_length_sets_how_much_of_the_newest_arc_is_occupied(tmp_path: Path) -> None:
    """One echo at 2 m, nothing else on the map: by default the mark is the echo's own cell
    (and the cell beside it the half-cell widening reaches); --mark-length 0.4 marks 0.4 m of
    the arc (about 9 cells of 0.05 m) occupied."""
    log = tmp_path / "log.csv"
    write_readings_csv(ReadingBatch.from_readings(
        [Reading(t=0.0, sensor=0, x=0.0, y=0.0, theta=0.0, range=2.0)]), log)
    occupied = {}
    for extra in ([], ["--mark-length", "0.4"]):
        out = tmp_path / f"grid{len(extra)}.yaml"
        assert main(["grid", str(log), "--resolution", "0.05", "--out", str(out), *extra]) == 0
        occupied[bool(extra)] = int(np.count_nonzero(read_map_server(out).cells == 100))
    assert 1 <= occupied[False] <= 3
    assert occupied[True] >= 8


@pytest.mark.parametrize("model", ["carved", "range-sensor-layer", "elfes"])
def test_beam_width_fills_readings_that_carry_none(readings: Path, tmp_path: Path,
                                                   model: str) -> None:
    # User review: a bag whose Range messages leave field_of_view 0 (or a CSV without the
    # column) could be gridded only with a 22.5° cone; process had --beam-width, grid not.
    wide = ReadingBatch.from_readings(
        Reading(t=0.1 * k, sensor=0, x=0.05 * k, y=0.0, theta=math.pi / 2, range=1.0,
                beam_width=math.radians(60.0))
        for k in range(60))
    written = tmp_path / "wide.csv"
    write_readings_csv(wide, written)

    def cells(source: Path, *args: str) -> np.ndarray:
        out = tmp_path / "grid.yaml"
        assert main(["grid", str(source), "--model", model, "--resolution", "0.1",
                     "--out", str(out), *args]) == 0
        return read_map_server(out).cells

    default = cells(readings)
    np.testing.assert_array_equal(cells(readings, "--beam-width", "22.5"), default)
    given = cells(readings, "--beam-width", "60")
    np.testing.assert_array_equal(given, cells(written))  # as if the CSV had said 60°
    assert given.shape != default.shape or np.any(given != default)
    # A beam_width column wins.
    np.testing.assert_array_equal(cells(written, "--beam-width", "10"), given)


def test_a_beam_width_out_of_range_is_one_line(readings: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "grid.yaml"
    assert main(["grid", str(readings), "--beam-width", "180", "--out", str(out)]) == 2
    assert capsys.readouterr().err == ("sonarcarve: error: --beam-width must lie in (0, 180) "
                                       "degrees, got 180\n")
    assert not out.exists()


@pytest.mark.parametrize(("sensors", "model", "noted"), [
    (1, "carved", True), (2, "carved", True), (3, "carved", False),
    (1, "range-sensor-layer", False), (1, "elfes", False)])
def test_a_carved_grid_of_one_or_two_sonars_notes_the_layer_frees_more(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], sensors: int, model: str,
        noted: bool) -> None:
    batch = ReadingBatch.from_readings(
        Reading(t=0.1 * k, sensor=k % sensors, x=0.05 * k, y=0.0, theta=math.pi / 2, range=1.0)
        for k in range(60))
    path = tmp_path / "readings.csv"
    write_readings_csv(batch, path)
    assert main(["grid", str(path), "--model", model, "--resolution", "0.1",
                 "--out", str(tmp_path / "grid.yaml")]) == 0
    out = " ".join(capsys.readouterr().out.split())  # rich wraps at the terminal's width
    plural = "s" if sensors > 1 else ""
    assert (f"Few sonars: {sensors} sonar{plural} in this log." in out) is noted
    assert ("--model range-sensor-layer frees more of the floor" in out) is noted
