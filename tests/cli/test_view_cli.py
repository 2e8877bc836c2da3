"""``sonarcarve view``: writes a Rerun recording, opens a viewer only where one can start."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from typer.testing import CliRunner

import sonarcarve.cli.view  # registers the command (main.py lists it lazily)
from sonarcarve.cli import main
from sonarcarve.cli.app import app
from sonarcarve.cli.view import find_viewer
from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.readings import ReadingBatch

rerun_chunk = pytest.importorskip("rerun.chunk")

N = 20


@pytest.fixture
def readings(tmp_path: Path) -> Path:
    sensor = np.arange(N) % 2
    batch = ReadingBatch.from_arrays(t=0.1 * np.arange(N), sensor=sensor,
                                     x=0.05 * np.arange(N), y=np.zeros(N),
                                     theta=np.where(sensor == 0, math.pi / 2, 1.2),
                                     range=np.where(sensor == 0, 2.0, 2.0 / math.sin(1.2)))
    path = tmp_path / "run.csv"
    write_readings_csv(batch, path)
    return path


@pytest.fixture
def headless(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(sys, "platform", "linux")


def _entities(path: Path) -> set[str]:
    return {str(chunk.entity_path) for chunk in rerun_chunk.RrdReader(path).stream().to_chunks()}


@pytest.mark.usefixtures("headless")
def test_view_saves_the_recording_beside_the_readings_and_says_where(readings: Path) -> None:
    result = CliRunner().invoke(app, ["view", str(readings), "--method", "carve"])
    assert result.exit_code == 0, result.output
    target = readings.with_suffix(".rrd")
    assert "no viewer opened" in result.output
    assert f"rerun {target}" in " ".join(result.output.split())
    assert {"/world/reading", "/world/map", "/world/robot/path/tail"} <= _entities(target)


@pytest.mark.usefixtures("headless")
def test_view_draws_the_walls_of_a_world(readings: Path, tmp_path: Path) -> None:
    out = tmp_path / "walls.rrd"
    assert main(["view", str(readings), "--world", "doorway", "--out", str(out)]) == 0
    assert "/world/walls" in _entities(out)
    plain = tmp_path / "plain.rrd"
    assert main(["view", str(readings), "--out", str(plain), "--no-open"]) == 0
    assert "/world/walls" not in _entities(plain)  # a real log: no truth file beside it


def test_view_opens_the_viewer_when_there_is_a_display(
        readings: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    started: list[list[str]] = []

    def fake_popen(args: list[str], **kwargs: Any) -> None:
        assert kwargs["start_new_session"]
        started.append(args)

    monkeypatch.setenv("DISPLAY", ":99")
    fake = tmp_path / "bin" / "rerun"
    fake.parent.mkdir()
    fake.write_text("#!/bin/sh\n")
    fake.chmod(0o755)
    monkeypatch.setattr(sys, "executable", str(tmp_path / "bin" / "python"))
    monkeypatch.setattr(sonarcarve.cli.view.subprocess, "Popen", fake_popen)
    out = tmp_path / "run.rrd"
    assert main(["view", str(readings), "--out", str(out)]) == 0
    assert started == [[str(fake), str(out)]]
    assert main(["view", str(readings), "--out", str(out), "--no-open"]) == 0
    assert len(started) == 1


@pytest.mark.usefixtures("headless")
def test_no_display_means_no_viewer_and_nothing_started() -> None:
    assert find_viewer() is None


@pytest.mark.usefixtures("headless")
@pytest.mark.parametrize(("args", "problem"), [
    (["--method", "nope"], "nope"),
    (["--every", "0"], "--every must be at least 1 reading, got 0"),
    (["--out", "{readings}"], "is the input file"),
    (["--world", "nowhere"], "unknown world 'nowhere'"),
    # UX review, finding 7: a Rerun file was written under this name.
    (["--out", "{readings}.out.csv"], "--out {readings}.out.csv: a Rerun recording's name must "
                                      "end in .rrd"),
])
def test_bad_inputs_are_one_line_exit_2(readings: Path, capsys: pytest.CaptureFixture[str],
                                        args: list[str], problem: str) -> None:
    given = [arg.format(readings=readings) for arg in args]
    assert main(["view", str(readings), *given]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert problem.format(readings=readings) in err
    assert not readings.with_suffix(".rrd").exists()
    assert not Path(f"{readings}.out.csv").exists()


@pytest.mark.usefixtures("headless")
def test_view_finds_the_truth_walls_of_a_simulated_log(readings: Path, tmp_path: Path) -> None:
    from sonarcarve.sim.truth import truth_path, write_truth_json
    from sonarcarve.sim.world import load_world

    write_truth_json(truth_path(readings), load_world("doorway"), np.zeros(N, np.int64),
                     np.full((N, 2), np.nan))
    out = tmp_path / "sim.rrd"
    assert main(["view", str(readings), "--out", str(out)]) == 0
    assert "/world/walls" in _entities(out)


def test_the_method_help_lists_evidence(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["view", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.replace("│", " ").split())
    assert "centerline | carve | atm | combined | evidence" in help_text


@pytest.mark.usefixtures("headless")
def test_a_header_only_log_gives_an_empty_recording_and_one_warning(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    empty = tmp_path / "empty.csv"
    empty.write_text("t,sensor,x,y,theta,range\n")
    assert main(["view", str(empty), "--method", "carve"]) == 0
    err = capsys.readouterr().err
    assert err == (f"sonarcarve: warning: {empty} has no readings, only a header: the "
                   "recording is empty\n")
    assert empty.with_suffix(".rrd").is_file()


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A short seeded doorway run written as a readings CSV (run.csv) and a ROS bag (run.mcap),
    each with its truth file beside it."""
    pytest.importorskip("rosbags")
    folder = tmp_path_factory.mktemp("view-runs")
    for name in ("run.csv", "run.mcap"):
        assert main(["simulate", "--world", "doorway", "--seed", "3",
                     "--out", str(folder / name)]) == 0
    return folder


@pytest.mark.usefixtures("headless")
def test_view_records_a_ros_bag_as_its_readings_csv(simulated: Path, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    # User review: `view run.mcap` said "cannot read as CSV: not UTF-8 text (byte 0x89)", where
    # process and grid read the same bag.
    capsys.readouterr()
    from_csv, from_bag = tmp_path / "csv.rrd", tmp_path / "bag.rrd"
    assert main(["view", str(simulated / "run.csv"), "--out", str(from_csv)]) == 0
    csv_out = capsys.readouterr().out
    assert main(["view", str(simulated / "run.mcap"), "--out", str(from_bag)]) == 0
    bag_out = capsys.readouterr().out
    # The same readings (the bag's ranges are float32) give the same counts, and the truth
    # file beside the bag gives its walls.
    assert len(_summary_rows(csv_out)) == 3
    assert _summary_rows(bag_out) == _summary_rows(csv_out)
    assert {"/world/reading", "/world/map", "/world/walls"} <= _entities(from_bag)


@pytest.mark.usefixtures("headless")
def test_view_takes_the_bag_options_for_bags_only(simulated: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    assert main(["view", str(simulated / "run.csv"), "--no-echo"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "--no-echo apply to ROS bag inputs only" in err
    silent = simulated / "silent.rrd"
    assert main(["view", str(simulated / "run.mcap"), "--no-echo", "--out", str(silent)]) == 0
    assert "no-echo" not in capsys.readouterr().err
    assert silent.is_file()


@pytest.mark.usefixtures("headless")
def test_view_counts_the_no_echo_readings_a_bag_dropped(
        simulated: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """As process and grid say it: the oracle is the inf rows `simulate --no-echo` writes for
    the same run; with --no-echo nothing is dropped."""
    silent_csv = tmp_path / "silent.csv"
    assert main(["simulate", "--world", "doorway", "--seed", "3", "--no-echo",
                 "--out", str(silent_csv)]) == 0
    silent = sum(row.split(",")[5] == "inf" for row in silent_csv.read_text().splitlines()[1:])
    assert silent > 0
    capsys.readouterr()
    assert main(["view", str(simulated / "run.mcap"), "--out", str(tmp_path / "a.rrd")]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"dropped: no-echo readings (--no-echo) │ {silent:,}" in text
    assert main(["view", str(simulated / "run.mcap"), "--no-echo",
                 "--out", str(tmp_path / "b.rrd")]) == 0
    assert "dropped: no-echo" not in capsys.readouterr().out


def _summary_rows(output: str) -> list[str]:
    """The summary table's rows of counts (readings in, points, true walls), not its paths."""
    rows = [" ".join(line.replace("│", " ").split()) for line in output.splitlines()]
    return [row for row in rows if row.startswith(("readings in", "points in", "true walls"))]


def _global_map_xy(path: Path) -> np.ndarray:
    """The points of the recording's global map (its last Points2D at /world/global_map)."""
    for chunk in rerun_chunk.RrdReader(path).stream().to_chunks():
        if str(chunk.entity_path) == "/world/global_map":
            column = chunk.to_record_batch().column("Points2D:positions")
            return np.array(column[len(column) - 1].as_py(), dtype=np.float64).reshape(-1, 2)
    msg = f"{path}: no global map"
    raise AssertionError(msg)


@pytest.fixture(scope="module")
def without_beam_width(simulated: Path) -> Path:
    """The simulated doorway run without its beam_width column: --beam-width then applies."""
    lines = (simulated / "run.csv").read_text().splitlines()
    path = simulated / "run6.csv"
    path.write_text("".join(",".join(line.split(",")[:6]) + "\n" for line in lines))
    return path


# Values the doorway run's global map is sensitive to (checked: each changes its points).
_METHOD_OPTIONS = [
    ["--history", "20"],
    ["--beam-width", "40"],
    ["--range-tolerance", "0.15"],
    ["--method", "atm", "--min-transversal", "60"],
    ["--max-incidence", "30"],
]


@pytest.mark.usefixtures("headless")
@pytest.mark.parametrize("option", _METHOD_OPTIONS, ids=lambda o: o[-2])
def test_view_maps_with_process_s_method_options(without_beam_width: Path, tmp_path: Path,
                                                  option: list[str]) -> None:
    # User review: view had none of process's method options, so a recording could not show a
    # run mapped with other parameters than the defaults. The recording's global map is the
    # map process writes with the same options, and not the one with the defaults.
    log = str(without_beam_width)
    base = option[:2] if option[0] == "--method" else []  # the method the option tunes
    maps = {}
    for name, args in (("given", option), ("default", base)):
        rrd, csv = tmp_path / f"{name}.rrd", tmp_path / f"{name}.csv"
        assert main(["view", log, *args, "--out", str(rrd), "--no-open"]) == 0
        assert main(["process", log, *args, "--out", str(csv)]) == 0
        from_process = np.loadtxt(csv, delimiter=",", skiprows=1, usecols=(3, 4), ndmin=2)
        maps[name] = _global_map_xy(rrd)
        np.testing.assert_allclose(maps[name], from_process, atol=1e-6)
    assert maps["given"].shape != maps["default"].shape or not np.allclose(
        maps["given"], maps["default"])


@pytest.mark.usefixtures("headless")
@pytest.mark.parametrize(("args", "problem"), [
    (["--history", "0"], "--history"),
    (["--beam-width", "200"], "--beam-width"),
    (["--range-tolerance", "-1"], "--range-tolerance"),
    (["--min-transversal", "0"], "--min-transversal"),
    (["--max-incidence", "95"], "--max-incidence"),
])
def test_a_bad_method_option_is_one_line_exit_2_naming_it(
        readings: Path, capsys: pytest.CaptureFixture[str], args: list[str],
        problem: str) -> None:
    assert main(["view", str(readings), *args]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert problem in err
    assert not readings.with_suffix(".rrd").exists()
    # process says the same about the same value (one set of checks for both commands)
    assert main(["process", str(readings), *args, "--out", str(readings.with_name("m.csv"))]) == 2
    assert capsys.readouterr().err.replace("process", "view") == err.replace("process", "view")


def test_view_lists_process_s_method_options_with_the_same_help(
        capsys: pytest.CaptureFixture[str]) -> None:
    texts = []
    for command in ("view", "process"):
        assert main([command, "--help"]) == 0
        texts.append(" ".join(capsys.readouterr().out.replace("│", " ").split()))
    for option in ("--history", "--beam-width", "--range-tolerance", "--min-transversal",
                   "--max-incidence"):
        assert option in texts[0]
    assert "ε in metres, 0 to 1" in texts[0]
    assert "β in degrees, in [0, 90]" in texts[0]
