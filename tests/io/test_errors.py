"""The shared file-reading helpers: one wording for every loader, raised as the caller's error."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.errors import (
    InputError,
    finite_number,
    load_json,
    load_yaml,
    parse_json,
    parse_yaml,
    read_text,
)
from sonarcarve.io.roboND import read_robond
from sonarcarve.robot import RobotError, load_robot
from sonarcarve.sim.waypoints import read_waypoints
from sonarcarve.sim.world import WorldError, load_world


class _MyError(SonarcarveError):
    """Stands for a caller's own error class."""


def test_read_text_returns_text_without_bom_and_with_unix_newlines(tmp_path: Path) -> None:
    path = tmp_path / "a.txt"
    path.write_bytes(b"\xef\xbb\xbfx,y\r\n1,2\r3,4\n")
    assert read_text(path) == "x,y\n1,2\n3,4\n"


def test_read_text_problems_are_one_line_in_the_callers_class(tmp_path: Path) -> None:
    missing = tmp_path / "gone.json"
    with pytest.raises(_MyError) as info:
        read_text(missing, _MyError)
    assert str(info.value) == f"{missing}: no such file"
    with pytest.raises(_MyError) as info:
        read_text(tmp_path, _MyError)
    assert str(info.value) == f"{tmp_path}: is a directory"
    binary = tmp_path / "latin1.csv"
    # Two good lines, then "é" in Latin-1 (0xe9, not valid UTF-8 here) on line 3.
    binary.write_bytes(b"x,y\n1,2\ncaf\xe9,3\n")
    with pytest.raises(_MyError) as info:
        read_text(binary, _MyError)
    assert str(info.value) == f"{binary}: line 3: not UTF-8 text (byte 0xe9)"
    assert info.value.__cause__ is None
    assert info.value.__suppress_context__


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="root reads files whatever their permissions")
def test_read_text_permission_denied(tmp_path: Path) -> None:
    path = tmp_path / "secret.json"
    path.write_text("{}")
    path.chmod(0)
    with pytest.raises(InputError, match=r"secret\.json: permission denied$"):
        read_text(path)


@pytest.mark.parametrize(
    ("parse", "text", "expected"),
    [
        # '[1, 2' ends at column 6 of line 2: the JSON parser wants ',' or ']' there.
        (parse_json, '\n[1, 2', "f.x: line 2, column 6: invalid JSON (Expecting ',' delimiter)"),
        (parse_json, "[" * 100_000, "f.x: invalid JSON (nested too deeply)"),
        (parse_json, "1" * 5000, "f.x: invalid JSON (Exceeds the limit"),
        # The second ':' of "key: a: b" is at line 2, column 7.
        (parse_yaml, "a: 1\nkey: a: b\n", "f.x: line 2, column 7: invalid YAML (mapping values "
                                         "are not allowed here)"),
        (parse_yaml, "a: " + "1" * 5000, "f.x: invalid YAML (Exceeds the limit"),
    ],
)
def test_parse_errors_name_line_and_column(parse: Callable[..., object], text: str,
                                           expected: str) -> None:
    with pytest.raises(_MyError) as info:
        parse(text, "f.x", _MyError)
    # Python's own wording of its integer-size limit varies by version: compare up to it.
    assert str(info.value) == expected or (
        expected.endswith("(Exceeds the limit") and str(info.value).startswith(expected)
        and "\n" not in str(info.value))


def test_load_json_and_yaml_read_then_parse(tmp_path: Path) -> None:
    (tmp_path / "a.json").write_text('{"k": [1, 2.5]}')
    (tmp_path / "a.yaml").write_text("k: [1, 2.5]\n")
    assert load_json(tmp_path / "a.json") == {"k": [1, 2.5]}
    assert load_yaml(tmp_path / "a.yaml") == {"k": [1, 2.5]}
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(InputError, match=r"bad\.json: line 1, column 2: invalid JSON"):
        load_json(tmp_path / "bad.json")


def test_finite_number() -> None:
    assert [finite_number(v) for v in (0, -3, 2.5, 10**300)] == [0.0, -3.0, 2.5, 1e300]
    assert [finite_number(v) for v in (True, "1", None, [1], float("inf"), float("nan"),
                                       10**400)] == [None] * 7


# Every loader that reads a file the user names, with the error class it must raise.
_LOADERS: dict[str, tuple[str, Callable[[Path], object], type[SonarcarveError]]] = {
    "waypoints csv": ("p.csv", read_waypoints, InputError),
    "waypoints json": ("p.json", read_waypoints, InputError),
    "world json": ("w.json", load_world, WorldError),
    "world yaml": ("w.yaml", load_world, WorldError),
    "robot yaml": ("r.yaml", load_robot, RobotError),
    "roboND": ("poses.txt", lambda path: read_robond(path.parent), InputError),
}


@pytest.mark.parametrize("loader", sorted(_LOADERS))
def test_every_loader_words_file_problems_the_same(tmp_path: Path, loader: str) -> None:
    name, load, error = _LOADERS[loader]
    path = tmp_path / name
    with pytest.raises(error) as info:
        load(path)
    assert str(info.value) == f"{path}: no such file"
    path.mkdir()
    with pytest.raises(error) as info:
        load(path)
    assert str(info.value) == f"{path}: is a directory"
    path.rmdir()
    path.write_bytes(b"\n\xff\n")
    with pytest.raises(error) as info:
        load(path)
    assert str(info.value) == f"{path}: line 2: not UTF-8 text (byte 0xff)"


@pytest.mark.parametrize("loader", ["waypoints json", "world json"])
def test_json_loaders_word_syntax_errors_the_same(tmp_path: Path, loader: str) -> None:
    name, load, error = _LOADERS[loader]
    path = tmp_path / name
    path.write_text('{"a": 1,\n  }')
    with pytest.raises(error) as info:
        load(path)
    # The trailing comma: a property name was expected at line 2, column 3.
    assert str(info.value) == (f"{path}: line 2, column 3: invalid JSON (Expecting property "
                               "name enclosed in double quotes)")


@pytest.mark.parametrize("loader", ["world yaml", "robot yaml"])
def test_yaml_loaders_word_syntax_errors_the_same(tmp_path: Path, loader: str) -> None:
    name, load, error = _LOADERS[loader]
    path = tmp_path / name
    path.write_text("name: x\nkey: a: b\n")
    with pytest.raises(error) as info:
        load(path)
    # The second ':' of "key: a: b" is at line 2, column 7.
    assert str(info.value) == (f"{path}: line 2, column 7: invalid YAML (mapping values are not "
                               "allowed here)")
