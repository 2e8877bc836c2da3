"""Waypoint files for `sonarcarve simulate --path`: CSV and JSON, with one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sonarcarve.io.errors import InputError
from sonarcarve.sim.waypoints import read_waypoints


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
        ("p.json", "[[0, 0],", r"line 1, column \d+: invalid JSON \(Expecting value\)"),
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


@pytest.mark.parametrize(
    ("name", "text"),
    [("same.csv", "x,y\n1.5,2\n1.5,2.0\n1.5,2\n"), ("same.json", "[[1.5, 2], [1.5, 2.0]]")],
)
def test_a_path_of_one_repeated_point_names_the_file(tmp_path: Path, name: str,
                                                     text: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_waypoints(path)
    count = 3 if name.endswith(".csv") else 2
    assert str(info.value) == (f"{path}: a path needs at least 2 distinct waypoints, all {count} "
                               "are (1.5, 2)")


@pytest.mark.parametrize(
    ("name", "text", "problem"),
    [
        ("far.csv", "x,y\n0,0\n1e300,0\n", "line 3, column 'x' must lie within ±100000 m, "
                                           "got '1e300'"),
        ("far.csv", "x,y\n0,0\n0,-100000.5\n", "line 3, column 'y' must lie within ±100000 m"),
        ("far.json", "[[0, 0], [0, 1e300]]", "waypoint 1 must lie within ±100000 m"),
        # An integer too big for a float is not a finite number.
        ("big.json", f"[[0, 0], [{10**400}, 0]]", "waypoint 1 must be [x, y] with finite numbers"),
    ],
)
def test_coordinates_beyond_the_limit_are_refused(tmp_path: Path, name: str, text: str,
                                                  problem: str) -> None:
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(InputError) as info:
        read_waypoints(path)
    message = str(info.value)
    assert message.startswith(f"{path}: ")
    assert problem in message
    assert "\n" not in message
    assert len(message) < 250


def test_coordinates_at_the_limit_are_accepted(tmp_path: Path) -> None:
    path = tmp_path / "edge.csv"
    path.write_text("x,y\n-100000,0\n100000,100000\n")
    np.testing.assert_array_equal(read_waypoints(path), [[-1e5, 0.0], [1e5, 1e5]])
