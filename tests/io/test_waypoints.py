"""Waypoint files for `sonarcarve simulate --path`: CSV and JSON, with one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sonarcarve.io.errors import InputError
from sonarcarve.io.waypoints import read_waypoints


def test_csv_with_comments_and_extra_columns(tmp_path: Path) -> None:
    path = tmp_path / "path.csv"
    path.write_text("# a lap\nlabel,y,x\na,1.0,2.0\n\nb,3.5,4\n")
    np.testing.assert_array_equal(read_waypoints(path), [[2.0, 1.0], [4.0, 3.5]])


@pytest.mark.parametrize("text", ['{"waypoints": [[0, 0], [1.5, 2]]}', "[[0, 0], [1.5, 2]]"])
def test_json_forms(tmp_path: Path, text: str) -> None:
    path = tmp_path / "path.json"
    path.write_text(text)
    np.testing.assert_array_equal(read_waypoints(path), [[0.0, 0.0], [1.5, 2.0]])


@pytest.mark.parametrize(
    ("name", "text", "problem"),
    [
        ("p.csv", "x,y\n0,0\n1,oops\n", r"line 3, column 'y' is not a number"),
        ("p.csv", "a,b\n0,0\n", r"line 1, header must name columns x and y"),
        ("p.csv", "x,y\n0,0\n", r"at least 2 waypoints, found 1"),
        ("p.json", '{"waypoints": [[0, 0], [1]]}', r"waypoint 1 must be \[x, y\]"),
        ("p.json", "[[0, 0],", r"line 1, column \d+: not valid JSON"),
        ("p.txt", "", r"must end in .csv"),
    ],
)
def test_bad_waypoint_files(tmp_path: Path, name: str, text: str, problem: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError, match=problem) as info:
        read_waypoints(path)
    assert "\n" not in str(info.value)
    assert str(path) in str(info.value)


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        read_waypoints(tmp_path / "none.csv")
