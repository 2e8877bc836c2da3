import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.io import read_map_csv, write_readings_csv
from sonarcarve.readings import ReadingBatch


def _readings(path: Path) -> ReadingBatch:
    """A robot driving along +x with one sensor looking left at a wall 1.5 m away; some rows
    are far (6 m) or near (0.1 m)."""
    n = 60
    k = np.arange(n)
    r = np.full(n, 1.5)
    r[[7, 30]] = 6.0
    r[[12]] = 0.1
    batch = ReadingBatch.from_arrays(t=0.1 * k, sensor=np.zeros(n, int), x=0.05 * k,
                                     y=np.zeros(n), theta=np.full(n, math.pi / 2), range=r)
    write_readings_csv(batch, path)
    return batch


def _run(tmp_path: Path, *options: str) -> tuple[int, Path]:
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    _readings(readings)
    return main(["process", str(readings), "--method", "centerline", "--out", str(out),
                 *options]), out


def test_reading_filters_keep_input_rows_as_ids(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    code, out = _run(tmp_path, "--max-range", "3.81", "--min-range", "0.2")
    assert code == 0
    ids = read_map_csv(out).reading_id.tolist()
    assert ids == [i for i in range(60) if i not in (7, 12, 30)]
    text = capsys.readouterr().out
    assert "beyond --max-range" in text
    assert "readings mapped" in text


def test_jump_filter_drops_the_row_after_a_spike_too(tmp_path: Path) -> None:
    code, out = _run(tmp_path, "--jump-threshold", "1.0")
    assert code == 0
    # Spikes at 7, 12 and 30 jump, and so do the readings after them (back to 1.5).
    dropped = {7, 8, 12, 13, 30, 31}
    assert read_map_csv(out).reading_id.tolist() == [i for i in range(60) if i not in dropped]


def test_map_filters_drop_outliers_and_inaccurate_points(tmp_path: Path) -> None:
    # Centerline points sit at the range along the axis: the wall row at y = 1.5 spaced 5 cm,
    # the 6 m rows 1.15 m apart at y = 6 and the 0.1 m row alone at y = 0.1.
    code, out = _run(tmp_path, "--outlier-radius", "0.2", "--outlier-neighbours", "2")
    assert code == 0
    assert read_map_csv(out).reading_id.tolist() == [i for i in range(60)
                                                     if i not in (7, 12, 30)]
    # Centerline max error is the chord for φ/2 (eq. 5.3): 2 r sin(φ/4), largest for 6 m.
    bound = 2 * 1.5 * math.sin(math.radians(22.5) / 4)
    code, out = _run(tmp_path, "--max-error", f"{bound * 1.01}")
    assert code == 0
    assert read_map_csv(out).reading_id.tolist() == [i for i in range(60) if i not in (7, 30)]


def test_occlusion_filter_drops_echoes_read_through_the_wall(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Rows 7 and 30 read 6 m straight through the wall the other rows hear at 1.5 m. The wall's
    # centerline points have an error bound of 0.29 m (eq. 5.3), and only points whose bound
    # is at most half the depth make up a wall: 0.5 m would let no point block, 0.6 m does.
    code, out = _run(tmp_path, "--occlusion-depth", "0.5")
    assert code == 0
    assert len(read_map_csv(out)) == 60
    code, out = _run(tmp_path, "--occlusion-depth", "0.6")
    assert code == 0
    assert read_map_csv(out).reading_id.tolist() == [i for i in range(60) if i not in (7, 30)]
    assert "dropped: behind a surface" in capsys.readouterr().out
    # 4.5 m behind the wall: a depth beyond that keeps them.
    code, out = _run(tmp_path, "--occlusion-depth", "4.6")
    assert code == 0
    assert len(read_map_csv(out)) == 60


def _forward_and_left(path: Path) -> None:
    """A Scout2 driving +x at 0.5 m/s, its centre from x = -0.205 to 2.745; even rows: sensor 4
    (on the left side) hears a wall 1.5 m away; odd rows: sensor 0 (at the front, x) hears
    something 0.52 m ahead, where the sensor passes about a second later."""
    n = 60
    k = np.arange(n)
    odd = k % 2 == 1
    x = 0.05 * k
    write_readings_csv(ReadingBatch.from_arrays(
        t=0.1 * k, sensor=np.where(odd, 0, 4), x=np.where(odd, x, x - 0.205),
        y=np.where(odd, 0.0, 0.205), theta=np.where(odd, 0.0, math.pi / 2),
        range=np.where(odd, 0.52, 1.5)), path)


@pytest.mark.parametrize(("body", "last"), [("0.1", 49), ("scout2", 47)])
def test_driven_through_drops_what_the_robot_drove_over(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], body: str, last: int) -> None:
    # Odd row k's point lies at x = 0.05 k + 0.52. Sensor 0 ends at x = 2.95: a disc of 0.1 m
    # around the sensors reaches 3.05 (k up to 49), the Scout2's body (a 0.205 m disc around
    # the centre, recovered from either sensor's mount) 2.95 (k up to 47).
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    _forward_and_left(readings)
    code = main(["process", str(readings), "--method", "centerline", "--out", str(out),
                 "--driven-through", body])
    assert code == 0
    dropped = set(range(1, last + 1, 2))
    assert read_map_csv(out).reading_id.tolist() == [i for i in range(60) if i not in dropped]
    assert "dropped: driven through" in capsys.readouterr().out


@pytest.mark.parametrize(("options", "text"), [
    (["--max-range", "-1"], "--max-range must be a finite number > 0"),
    (["--min-range", "nan"], "--min-range must be"),
    (["--max-range", "1", "--min-range", "2"], "--min-range (2.0) exceeds --max-range (1.0)"),
    (["--jump-threshold", "0"], "--jump-threshold must be"),
    (["--outlier-radius", "inf"], "--outlier-radius must be"),
    (["--outlier-radius", "1", "--outlier-neighbours", "0"], "--outlier-neighbours must be"),
    (["--outlier-neighbours", "3"], "--outlier-neighbours needs --outlier-radius"),
    (["--max-error", "-0.5"], "--max-error must be"),
    (["--occlusion-depth", "0"], "--occlusion-depth must be a finite number > 0"),
    (["--occlusion-depth", "inf"], "--occlusion-depth must be"),
    (["--driven-through", "0"], "--driven-through must be a robot (name or YAML) or a "
                                "clearance radius > 0"),
    (["--driven-through", "-inf"], "--driven-through must be"),
    (["--driven-through", "no-such-robot"], "no-such-robot"),
    (["--late-echo-period", "0"], "--late-echo-period must be a robot (name or YAML) or a "
                                  "firing period in 0.0001..3600 (seconds)"),
    (["--late-echo-period", "1e-9"], "--late-echo-period must be"),
    (["--late-echo-period", "5000"], "--late-echo-period must be"),
    (["--late-echo-period", "0.04s"], "--late-echo-period takes plain seconds (0.04)"),
    (["--late-echo-period", "40 ms"], "--late-echo-period takes plain seconds"),
    (["--late-echo-period", "nan"], "--late-echo-period must be"),
    (["--late-echo-period", "no-such-robot"], "no-such-robot"),
])
def test_bad_filter_values_are_one_line_errors(tmp_path: Path, options: list[str], text: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    code, out = _run(tmp_path, *options)
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert text in err
    assert len(err.splitlines()) == 1
    assert not out.exists()


def _ghost_wall(path: Path) -> None:
    """One sensor at the origin facing +x, a narrow beam (0.05 rad), firing every 0.02 s: ten
    echoes of a wall at x = 4, then ten late echoes of it, read c·Δt/2 = 343 × 0.02 / 2 =
    3.43 m short, at 0.57 m."""
    n = 20
    r = np.where(np.arange(n) < 10, 4.0, 4.0 - 3.43)
    batch = ReadingBatch.from_arrays(t=0.02 * np.arange(n), sensor=np.zeros(n, int),
                                     x=np.zeros(n), y=np.zeros(n), theta=np.zeros(n), range=r,
                                     beam_width=np.full(n, 0.05))
    write_readings_csv(batch, path)


@pytest.mark.parametrize("period", ["0.02", "0.025"])
def test_late_echo_period_drops_the_ghost_wall_and_keeps_the_wall(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], period: str) -> None:
    # With the right period the far point of each 0.57 m echo is the wall at 4 m: dropped.
    # With 0.025 s it is 0.57 + 4.29 = 4.86 m (lag 1) or 9.15 m (lag 2): no wall there, kept.
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    _ghost_wall(readings)
    code = main(["process", str(readings), "--method", "centerline", "--out", str(out),
                 "--late-echo-period", period])
    assert code == 0
    kept = read_map_csv(out).reading_id.tolist()
    assert kept == (list(range(10)) if period == "0.02" else list(range(20)))
    assert "dropped: late echoes" in capsys.readouterr().out


@pytest.mark.parametrize(("option", "text"), [
    ("--driven-through", "--driven-through must be a robot (name or YAML) or a clearance"),
    ("--late-echo-period", "--late-echo-period must be a robot (name or YAML) or a firing"),
])
def test_an_empty_robot_or_number_is_named(tmp_path: Path, option: str, text: str,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    # An empty value was read as the robot file "." and failed with ".: is a directory".
    code, out = _run(tmp_path, option, "")
    assert code == 2
    assert text in capsys.readouterr().err
    assert not out.exists()


def test_a_bag_output_names_every_map_filter_it_refuses(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    readings = tmp_path / "r.csv"
    _readings(readings)
    code = main(["process", str(readings), "--out", str(tmp_path / "run.mcap"),
                 "--late-echo-period", "0.04"])
    assert code == 2
    assert "--late-echo-period" in capsys.readouterr().err


def test_a_robot_without_a_radius_drives_through_with_its_sensors_hull(tmp_path: Path) -> None:
    # robot_radius 0 is a valid robot file; its body is then the hull of its mounts, which for
    # the Scout2's 16 sensors on its rim is the 16-gon the 0.205 m disc makes: the same map.
    from importlib.resources import files

    text = (files("sonarcarve") / "robots" / "scout2.yaml").read_text()
    robot = tmp_path / "rimless.yaml"
    robot.write_text(text.replace("robot_radius: 0.205", "robot_radius: 0.0"))
    readings, out = tmp_path / "r.csv", tmp_path / "map.csv"
    _forward_and_left(readings)
    code = main(["process", str(readings), "--method", "centerline", "--out", str(out),
                 "--driven-through", str(robot)])
    assert code == 0
    dropped = set(range(1, 48, 2))
    assert read_map_csv(out).reading_id.tolist() == [i for i in range(60) if i not in dropped]
