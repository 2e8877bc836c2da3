"""`sonarcarve process INPUT --out OUT`: bag inputs, and the output picked by OUT's ending
(map CSV, ROS bag, Rerun recording); bad requests are one line, exit 2 and write nothing."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.io import read_map_csv, read_readings_csv, write_readings_csv
from sonarcarve.io.bag_out import ARCS_TOPIC, GRID_TOPIC, LOCAL_MAP_TOPIC
from sonarcarve.methods import make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch

AnyReader = pytest.importorskip("rosbags.highlevel").AnyReader

# What simulate writes and process reads back, for every test: a short, seeded doorway run.
SIM = ["simulate", "--world", "doorway", "--seed", "3"]


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same simulation written as a readings CSV (r.csv) and as a bag (run.mcap)."""
    folder = tmp_path_factory.mktemp("runs")
    assert main([*SIM, "--out", str(folder / "r.csv")]) == 0
    assert main([*SIM, "--out", str(folder / "run.mcap")]) == 0
    return folder


def _topics(path: Path) -> dict[str, tuple[str, int]]:
    """Topic -> (message type, message count), read back with rosbags' AnyReader."""
    with AnyReader([path]) as reader:
        return {c.topic: (c.msgtype, c.msgcount) for c in reader.connections}


def _frames(path: Path, topic: str) -> set[str]:
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic == topic]
        return {reader.deserialize(raw, conn.msgtype).header.frame_id
                for conn, _, raw in reader.messages(connections=conns)}


def test_simulated_bag_maps_to_the_csv_paths_map(runs: Path, tmp_path: Path) -> None:
    """simulate → bag → process equals simulate → CSV → process: same ids, sensors and
    sources; positions to float32 precision (Range.range and field_of_view are float32)."""
    assert (runs / "run.truth.json").read_bytes() == (runs / "r.truth.json").read_bytes()
    from_csv, from_bag = tmp_path / "csv-map.csv", tmp_path / "bag-map.csv"
    assert main(["process", str(runs / "r.csv"), "--out", str(from_csv)]) == 0
    assert main(["process", str(runs / "run.mcap"), "--out", str(from_bag)]) == 0
    a, b = read_map_csv(from_csv), read_map_csv(from_bag)
    assert len(a) > 50
    assert b.reading_id.tolist() == a.reading_id.tolist()
    assert b.sensor.tolist() == a.sensor.tolist()
    assert b.source_labels() == a.source_labels()
    np.testing.assert_allclose(b.t, a.t, rtol=0.0, atol=1e-9)  # nanosecond stamps
    # Most points agree to 1e-6 m; a circle intersection (ATM) or a carved end magnifies the
    # float32 rounding of a range (~2e-7 m) or a beam width a few times.
    error = np.hypot(*(b.xy - a.xy).T)
    assert np.mean(error < 1e-6) > 0.95
    assert error.max() < 5e-5


def test_the_bag_path_is_the_csv_path_with_float32_ranges(runs: Path, tmp_path: Path) -> None:
    """The CSV rounded to what a Range message holds maps to the same map (to 1e-9 m: the
    poses and stamps still differ in the last bit, through nanoseconds and quaternions)."""
    csv = read_readings_csv(runs / "r.csv")
    rounded = ReadingBatch.from_arrays(
        t=csv.t, sensor=csv.sensor, x=csv.x, y=csv.y, theta=csv.theta,
        range=csv.range.astype(np.float32).astype(np.float64),
        beam_width=csv.beam_width.astype(np.float32).astype(np.float64))
    write_readings_csv(rounded, tmp_path / "r32.csv")
    for method in ("combined", "carve"):
        from_csv, from_bag = tmp_path / f"csv-{method}.csv", tmp_path / f"bag-{method}.csv"
        assert main(["process", str(tmp_path / "r32.csv"), "-m", method, "--out",
                     str(from_csv)]) == 0
        assert main(["process", str(runs / "run.mcap"), "-m", method, "--out",
                     str(from_bag)]) == 0
        a, b = read_map_csv(from_csv), read_map_csv(from_bag)
        assert b.reading_id.tolist() == a.reading_id.tolist(), method
        assert b.source_labels() == a.source_labels(), method
        np.testing.assert_allclose(b.xy, a.xy, rtol=0.0, atol=1e-9, err_msg=method)
        np.testing.assert_allclose(b.width, a.width, rtol=0.0, atol=1e-9, err_msg=method)


def test_bag_output_holds_the_input_topics_and_the_map_topics(runs: Path,
                                                              tmp_path: Path) -> None:
    out = tmp_path / "mapped.mcap"
    assert main(["process", str(runs / "run.mcap"), "--out", str(out), "--map-rate", "4"]) == 0
    given, written = _topics(runs / "run.mcap"), _topics(out)
    for topic, (kind, count) in given.items():  # copied through, every message
        assert written[topic] == (kind, count), topic
    assert written[LOCAL_MAP_TOPIC][0] == "sensor_msgs/msg/PointCloud2"
    assert written[ARCS_TOPIC][0] == "visualization_msgs/msg/MarkerArray"
    # 7.5 s of log at 4 maps per second (doorway tour, read from the /odom stamps).
    with AnyReader([runs / "run.mcap"]) as reader:
        odom = [c for c in reader.connections if c.topic == "/odom"]
        stamps = [t for _, t, _ in reader.messages(connections=odom)]
    span = (stamps[-1] - stamps[0]) * 1e-9
    assert abs(written[LOCAL_MAP_TOPIC][1] - span * 4) <= 2
    assert written[ARCS_TOPIC][1] == written[LOCAL_MAP_TOPIC][1]
    assert _frames(out, LOCAL_MAP_TOPIC) == {"odom"}  # the input's odometry frame


@pytest.mark.parametrize("name", ["map.bag", "map_folder"])
def test_csv_input_to_a_ros1_bag_or_a_rosbag2_folder(runs: Path, tmp_path: Path,
                                                     name: str) -> None:
    out = tmp_path / name
    assert main(["process", str(runs / "r.csv"), "--method", "carve", "--out", str(out)]) == 0
    topics = _topics(out)
    # A CSV has no messages to copy; the carved grid comes with every local map.
    assert set(topics) == {LOCAL_MAP_TOPIC, ARCS_TOPIC, GRID_TOPIC}
    assert topics[GRID_TOPIC] == ("nav_msgs/msg/OccupancyGrid", topics[LOCAL_MAP_TOPIC][1])
    assert topics[LOCAL_MAP_TOPIC][1] > 0
    assert out.is_dir() == (name == "map_folder")


def test_rrd_output_holds_the_same_global_map(runs: Path, tmp_path: Path) -> None:
    rerun_chunk = pytest.importorskip("rerun.chunk")
    out, csv_map = tmp_path / "run.rrd", tmp_path / "map.csv"
    assert main(["process", str(runs / "run.mcap"), "--method", "atm", "--out", str(out)]) == 0
    assert main(["process", str(runs / "run.mcap"), "--method", "atm", "--out",
                 str(csv_map)]) == 0
    chunks = [c for c in rerun_chunk.RrdReader(out).stream().to_chunks()
              if str(c.entity_path) == "/world/global_map"]
    positions = chunks[0].to_record_batch().column("Points2D:positions").to_pylist()[0]
    np.testing.assert_allclose(np.array(positions), read_map_csv(csv_map).xy, rtol=1e-6)


def test_csv_to_csv_still_equals_the_library(tmp_path: Path) -> None:
    """The streamed path is untouched: a hand-made two-wall log maps as process_readings."""
    k = np.arange(40)
    batch = ReadingBatch.from_arrays(t=0.1 * k, sensor=k % 2, x=0.05 * k, y=np.zeros(40),
                                     theta=np.where(k % 2 == 0, math.pi / 2, -math.pi / 2),
                                     range=np.full(40, 1.5))
    write_readings_csv(batch, tmp_path / "r.csv")
    assert main(["process", str(tmp_path / "r.csv"), "--method", "centerline", "--out",
                 str(tmp_path / "m.csv")]) == 0
    expected = process_readings(batch, make_method("centerline")).global_map
    got = read_map_csv(tmp_path / "m.csv")
    np.testing.assert_allclose(got.xy, expected.xy)
    np.testing.assert_allclose(np.abs(got.xy[:, 1]), 1.5)


def _bad_requests(runs: Path, tmp_path: Path) -> list[tuple[list[str], str, str]]:
    """(arguments, OUT name, words of the one-line error)."""
    corrupt = tmp_path / "corrupt.mcap"
    corrupt.write_bytes(b"\x89MCAP0\r\n" + b"\x00garbage" * 20)
    truncated = tmp_path / "truncated.mcap"
    truncated.write_bytes((runs / "run.mcap").read_bytes()[:3000])
    csv, bag = str(runs / "r.csv"), str(runs / "run.mcap")
    return [
        ([str(corrupt)], "out.csv", str(corrupt)),
        ([str(truncated)], "out.mcap", str(truncated)),
        ([str(truncated)], "out.rrd", str(truncated)),
        ([str(tmp_path / "absent.bag")], "out.mcap", "absent.bag"),
        ([bag, "--range-topic", "/nope"], "out.csv", "/nope"),
        ([csv], "out.png", "unknown ending '.png'"),
        ([csv, "--robot", "scout2"], "out.csv", "apply to ROS bag inputs only"),
        ([bag, "--robot", "no-such-robot"], "out.csv", "unknown robot 'no-such-robot'"),
        ([csv, "--max-error", "0.1"], "out.mcap", "apply to a map CSV output only"),
        ([csv, "--jump-threshold", "0.5"], "out.rrd", "apply to a map CSV output only"),
        ([csv, "--max-range", "3", "--min-range", "0.2"], "out.mcap",
         "--max-range applies to every output"),
        ([csv, "--map-rate", "2"], "out.csv", "--map-rate applies to a bag output only"),
        ([bag, "--map-rate", "0"], "out.mcap", "--map-rate must be a number > 0"),
        ([csv, csv], "out.csv", "--out takes one INPUT, got 2"),
        ([csv, "--workers", "2"], "out.csv", "apply to --out-dir"),
        ([bag, "--method", "nonsense"], "out.mcap", "--method must be one of"),
    ]


def test_bad_requests_are_one_line_exit_2_and_write_nothing(
    runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for args, name, words in _bad_requests(runs, tmp_path):
        out = tmp_path / "outs" / name
        out.parent.mkdir(exist_ok=True)
        assert main(["process", *args, "--out", str(out)]) == 2, args
        err = capsys.readouterr().err
        assert words in err, (args, err)
        assert err.count("\n") == 1, err
        assert err.startswith("sonarcarve: error: "), err
        assert list(out.parent.iterdir()) == [], (args, "nothing written, no temporary left")


def test_an_existing_bag_is_never_overwritten(runs: Path, tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    for name in ("old.mcap", "old_folder"):
        out = tmp_path / name
        if name.endswith(".mcap"):
            out.write_bytes(b"precious")
        else:
            out.mkdir()
            (out / "keep").write_text("precious")
        assert main(["process", str(runs / "r.csv"), "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert ("already exists" if name.endswith(".mcap") else "is a directory") in err
    assert (tmp_path / "old.mcap").read_bytes() == b"precious"
    assert (tmp_path / "old_folder" / "keep").read_text() == "precious"


def test_missing_out_names_both_choices(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["process", str(tmp_path / "r.csv")]) == 2
    err: Any = capsys.readouterr().err
    assert "missing option '--out'" in err
    assert "--out-dir" in err


def test_no_echo_readings_from_a_csv_or_a_bag_give_the_same_map(runs: Path,
                                                                tmp_path: Path) -> None:
    """Silent firings as free space, two ways: `simulate --no-echo` writes them into the CSV
    (range inf, max_range), a bag always holds them (+Inf) and `process --no-echo` reads them.
    Both give one map, with the same ids (rows of the merged log) and sources; and the silent
    firings carve: the map differs from the echoes-only one."""
    csv_log = tmp_path / "silent.csv"
    assert main([*SIM, "--no-echo", "--out", str(csv_log)]) == 0
    header, *rows = csv_log.read_text().splitlines()
    assert header == "t,sensor,x,y,theta,range,beam_width,max_range"
    silent = [row for row in rows if row.split(",")[5] == "inf"]
    assert silent
    assert all(float(row.split(",")[7]) > 0 for row in silent)
    from_csv, from_bag, echoes_only = (tmp_path / n for n in ("a.csv", "b.csv", "c.csv"))
    assert main(["process", str(csv_log), "--method", "carve", "--out", str(from_csv)]) == 0
    assert main(["process", str(runs / "run.mcap"), "--no-echo", "--method", "carve",
                 "--out", str(from_bag)]) == 0
    assert main(["process", str(runs / "r.csv"), "--method", "carve",
                 "--out", str(echoes_only)]) == 0

    def ids_sources(path: Path) -> list[tuple[str, str]]:
        return [(r.split(",")[0], r.split(",")[5]) for r in path.read_text().splitlines()[1:]]

    assert ids_sources(from_csv) == ids_sources(from_bag)
    assert len(ids_sources(from_csv)) > 0
    assert ids_sources(from_csv) != ids_sources(echoes_only)


def test_the_summary_counts_a_bag_s_no_echo_readings_dropped_or_mapped(
        runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """A bag's silent firings are dropped unless --no-echo maps them; the summary says which,
    with their count. The oracle: the inf rows `simulate --no-echo` writes for the same run.
    A readings CSV gets no such row (its inf rows are always mapped)."""
    csv_log = tmp_path / "silent.csv"
    assert main([*SIM, "--no-echo", "--out", str(csv_log)]) == 0
    silent = sum(row.split(",")[5] == "inf" for row in csv_log.read_text().splitlines()[1:])
    assert silent > 0
    capsys.readouterr()
    bag = str(runs / "run.mcap")
    cases = [([bag, "--out", str(tmp_path / "a.csv")], "dropped: no-echo readings (--no-echo)"),
             ([bag, "--no-echo", "--out", str(tmp_path / "b.csv")],
              "no-echo readings mapped as free space"),
             ([bag, "--grid-resolution", "0", "--out", str(tmp_path / "c.mcap")],
              "dropped: no-echo readings (--no-echo)")]
    for args, label in cases:
        assert main(["process", *args]) == 0
        text = " ".join(capsys.readouterr().out.split())
        assert f"{label} │ {silent:,}" in text, args
    assert main(["process", str(csv_log), "--out", str(tmp_path / "d.csv")]) == 0
    assert "no-echo readings" not in capsys.readouterr().out


def test_no_echo_is_refused_where_it_does_not_apply(runs: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["process", str(runs / "r.csv"), "--no-echo", "--out",
                 str(tmp_path / "m.csv")]) == 2
    assert main([*SIM, "--no-echo", "--out", str(tmp_path / "x.mcap")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2
    assert "--no-echo apply to ROS bag inputs only" in lines[0]
    assert "--no-echo applies to a readings CSV output" in lines[1]
    assert not (tmp_path / "m.csv").exists()
    assert not (tmp_path / "x.mcap").exists()


def _last_grid_free_reach(path: Path) -> float:
    """How far the free cells on the x axis (y = 0) reach in the bag's last published grid,
    metres: the far edge of the last free cell (OccupancyGrid rows start at the lower left)."""
    with AnyReader([path]) as reader:
        conns = [c for c in reader.connections if c.topic == GRID_TOPIC]
        *_, (conn, _, raw) = reader.messages(connections=conns)
        grid = reader.deserialize(raw, conn.msgtype)
    h, (x0, y0) = grid.info.resolution, (grid.info.origin.position.x, grid.info.origin.position.y)
    row = np.asarray(grid.data).reshape(grid.info.height, grid.info.width)[int(-y0 / h)]
    return float(x0 + (np.flatnonzero(row == 0).max() + 1) * h)


def test_the_bag_s_grid_carves_with_the_run_s_range_tolerance(tmp_path: Path) -> None:
    """Ten echoes at 1 m from one pose: the published grid's band reaches b = (h + ε) / 2 before
    the echo, 0.05 m by default and 0.25 m with --range-tolerance 0.45 (as grid's option)."""
    log = tmp_path / "log.csv"
    k = np.arange(10)
    write_readings_csv(ReadingBatch.from_arrays(t=0.2 * k, sensor=np.zeros(10, dtype=int),
                                                x=np.zeros(10), y=np.zeros(10),
                                                theta=np.zeros(10), range=np.ones(10)), log)
    reach = {}
    for extra in ([], ["--range-tolerance", "0.45"]):
        out = tmp_path / f"map{len(extra)}.mcap"
        assert main(["process", str(log), "--method", "carve", "--grid-resolution", "0.05",
                     "--out", str(out), *extra]) == 0
        reach[bool(extra)] = _last_grid_free_reach(out)
    assert reach[False] == pytest.approx(0.95, abs=0.05 + 1e-9)
    assert reach[True] == pytest.approx(0.75, abs=0.05 + 1e-9)
