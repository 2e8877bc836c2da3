"""Every command refuses an output it cannot write: one line, exit 2, nothing written."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.io import write_readings_csv
from sonarcarve.lab.report import BEGIN_MARKER, END_MARKER
from sonarcarve.readings import ReadingBatch

#: A directory that refuses new files even for root (the sandbox may run tests as root, for
#: whom permission bits do not apply).
UNWRITABLE = Path("/proc")


def _readings(path: Path) -> None:
    n = 40
    k = np.arange(n)
    write_readings_csv(ReadingBatch.from_arrays(
        t=0.1 * k, sensor=np.zeros(n, int), x=0.05 * k, y=np.zeros(n),
        theta=np.full(n, math.pi / 2), range=np.full(n, 1.5)), path)


def _snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` with its bytes (temporary files included: names start '.')."""
    return {str(p.relative_to(folder)): p.read_bytes() if p.is_file() else b"<dir>"
            for p in sorted(folder.rglob("*"))}


def _one_line_error(capsys: pytest.CaptureFixture[str], *words: str) -> str:
    err = capsys.readouterr().err
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("sonarcarve: error: "), err
    assert "Traceback" not in err
    for word in words:
        assert word in lines[0], (word, lines[0])
    return lines[0]


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A folder with an input CSV, an existing output, a subfolder; the current directory."""
    _readings(tmp_path / "r.csv")
    (tmp_path / "old.csv").write_text("precious\n")
    (tmp_path / "adir").mkdir()
    (tmp_path / "afile").write_text("not a folder\n")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _file_commands(out: str) -> list[list[str]]:
    """One invocation per command that writes a file to --out."""
    return [
        ["process", "r.csv", "--method", "centerline", "--out", out],
        ["simulate", "--world", "doorway", "--out", out],
        ["convert", "roboND", "--out", out],
        ["worlds", "doorway", "--out", out],
    ]


@pytest.mark.parametrize(("out", "words"), [
    (str(UNWRITABLE / "x.csv"), ["/proc/x.csv", "cannot create a file in /proc"]),
    ("adir", ["adir", "is a directory"]),
    ("", ["empty, expected a file name"]),
    ("no/such/dir/x.csv", ["no/such/dir/x.csv", "directory no/such/dir does not exist"]),
    ("/dev/null", ["/dev/null", "not a regular file"]),
])
def test_unwritable_file_out_is_refused_by_every_command(
    workdir: Path, capsys: pytest.CaptureFixture[str], out: str, words: list[str],
) -> None:
    before = _snapshot(workdir)
    for args in _file_commands(out):
        assert main(args) == 2, args
        _one_line_error(capsys, "--out", *words)
        assert _snapshot(workdir) == before, args  # nothing written, no temporary file left
    assert not (workdir / "no").exists()  # a missing folder is an error, never created


def test_process_refuses_to_overwrite_its_input(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _snapshot(workdir)
    assert main(["process", "r.csv", "--out", str(workdir / "r.csv")]) == 2
    _one_line_error(capsys, "--out", "is the input file")
    assert _snapshot(workdir) == before


def test_convert_refuses_to_overwrite_the_data_sets_files(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    folder = workdir / "log"
    folder.mkdir()
    (folder / "poses.txt").write_text("1000 0 0 0\n")
    (folder / "measurement.txt").write_text("1000 5110 800 5110 5110 5110 5110 5110 1500\n")
    before = _snapshot(workdir)
    assert main(["convert", "roboND", str(folder), "--out", str(folder / "poses.txt")]) == 2
    _one_line_error(capsys, "is the input file")
    assert _snapshot(workdir) == before


def test_simulate_keeps_both_old_files_when_the_readings_cannot_be_written(
    workdir: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
) -> None:
    (workdir / "run.csv").write_text("old readings\n")
    (workdir / "run.truth.json").write_text("old truth\n")
    before = _snapshot(workdir)

    def disk_full(*_: object) -> None:
        raise OSError(28, "No space left on device")

    # The failure comes after the truth file has been written (to its temporary file).
    monkeypatch.setattr("sonarcarve.sim.truth.write_readings_csv", disk_full)
    assert main(["simulate", "--world", "doorway", "--out", "run.csv"]) == 2
    _one_line_error(capsys, "run.csv", "No space left on device")
    assert _snapshot(workdir) == before


def test_simulate_refuses_a_truth_file_it_cannot_write(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (workdir / "run.truth.json").mkdir()
    before = _snapshot(workdir)
    assert main(["simulate", "--world", "doorway", "--out", "run.csv"]) == 2
    _one_line_error(capsys, "run.truth.json", "is a directory")
    assert _snapshot(workdir) == before


def test_simulate_writes_both_files_together(workdir: Path) -> None:
    (workdir / "run.truth.json").write_text("old truth\n")
    assert main(["simulate", "--world", "doorway", "--out", "run.csv"]) == 0
    assert (workdir / "run.csv").read_text().startswith("t,sensor,")
    assert (workdir / "run.truth.json").read_text().startswith('{"world"')
    assert not [p for p in workdir.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize(("out", "words"), [
    (str(UNWRITABLE / "x"), ["/proc/x", "cannot create a folder in /proc"]),
    ("afile", ["afile", "exists and is not a directory"]),
    ("afile/sub", ["afile/sub", "afile exists and is not a directory"]),
    ("", ["--out: empty, expected a folder name"]),
])
def test_unwritable_folder_out_is_refused_by_demo_and_experiments(
    workdir: Path, capsys: pytest.CaptureFixture[str], out: str, words: list[str],
) -> None:
    before = _snapshot(workdir)
    for args in (["demo", "--world", "doorway", "--out", out],
                 ["experiments", "--quick", "--only", "t-junction", "--out", out]):
        assert main(args) == 2, args
        _one_line_error(capsys, *words)
        assert _snapshot(workdir) == before, args


def test_experiments_checks_figures_before_running(
    workdir: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    before = _snapshot(workdir)
    assert main(["experiments", "--quick", "--only", "t-junction", "--out", "exp",
                 "--figures", str(UNWRITABLE / "fig")]) == 2
    _one_line_error(capsys, "--figures /proc/fig", "cannot create a folder")
    assert _snapshot(workdir) == before  # no results.json written first


@pytest.mark.parametrize(("text", "words"), [
    ("# My notes\n\nNo markers here.\n", ["has no", BEGIN_MARKER, END_MARKER]),
    (f"# Results\n{BEGIN_MARKER}\nno end\n", [END_MARKER]),
    (f"{END_MARKER}\n{BEGIN_MARKER}\n", [BEGIN_MARKER]),
])
def test_experiments_refuses_a_results_md_without_its_markers(
    workdir: Path, capsys: pytest.CaptureFixture[str], text: str, words: list[str],
) -> None:
    (workdir / "notes.md").write_text(text)
    before = _snapshot(workdir)
    assert main(["experiments", "--quick", "--out", "exp", "--results-md", "notes.md"]) == 2
    _one_line_error(capsys, "notes.md", *words)
    assert _snapshot(workdir) == before


def test_results_md_may_be_new_but_its_folder_must_exist(workdir: Path) -> None:
    from sonarcarve.cli.experiments import _check_results_md
    from sonarcarve.io import OutputError

    _check_results_md(workdir / "new.md")  # created by the run: accepted
    _check_results_md(workdir / "adir" / "new.md")
    (workdir / "ok.md").write_text(f"# R\n\n{BEGIN_MARKER}\nold\n{END_MARKER}\n")
    _check_results_md(workdir / "ok.md")
    with pytest.raises(OutputError, match="does not exist"):
        _check_results_md(workdir / "nowhere" / "new.md")
    with pytest.raises(OutputError, match="is a directory"):
        _check_results_md(workdir / "adir")
    assert not (workdir / "new.md").exists()


def test_readings_progress_draws_a_bar_only_for_long_logs() -> None:
    from sonarcarve.cli.app import SLOW_PROGRESS_MIN_READINGS, readings_progress

    with readings_progress("carve", SLOW_PROGRESS_MIN_READINGS - 1) as short:
        assert short is None
    with readings_progress("carve", SLOW_PROGRESS_MIN_READINGS) as long:
        assert long is not None
        long(SLOW_PROGRESS_MIN_READINGS // 2)  # the callback the writers call
