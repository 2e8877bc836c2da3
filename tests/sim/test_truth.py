"""The simulator's truth file, ``READINGS.truth.json``: writer, reader, name, refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.errors import InputError
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.sim.truth import TRUTH_SUFFIX, read_truth_json, truth_path, write_truth_json
from sonarcarve.sim.world import World

BOX = World(np.array([[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 3.0]]), name="box")


def test_written_text_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "run.truth.json"
    write_truth_json(path, BOX, [EchoKind.DIRECT, EchoKind.FLOOR, EchoKind.MULTIPATH],
                     [[1.0, 2.5], [math.nan, math.nan], [-0.5, 3.0]])
    assert path.read_text(encoding="utf-8") == (
        '{"world": {"name": "box", "segments": [[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 3.0]]},\n'
        ' "readings": [\n'
        '  {"id": 0, "kind": "direct", "reflection": [1.0, 2.5]},\n'
        '  {"id": 1, "kind": "floor", "reflection": null},\n'
        '  {"id": 2, "kind": "multipath", "reflection": [-0.5, 3.0]}\n'
        ' ]}\n'
    )


def test_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "run.truth.json"
    kind = [0, 1, 2, 3, 0]
    reflection = [[0.1, 1 / 3], [math.nan, math.nan], [math.nan, math.nan], [math.pi, -1e-300],
                  [-0.0, 5e-324]]
    write_truth_json(path, BOX, kind, reflection)
    truth = read_truth_json(path)
    assert truth.kind.tolist() == [0, 1, 2, 3, 0]
    assert truth.kind.dtype == np.int64
    assert truth.reflection.shape == (5, 2)
    # Bit for bit, NaN rows where there is no reflection.
    assert truth.reflection.tobytes() == np.array(reflection).tobytes()
    assert truth.world.name == "box"
    assert truth.world.segments.tolist() == [[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 3.0]]


def test_no_readings_no_walls(tmp_path: Path) -> None:
    path = tmp_path / "empty.truth.json"
    write_truth_json(path, World(np.zeros((0, 4)), name="void"), [], np.zeros((0, 2)))
    truth = read_truth_json(path)
    assert truth.kind.shape == (0,)
    assert truth.reflection.shape == (0, 2)
    assert truth.world.segments.shape == (0, 4)
    assert truth.world.name == "void"


def test_writer_refuses_mismatched_lengths(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="2 kinds but 1 reflection points"):
        write_truth_json(tmp_path / "x.truth.json", BOX, [0, 0], [[1.0, 1.0]])
    assert not (tmp_path / "x.truth.json").exists()


def test_labels_are_the_file_contract() -> None:
    assert [(int(k), k.label) for k in EchoKind] == [
        (0, "direct"), (1, "crosstalk"), (2, "floor"), (3, "multipath")]


@pytest.mark.parametrize(("readings_path", "expected"), [
    ("x/run.csv", "x/run.truth.json"),
    ("run.CSV", "run.truth.json"),
    ("run", "run.truth.json"),
    ("run.txt", "run.txt.truth.json"),  # only .csv is replaced
    ("logs.2024/run.v2.csv", "logs.2024/run.v2.truth.json"),
])
def test_truth_path(readings_path: str, expected: str) -> None:
    assert truth_path(readings_path) == Path(expected)
    assert truth_path(Path(readings_path)) == Path(expected)
    assert expected.endswith(TRUTH_SUFFIX)


WORLD = '{"world": {"segments": [[0, 0, 1, 0]]}, '
BIG = "1" + "0" * 400  # an integer too big for a float


@pytest.mark.parametrize(("text", "problem"), [
    ("", "not valid JSON"),
    ("[]", "expected an object"),
    ('{"world": {"segments": []}}', "expected an object"),
    ('{"readings": []}', "'world'"),
    ('{"world": [], "readings": []}', "'world'"),
    ('{"world": {"segments": [[1, 2, 3]]}, "readings": []}', "rows of four numbers"),
    ('{"world": {"segments": [[1, 2], [3, 4]]}, "readings": []}', "rows of four numbers"),
    ('{"world": {"segments": [0, 0, 1, 1]}, "readings": []}', "rows of four numbers"),
    ('{"world": {"segments": [["a", 0, 1, 1]]}, "readings": []}', "rows of four numbers"),
    ('{"world": {"segments": [[' + BIG + ', 0, 1, 1]]}, "readings": []}', "four numbers"),
    ('{"world": {"segments": [[0, 0, NaN, 1]]}, "readings": []}', "must be finite"),
    ('{"world": {"segments": [[1, 1, 1, 1]]}, "readings": []}', "zero length"),
    (WORLD + '"readings": [3]}', "readings[0] must be an object"),
    (WORLD + '"readings": [{"id": 1, "kind": "direct", "reflection": null}]}', "expected 0"),
    (WORLD + '"readings": [{"id": false, "kind": "direct", "reflection": null}]}', "expected 0"),
    (WORLD + '"readings": [{"id": 0.0, "kind": "direct", "reflection": null}]}', "expected 0"),
    (WORLD + '"readings": [{"kind": "direct", "reflection": null}]}', "expected 0"),
    (WORLD + '"readings": [{"id": 0, "kind": "echo", "reflection": null}]}', "unknown kind"),
    (WORLD + '"readings": [{"id": 0, "kind": ["direct"], "reflection": null}]}', "unknown kind"),
    (WORLD + '"readings": [{"id": 0, "kind": "direct", "reflection": [1]}]}',
     "reflection must be"),
    (WORLD + '"readings": [{"id": 0, "kind": "direct", "reflection": [1, NaN]}]}',
     "reflection must be"),
    (WORLD + '"readings": [{"id": 0, "kind": "direct", "reflection": [1, true]}]}',
     "reflection must be"),
    (WORLD + '"readings": [{"id": 0, "kind": "direct", "reflection": [1, "2"]}]}',
     "reflection must be"),
    (WORLD + '"readings": [{"id": 0, "kind": "direct", "reflection": [' + BIG + ', 2]}]}',
     "reflection must be"),
])
def test_malformed_files_fail_with_one_line_naming_the_file(
    tmp_path: Path, text: str, problem: str
) -> None:
    path = tmp_path / "bad.truth.json"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as info:
        read_truth_json(path)
    assert isinstance(info.value, SonarcarveError)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: ")
    assert problem in message


def test_second_bad_reading_is_named(tmp_path: Path) -> None:
    path = tmp_path / "bad.truth.json"
    path.write_text(WORLD + '"readings": [\n {"id": 0, "kind": "floor", "reflection": null},\n'
                    ' {"id": 1, "kind": "ghost", "reflection": null}\n]}')
    with pytest.raises(InputError, match=r"readings\[1\]: unknown kind 'ghost'"):
        read_truth_json(path)


def test_missing_file(tmp_path: Path) -> None:
    path = tmp_path / "absent.truth.json"
    with pytest.raises(InputError, match="no such file"):
        read_truth_json(path)


def test_no_echo_readings_are_kind_none(tmp_path: Path) -> None:
    path = tmp_path / "run.truth.json"
    write_truth_json(path, BOX, [EchoKind.DIRECT, -1], [[1.0, 2.5], [math.nan, math.nan]])
    assert '{"id": 1, "kind": "none", "reflection": null}' in path.read_text(encoding="utf-8")
    truth = read_truth_json(path)
    assert truth.kind.tolist() == [0, -1]
    assert np.isnan(truth.reflection[1]).all()
