"""``sonarcarve grid BAG``: a ROS bag maps to the grid its readings map to through a readings
CSV; the bag options mean what they mean for ``process``; bad input is one line, exit 2, and
writes nothing."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import sonarcarve.cli.grid  # noqa: F401  # registers the command on the app
from sonarcarve.cli import main
from sonarcarve.fleet import BagOptions, read_log
from sonarcarve.io.bag_out import BagWriter, quaternion, stamp
from sonarcarve.io.map_server import MapServerMap, read_map_server
from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.readings import Reading, ReadingBatch

pytest.importorskip("rosbags")

MODELS = ["carved", "range-sensor-layer", "elfes"]
# A short, seeded doorway run, as the process tests use (scout2: some firings hear nothing).
SIM = ["simulate", "--world", "doorway", "--seed", "3"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One simulation written as readings CSVs (r.csv; silent.csv with its no-echo rows) and
    as bags (run.mcap, run.bag, a rosbag2 folder run_folder)."""
    folder = tmp_path_factory.mktemp("grid-runs")
    for name in ("r.csv", "run.mcap", "run.bag", "run_folder"):
        assert main([*SIM, "--out", str(folder / name)]) == 0
    assert main([*SIM, "--no-echo", "--out", str(folder / "silent.csv")]) == 0
    return folder


def _grid(source: Path, out: Path, *args: str) -> MapServerMap:
    assert main(["grid", str(source), "--resolution", "0.05", "--out", str(out), *args]) == 0
    return read_map_server(out)


def _assert_same_grid(got: MapServerMap, expected: MapServerMap, atol: float) -> None:
    """The same cells, resolution and thresholds; the origin to ``atol`` metres."""
    np.testing.assert_array_equal(got.cells, expected.cells)
    assert got.resolution == expected.resolution
    assert (got.occupied_thresh, got.free_thresh) == (expected.occupied_thresh,
                                                     expected.free_thresh)
    np.testing.assert_allclose(got.origin, expected.origin, rtol=0.0, atol=atol)


@pytest.mark.parametrize("model", MODELS)
def test_a_bag_grids_as_the_simulators_csv(runs: Path, tmp_path: Path, model: str) -> None:
    """simulate → bag → grid equals simulate → CSV → grid: the same cells; the origin to
    float32 precision (Range.range and field_of_view are float32, ~2e-7 m here)."""
    from_csv = _grid(runs / "r.csv", tmp_path / "csv.yaml", "--model", model)
    from_bag = _grid(runs / "run.mcap", tmp_path / "bag.yaml", "--model", model)
    assert np.count_nonzero(from_csv.cells == 100) > 10  # a real map, not an empty one
    assert np.count_nonzero(from_csv.cells == 0) > 50
    _assert_same_grid(from_bag, from_csv, atol=1e-6)
    assert from_bag.image == "bag.pgm"


@pytest.mark.parametrize("name", ["run.bag", "run_folder"])
def test_ros1_bags_and_rosbag2_folders_grid_as_the_mcap(runs: Path, tmp_path: Path,
                                                        name: str) -> None:
    mcap = _grid(runs / "run.mcap", tmp_path / "mcap.yaml")
    other = _grid(runs / name, tmp_path / "other.yaml")
    _assert_same_grid(other, mcap, atol=0.0)


def test_a_bag_grids_as_its_readings_written_to_a_csv(runs: Path, tmp_path: Path) -> None:
    """The bag's readings as the library reads them, written to a readings CSV, give the same
    files byte for byte (but the image's name in the YAML)."""
    for no_echo in (False, True):
        flag = ["--no-echo"] if no_echo else []
        csv = tmp_path / f"converted-{no_echo}.csv"
        write_readings_csv(read_log(runs / "run.mcap", BagOptions(no_echo=no_echo)), csv)
        from_csv, from_bag = tmp_path / f"csv-{no_echo}.yaml", tmp_path / f"bag-{no_echo}.yaml"
        _grid(csv, from_csv)
        _grid(runs / "run.mcap", from_bag, *flag)
        image = from_bag.with_suffix(".pgm").read_bytes()
        assert image == from_csv.with_suffix(".pgm").read_bytes(), no_echo
        assert from_bag.read_text().replace("bag-", "csv-") == from_csv.read_text(), no_echo


@pytest.mark.parametrize("model", MODELS)
def test_no_echo_from_a_bag_or_a_csv_gives_the_same_grid(runs: Path, tmp_path: Path,
                                                         model: str) -> None:
    """Silent firings two ways: `simulate --no-echo` writes them into the CSV (range inf,
    max_range); the bag holds them as +Inf and `grid --no-echo` keeps them."""
    from_csv = _grid(runs / "silent.csv", tmp_path / "csv.yaml", "--model", model)
    from_bag = _grid(runs / "run.mcap", tmp_path / "bag.yaml", "--model", model, "--no-echo")
    echoes = _grid(runs / "run.mcap", tmp_path / "echoes.yaml", "--model", model)
    _assert_same_grid(from_bag, from_csv, atol=1e-6)
    # Their max_range widens the grid's extent whichever model maps them.
    assert from_bag.cells.size > echoes.cells.size


def test_the_summary_counts_the_no_echo_readings_a_bag_dropped(
        runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Without --no-echo a bag's silent firings are dropped, and the summary says how many:
    the inf rows `simulate --no-echo` wrote for the same run (the oracle). With --no-echo they
    are mapped and counted in the readings row instead; a CSV drops none."""
    rows = (runs / "silent.csv").read_text().splitlines()[1:]
    silent = sum(row.split(",")[5] == "inf" for row in rows)
    assert silent > 0
    capsys.readouterr()
    _grid(runs / "run.mcap", tmp_path / "a.yaml")
    text = " ".join(capsys.readouterr().out.split())
    assert f"dropped: no-echo readings (--no-echo) │ {silent:,}" in text
    _grid(runs / "run.mcap", tmp_path / "b.yaml", "--no-echo")
    text = " ".join(capsys.readouterr().out.split())
    assert "dropped: no-echo" not in text
    assert f"({silent:,} no-echo)" in text
    _grid(runs / "r.csv", tmp_path / "c.yaml")
    assert "no-echo" not in capsys.readouterr().out


# -- a hand-made bag: a robot driving along a wall 1 m to its left, a second sensor facing
# -- away from the wall into open space that hears nothing (+Inf) up to its 2 m.

# Odometry and firings at t = 0.1 k, 0.02 m apart along +x: a cell is free once a few
# beams have crossed it.
_STEPS, _STEP = 80, 0.02


def _write_bag(path: Path, *, silent_only: bool = False, with_ranges: bool = True) -> Path:
    with BagWriter(path) as out:
        out.write("/tf_static", "tf2_msgs/msg/TFMessage", 0.0, {"transforms": [{
            "header": {"stamp": stamp(0.0), "frame_id": "base_link"},
            "child_frame_id": f"sonar_{i}",
            "transform": {"translation": {"x": 0.0, "y": 0.0},
                          "rotation": quaternion(bearing)},
        } for i, bearing in enumerate((math.pi / 2, -math.pi / 2))]})
        for k in range(_STEPS):
            t = 0.1 * k
            out.write("/odom", "nav_msgs/msg/Odometry", t, {
                "header": {"stamp": stamp(t), "frame_id": "odom"},
                "child_frame_id": "base_link",
                "pose": {"pose": {"position": {"x": _STEP * k, "y": 0.0},
                                  "orientation": quaternion(0.0)}}})
            if not with_ranges:
                continue
            for i, heard in enumerate((1.0, math.inf)):
                out.write(f"/sonar/{i}", "sensor_msgs/msg/Range", t, {
                    "header": {"stamp": stamp(t), "frame_id": f"sonar_{i}"},
                    "radiation_type": 0, "field_of_view": 0.3, "min_range": 0.1,
                    "max_range": 2.0, "range": math.inf if silent_only else heard})
    return path


def _cell_rows(m: MapServerMap, y_low: float, y_high: float) -> np.ndarray:
    """The grid's rows whose cell centres lie in (y_low, y_high), over the robot's path."""
    rows, cols = m.cells.shape
    ys = m.origin[1] + (np.arange(rows) + 0.5) * m.resolution
    xs = m.origin[0] + (np.arange(cols) + 0.5) * m.resolution
    inside = (xs > 0.3) & (xs < _STEP * (_STEPS - 1) - 0.3)
    return m.cells[(ys > y_low) & (ys < y_high)][:, inside]


@pytest.mark.parametrize("model", MODELS)
def test_silent_firings_clear_the_open_side_with_no_echo(tmp_path: Path, model: str) -> None:
    bag = _write_bag(tmp_path / "wall.mcap")
    echoes = _grid(bag, tmp_path / "echoes.yaml", "--model", model)
    silent = _grid(bag, tmp_path / "silent.yaml", "--model", model, "--no-echo")
    # Echoes only: the grid ends at the margin below the path; the wall is mapped.
    assert echoes.origin[1] == pytest.approx(-0.5, abs=1e-9)
    assert np.any(_cell_rows(echoes, 0.9, 1.1) == 100)
    # With the silent firings: down to their 2 m plus the margin, and free below the path
    # (the carved and Elfes grids; as in front of the wall, from 0.4 m out, and not past
    # about 1.45 m, where the free-space update, faded past d_f = 1.2 m as ROS fades it, no
    # longer reaches the free threshold);
    # ROS's layer drops +Inf, as ROS does, leaving it unknown.
    assert silent.origin[1] == pytest.approx(-2.5, abs=1e-9)
    below = _cell_rows(silent, -1.35, -0.45)
    assert below.size
    if model == "range-sensor-layer":
        assert np.all(below == -1)
    else:
        assert np.all(below == 0)
    assert np.any(_cell_rows(silent, 0.9, 1.1) == 100)


def test_the_hand_made_bag_grids_as_the_same_readings_written_by_hand(tmp_path: Path) -> None:
    """The readings the bag holds, written as a CSV without the bag reader (ranges, beam
    widths and max ranges as float32 holds them): the same grid, echoes and no-echo rows."""
    bag = _write_bag(tmp_path / "wall.mcap")
    fov = float(np.float32(0.3))
    readings = []
    for k in range(_STEPS):
        readings.append(Reading(t=0.1 * k, sensor=0, x=_STEP * k, y=0.0, theta=math.pi / 2,
                                range=1.0, beam_width=fov, max_range=2.0))
        readings.append(Reading(t=0.1 * k, sensor=1, x=_STEP * k, y=0.0, theta=-math.pi / 2,
                                range=math.inf, beam_width=fov, max_range=2.0))
    csv = tmp_path / "by-hand.csv"
    write_readings_csv(ReadingBatch.from_readings(readings), csv)
    for model in MODELS:
        from_csv = _grid(csv, tmp_path / f"csv-{model}.yaml", "--model", model)
        from_bag = _grid(bag, tmp_path / f"bag-{model}.yaml", "--model", model, "--no-echo")
        _assert_same_grid(from_bag, from_csv, atol=1e-9)


@pytest.mark.parametrize("model", MODELS)
def test_convert_no_echo_keeps_the_free_space_grid_no_echo_takes_from_the_bag(
        runs: Path, tmp_path: Path, model: str) -> None:
    """bag → convert rosbag --no-echo → CSV → grid equals grid BAG --no-echo (before, convert
    always dropped the +Inf firings, so the CSV's carved grid missed their free space)."""
    csv = tmp_path / "converted.csv"
    assert main(["convert", "rosbag", str(runs / "run.mcap"), "--no-echo", "--out", str(csv)]) == 0
    assert "inf" in csv.read_text()
    from_bag = _grid(runs / "run.mcap", tmp_path / "bag.yaml", "--model", model, "--no-echo")
    from_csv = _grid(csv, tmp_path / "csv.yaml", "--model", model)
    _assert_same_grid(from_csv, from_bag, atol=1e-12)


# -- bad input: one line on stderr naming the problem and where, exit 2, nothing written.

_CSV_WITH_BAG_OPTION = {"csv-robot": ["--robot", "scout2"],
                        "csv-range-topic": ["--range-topic", "/sonar/0"],
                        "csv-odom-topic": ["--odom-topic", "/odom"],
                        "csv-frame": ["--frame", "base_link"],
                        "csv-no-echo": ["--no-echo"]}
_BAD = ["corrupt", "truncated", "not-ros1", "absent", "no-range-topic", "all-silent",
        "unknown-range-topic", "unknown-odom-topic", "unknown-robot", "robot-misfit",
        *_CSV_WITH_BAG_OPTION]


@pytest.fixture(scope="module")
def bad_requests(runs: Path, tmp_path_factory: pytest.TempPathFactory,
                 ) -> dict[str, tuple[list[str], str]]:
    """Name -> (arguments before --out, words of the one-line error)."""
    inputs = tmp_path_factory.mktemp("bad-inputs")
    corrupt = inputs / "corrupt.mcap"
    corrupt.write_bytes(b"\x89MCAP0\r\n" + b"\x00garbage" * 20)
    truncated = inputs / "truncated.mcap"
    truncated.write_bytes((runs / "run.mcap").read_bytes()[:3000])
    not_ros1 = inputs / "text.bag"
    not_ros1.write_text("t,sensor,x,y,theta,range\n")
    no_ranges = _write_bag(inputs / "odometry-only.mcap", with_ranges=False)
    silent = _write_bag(inputs / "silent.mcap", silent_only=True)
    csv, bag = str(runs / "r.csv"), str(runs / "run.mcap")
    return {
        "corrupt": ([str(corrupt)], f"{corrupt}: corrupt MCAP file (Unexpected record)"),
        "truncated": ([str(truncated)], f"{truncated}: truncated or corrupt MCAP file (no end "
                                        "marker: was the recording cut short?)"),
        "not-ros1": ([str(not_ros1)], f"{not_ros1}: not a ROS bag"),
        "absent": ([str(inputs / "absent.mcap")], "absent.mcap: no such file or folder"),
        "no-range-topic": ([str(no_ranges)],
                           f"{no_ranges}: no topic of type sensor_msgs/msg/Range"),
        "all-silent": ([str(silent)],
                       f"{silent}: no readings to map (its 160 Range messages heard nothing"),
        "unknown-range-topic": ([bag, "--range-topic", "/nope"],
                                f"{bag}: topic '/nope' is not in the bag"),
        "unknown-odom-topic": ([bag, "--odom-topic", "/nope"],
                               f"{bag}: topic '/nope' is not in the bag"),
        "unknown-robot": ([bag, "--robot", "no-such-robot"], "unknown robot 'no-such-robot'"),
        "robot-misfit": ([bag, "--robot", "p3dx-front"], "robot 'p3dx-front' has 8 sensors"),
        **{name: ([csv, *option], f"{csv} is a readings CSV; --robot, --range-topic, "
                                  "--odom-topic, --frame and --no-echo apply to ROS bag inputs "
                                  "only")
           for name, option in _CSV_WITH_BAG_OPTION.items()},
    }


@pytest.mark.parametrize("case", _BAD)
def test_bad_bag_requests_are_one_line_exit_2_and_write_nothing(
    bad_requests: dict[str, tuple[list[str], str]], tmp_path: Path, case: str,
    capsys: pytest.CaptureFixture[str],
) -> None:
    args, words = bad_requests[case]
    for model in ("carved", "elfes"):
        assert main(["grid", *args, "--model", model, "--out", str(tmp_path / "g.yaml")]) == 2
        err = capsys.readouterr().err
        assert words in err, err
        assert err.count("\n") == 1, err
        assert err.startswith("sonarcarve: error: "), err
        assert list(tmp_path.iterdir()) == [], "nothing written, no temporary left"


def test_grid_help_teaches_bag_input(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["grid", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    for words in ("READINGS.csv|BAG", "ROS bag", ".mcap", "rosbag2 folder", "--robot",
                  "--range-topic", "--odom-topic", "--frame", "--no-echo",
                  "sonarcarve grid run.mcap --no-echo"):
        assert words in text, words
