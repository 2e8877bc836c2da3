"""``sonarcarve demo`` in process: the files it writes, what it prints, how it refuses input."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from sonarcarve.cli import main
from sonarcarve.lab.demo import (
    DEMO_METHODS,
    FIGURE_FILES,
    GRID_FIGURE_FILE,
    KEPT_FIGURE_FILE,
    METHOD_LABELS,
)

PERCENT_FIELDS = ("unprocessed_pct", "fully_carved_pct", "spurious_removed_pct", "true_lost_pct")


@pytest.fixture(scope="module")
def doorway_demo(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """One ``sonarcarve demo`` run on the doorway world, into a folder it must create with its
    parents: (that folder, what it printed). Shared by the tests that read its files (a run
    costs several seconds)."""
    out = tmp_path_factory.mktemp("demo") / "nested" / "demo"
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert main(["demo", "--world", "doorway", "--seed", "1", "--out", str(out)]) == 0
    return out, printed.getvalue()


def test_cli_prints_the_verdict_between_the_table_and_the_caption(
        doorway_demo: tuple[Path, str]) -> None:
    out, printed = doorway_demo
    verdict = json.loads((out / "summary.json").read_text())["verdict"]
    assert verdict.startswith("Sharpest map: ")
    flat = " ".join(printed.split())  # the console wraps long lines
    assert flat.index("sonarcarve demo: ") < flat.index(verdict) < flat.index("How to read")


def test_cli_writes_every_figure_and_summary(doorway_demo: tuple[Path, str]) -> None:
    out, printed = doorway_demo
    names = sorted(p.name for p in out.iterdir())
    grid_files = ["carved-grid.yaml", "carved-grid.pgm", "range-sensor-layer.yaml",
                  "range-sensor-layer.pgm"]
    assert names == sorted([*FIGURE_FILES.values(), GRID_FIGURE_FILE, KEPT_FIGURE_FILE,
                            "approach.gif", "summary.json", "summary.md", *grid_files])
    with Image.open(out / "approach.gif") as gif:
        assert gif.format == "GIF"
        assert gif.n_frames > 10  # an animation, not a still
    for name in [*FIGURE_FILES.values(), GRID_FIGURE_FILE, KEPT_FIGURE_FILE]:
        with Image.open(out / name) as png:
            assert png.format == "PNG"
            assert min(png.size) >= 400  # a real figure, not an empty canvas

    summary = json.loads((out / "summary.json").read_text())
    rows = summary["methods"]
    assert [row["method"] for row in rows] == list(DEMO_METHODS)
    by_name = {row["method"]: row for row in rows}
    assert by_name["centerline"]["unprocessed_pct"] == 0.0
    # Centerline keeps every reading: one point each, nothing removed.
    assert by_name["centerline"]["map_points"] == summary["readings"]
    for row in rows:
        assert row["readings"] == summary["readings"]
        for name in PERCENT_FIELDS:
            assert row[name] is None or 0.0 <= row[name] <= 100.0
        assert 0.0 <= row["median_error_m"] <= row["p90_error_m"]
        assert row["readings_per_second"] > 0.0

    first_words = [METHOD_LABELS[m].split()[0] for m in DEMO_METHODS]
    table_rows = [line for line in printed.splitlines()
                  if line.split() and line.split()[0] in first_words]
    assert [line.split()[0] for line in table_rows] == first_words
    assert "evidence carving" in printed
    assert "(beyond the paper)" in printed
    assert "How to read" in printed
    # The grid table, under the methods table, and one caption line per file written.
    assert printed.index("occupied") > printed.index(first_words[-1])
    assert "carved grid" in printed
    assert "RangeSensorLayer (defaults)" in printed
    listed = [line.split()[0] for line in printed.splitlines() if line.startswith("  ")]
    assert sorted(name for name in listed if name in names) == names
    markdown = (out / "summary.md").read_text()
    assert sum(line.startswith(f"| {METHOD_LABELS[m]} |") for m in DEMO_METHODS
               for line in markdown.splitlines()) == len(DEMO_METHODS)
    assert "| evidence carving (beyond the paper) |" in markdown
    assert "| carved grid |" in markdown


def _pgm_pixels(path: Path) -> np.ndarray:
    """A binary PGM's pixels, parsed here: magic, width, height, maxval, then the bytes."""
    magic, cols, rows, maxval, body = path.read_bytes().split(maxsplit=4)
    assert (magic, maxval) == (b"P5", b"255")
    assert len(body) == int(cols) * int(rows)
    return np.frombuffer(body, dtype=np.uint8).reshape(int(rows), int(cols))


def test_cli_writes_each_grid_as_a_trinary_map_server_map(
    doorway_demo: tuple[Path, str],
) -> None:
    out, _ = doorway_demo
    summary = json.loads((out / "summary.json").read_text())
    grids = {g["kind"]: g for g in summary["grids"]}
    assert list(grids) == ["carved", "range-sensor-layer"]
    for kind, stem in (("carved", "carved-grid"), ("range-sensor-layer", "range-sensor-layer")):
        meta = yaml.safe_load((out / f"{stem}.yaml").read_text())
        assert meta["image"] == f"{stem}.pgm"
        assert meta["resolution"] == 0.1
        assert meta["negate"] == 0
        assert meta["free_thresh"] < meta["occupied_thresh"]
        # The doorway world's walls span x in [-4, 4], y in [-1.5, 8]; the grid adds 0.5 m.
        assert meta["origin"] == pytest.approx([-4.5, -2.0, 0.0])
        pixels = _pgm_pixels(out / f"{stem}.pgm")
        assert pixels.shape == (grids[kind]["rows"], grids[kind]["columns"]) == (105, 90)
        # Trinary, as map_saver writes it: occupied 0, unknown 205, free 254, and nothing else.
        assert set(np.unique(pixels).tolist()) == {0, 205, 254}
        assert int(np.count_nonzero(pixels == 0)) == grids[kind]["occupied_cells"]


def test_cli_help_teaches_the_columns() -> None:
    from typer.testing import CliRunner

    import sonarcarve.cli.demo  # noqa: F401  (registers the command, as main() does lazily)
    from sonarcarve.cli.app import app

    result = CliRunner().invoke(app, ["demo", "--help"], terminal_width=100)
    assert result.exit_code == 0
    for phrase in ("unprocessed", "spurious removed", "true lost", "Example", "--history",
                   "RangeSensorLayer", "precision", "recall", "map_server"):
        assert phrase in result.output


@pytest.mark.parametrize(("args", "message"), [
    (["--world", "no-such-world"], "no-such-world"),
    (["--world", "doorway", "--history", "0"],
     "--history must be a whole number of arcs in [1, 100,000], got 0"),
    (["--world", "doorway", "--history", "1000000"],
     "--history must be a whole number of arcs in [1, 100,000], got 1000000"),
])
def test_cli_bad_input_is_one_line_and_writes_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str,
) -> None:
    fresh = tmp_path / "fresh"
    assert main(["demo", *args, "--out", str(fresh)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err
    assert len(err.splitlines()) == 1
    assert not fresh.exists()

    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / "mine.txt").write_text("untouched")
    assert main(["demo", *args, "--out", str(kept)]) == 2
    assert [p.name for p in kept.iterdir()] == ["mine.txt"]
    assert (kept / "mine.txt").read_text() == "untouched"


def test_cli_out_that_is_a_file_is_refused(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["demo", "--world", "doorway", "--out", str(blocker / "sub")]) == 2
    assert "not a directory" in capsys.readouterr().err
    assert blocker.read_text() == "x"


def test_cli_world_without_tour_is_refused(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    walls = tmp_path / "walls.json"
    walls.write_text('{"name": "box", "segments": [[0, 0, 4, 0], [4, 0, 4, 4]]}')
    out = tmp_path / "out"
    assert main(["demo", "--world", str(walls), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "has no tour" in err[0]
    assert not out.exists()
