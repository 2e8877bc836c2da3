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
