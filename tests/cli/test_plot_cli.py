"""``sonarcarve plot``: a user's own map CSV to a figure, one-line errors for bad inputs."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import sonarcarve.cli.plot  # registers the command (main.py lists it lazily)
from sonarcarve.cli import main
from sonarcarve.cli.app import app
from sonarcarve.io import write_map_csv
from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch

assert sonarcarve.cli.plot.plot  # the import is for its side effect

PNG = b"\x89PNG\r\n\x1a\n"


def _readings() -> ReadingBatch:
    """Two sensors on a robot driving along +x past a wall at y = 2 (one looks up, one ahead)."""
    n = 40
    x = np.repeat(0.05 * np.arange(n // 2), 2)
    sensor = np.tile([0, 1], n // 2)
    theta = np.where(sensor == 0, math.pi / 2, math.pi / 4)
    return ReadingBatch.from_arrays(t=0.05 * np.arange(n), sensor=sensor, x=x, y=np.zeros(n),
                                    theta=theta, range=np.where(sensor == 0, 2.0, 2.0 * 2**0.5))


@pytest.fixture
def run(tmp_path: Path) -> tuple[Path, Path, GlobalMap]:
    readings = _readings()
    global_map = process_readings(readings, make_method("combined")).global_map
    write_readings_csv(readings, tmp_path / "run.csv")
    write_map_csv(global_map, tmp_path / "map.csv")
    return tmp_path / "run.csv", tmp_path / "map.csv", global_map


def test_plot_draws_a_map_with_path_arcs_and_error_bars(run: tuple[Path, Path, GlobalMap],
                                                        tmp_path: Path) -> None:
    readings, map_csv, global_map = run
    out = tmp_path / "map.png"
    result = CliRunner().invoke(app, ["plot", str(map_csv), "--readings", str(readings),
                                      "--arcs", "--error-bars", "--out", str(out)])
    assert result.exit_code == 0, result.output
    assert out.read_bytes()[:8] == PNG
    assert f"{len(global_map)}" in result.output
    assert "figure written to" in result.output


def test_plot_alone_and_as_svg(run: tuple[Path, Path, GlobalMap], tmp_path: Path) -> None:
    _, map_csv, _ = run
    assert main(["plot", str(map_csv), "--out", str(tmp_path / "a.png")]) == 0
    assert main(["plot", str(map_csv), "--out", str(tmp_path / "a.svg")]) == 0
    assert b"<svg" in (tmp_path / "a.svg").read_bytes()[:500]


def test_the_command_draws_with_agg(run: tuple[Path, Path, GlobalMap], tmp_path: Path) -> None:
    """The command picks the Agg backend itself (review finding 18): the library's plotting
    no longer does, and a command must not need a display whatever the default is."""
    import matplotlib
    import matplotlib.pyplot as plt

    _, map_csv, _ = run
    before = matplotlib.get_backend()
    plt.switch_backend("svg")
    try:
        assert main(["plot", str(map_csv), "--out", str(tmp_path / "a.png")]) == 0
        assert matplotlib.get_backend().lower() == "agg"
    finally:
        plt.switch_backend(before)


def test_confidence_min_keeps_confident_and_unmodelled_points(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    n = 4
    points = GlobalMap(reading_id=np.arange(n), t=np.arange(n, dtype=float),
                       sensor=np.zeros(n, np.int64), xy=np.ones((n, 2)),
                       source=np.ones(n, np.int8), width=np.zeros(n), max_error=np.zeros(n),
                       range=np.ones(n), confidence=np.array([0.9, 0.2, np.nan, 0.5]))
    write_map_csv(points, tmp_path / "map.csv")
    assert main(["plot", str(tmp_path / "map.csv"), "--confidence-min", "0.5",
                 "--out", str(tmp_path / "map.png")]) == 0
    out = capsys.readouterr().out
    assert re.search(r"dropped: confidence < 0\.5\s*│\s*1\s*│", out), out
    assert re.search(r"points drawn\s*│\s*3\s*│", out), out


def test_plot_over_a_grid(run: tuple[Path, Path, GlobalMap], tmp_path: Path) -> None:
    from PIL import Image

    _, map_csv, _ = run
    Image.fromarray(np.full((10, 10), 254, np.uint8)).save(tmp_path / "grid.pgm")
    (tmp_path / "grid.yaml").write_text(
        "image: grid.pgm\nresolution: 0.3\norigin: [-1, -1, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n", encoding="utf-8")
    out = tmp_path / "map.png"
    assert main(["plot", str(map_csv), "--grid", str(tmp_path / "grid.yaml"),
                 "--out", str(out)]) == 0
    assert out.read_bytes()[:8] == PNG


@pytest.mark.parametrize(("extra", "problem"), [
    (["--arcs"], "--arcs needs --readings"),
    (["--confidence-min", "1.5"], "--confidence-min must lie in [0, 1], got 1.5"),
    (["--readings", "{other}"], "not the readings this map was made from"),
    (["--readings", "{missing}"], "no such file"),
    (["--grid", "{missing}"], "no such file"),
])
def test_bad_inputs_are_one_line_exit_2_and_write_nothing(
        run: tuple[Path, Path, GlobalMap], tmp_path: Path, capsys: pytest.CaptureFixture[str],
        extra: list[str], problem: str) -> None:
    _, map_csv, _ = run
    other = tmp_path / "other.csv"
    write_readings_csv(_readings()[:5], other)
    args = [a.format(other=other, missing=tmp_path / "missing.csv") for a in extra]
    out = tmp_path / "map.png"
    assert main(["plot", str(map_csv), *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert problem in err
    assert not out.exists()


def test_bad_map_and_bad_out_are_one_line_errors(run: tuple[Path, Path, GlobalMap],
                                                 tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    readings, map_csv, _ = run
    assert main(["plot", str(readings), "--out", str(tmp_path / "m.png")]) == 2
    assert "expected header id,t,sensor" in capsys.readouterr().err
    assert main(["plot", str(map_csv), "--out", str(tmp_path / "m.jpg")]) == 2
    assert "expected a .png, .svg or .pdf" in capsys.readouterr().err
    assert main(["plot", str(map_csv), "--out", str(tmp_path / "nowhere" / "m.png")]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_a_map_of_other_readings_names_the_map_file_and_line(
        run: tuple[Path, Path, GlobalMap], tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    # UX review, finding 13: the message named neither the map nor its line.
    readings, map_csv, _ = run
    lines = map_csv.read_text().splitlines(keepends=True)
    fields = lines[2].split(",")
    lines[2] = ",".join(["99999", *fields[1:]])
    map_csv.write_text("".join(lines))
    out = tmp_path / "p.png"
    assert main(["plot", str(map_csv), "--readings", str(readings), "--arcs",
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"sonarcarve: error: {map_csv}: line 3, map point has id 99999 but "
                          f"{readings} has 40 rows"), err
    assert not out.exists()


def test_plot_warns_of_a_cut_last_line(run: tuple[Path, Path, GlobalMap], tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    """As process and grid do: a log or map cut mid-number still parses (review rev6)."""
    readings, map_csv, _ = run
    readings.write_bytes(readings.read_bytes().rstrip(b"\n"))
    lines = readings.read_text().count("\n") + 1
    capsys.readouterr()
    assert main(["plot", str(map_csv), "--readings", str(readings),
                 "--out", str(tmp_path / "cut.png")]) == 0
    assert capsys.readouterr().err.splitlines() == [
        f"sonarcarve: warning: {readings}: line {lines:,}, the last, has no line end: if the "
        "file was cut short, its last reading may be wrong (a number cut short still reads as "
        "a number)"]


def test_readings_with_no_echo_rows_a_map_left_out_are_named(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    # User review: `process run.mcap --out map.csv` numbers the bag's echoes; `plot map.csv
    # --readings run.csv` with the CSV `convert rosbag --no-echo` wrote said only "does not
    # match row 3": the silent rows shift every id. Here a silent firing is slipped in
    # between the echoes a map was made from.
    monkeypatch.chdir(tmp_path)  # short paths: the message is cut at 300 characters
    echoes = _readings()
    global_map = process_readings(echoes, make_method("combined")).global_map
    write_map_csv(global_map, tmp_path / "map.csv")
    n = len(echoes)
    silent = ReadingBatch.from_arrays(t=echoes.t[:2], sensor=echoes.sensor[:2],
                                      x=echoes.x[:2], y=echoes.y[:2], theta=echoes.theta[:2],
                                      range=np.full(2, np.inf), max_range=np.full(2, 5.0))
    everything = ReadingBatch.concatenate([echoes[:1], silent, echoes[1:]])
    assert len(everything) == n + 2
    write_readings_csv(everything, tmp_path / "all.csv")
    out = tmp_path / "map.png"
    assert main(["plot", "map.csv", "--readings", "all.csv", "--out", "map.png"]) == 2
    assert capsys.readouterr().err == (
        "sonarcarve: error: map.csv: its ids skip the 2 no-echo rows (range inf) of all.csv, "
        "as a map of a bag made without --no-echo does: give --readings converted without "
        "--no-echo\n")
    assert not out.exists()
