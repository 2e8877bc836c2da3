"""`sonarcarve sweep` in-process: a tiny grid, its table, and a rerun that skips it all."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

import sonarcarve.cli.sweep  # noqa: F401  registers the command until main.py lists it
from sonarcarve.cli import main


def test_sweep_writes_a_table_and_resumes(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    args = ["sweep", "--param", "history=50,100", "--method", "carve", "--length", "3",
            "--workers", "1", "--out", str(tmp_path)]
    assert main(args) == 0
    with (tmp_path / "runs.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert [row["history"] for row in rows] == ["50", "100"]
    assert all(row["method"] == "carve" for row in rows)
    capsys.readouterr()
    assert main(args) == 0
    assert "already finished" in capsys.readouterr().out
    assert len((tmp_path / "runs.jsonl").read_text().splitlines()) == 2


def test_a_bad_parameter_is_a_one_line_error(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "--param", "warp=1", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "warp" in err
    assert len(err.splitlines()) == 1


def test_a_bad_length_names_the_option(tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "--length", "0", "--out", str(tmp_path / "sw")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "sonarcarve: error: --length must be > 0 metres, got 0"
    assert not (tmp_path / "sw").exists()


def test_a_bad_sweep_point_leaves_no_folder(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "--param", "history=0,250", "--out", str(tmp_path / "sw")]) == 2
    err = capsys.readouterr().err.strip()
    assert "sweep point {'history': 0}" in err
    assert "history_size" in err
    assert not (tmp_path / "sw").exists()  # refused before the folder was made


def test_an_angle_out_of_range_is_named_in_degrees(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "--param", "psi=0,20", "--out", str(tmp_path / "sw")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.endswith("min_transversal_deg must lie in (0, 90] degrees, got 0"), err
