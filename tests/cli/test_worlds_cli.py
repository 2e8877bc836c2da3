"""``sonarcarve worlds``: lists the built-ins, describes and converts given worlds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.sim.world import builtin_worlds, load_world


def test_worlds_lists_every_builtin(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["worlds"]) == 0
    out = capsys.readouterr().out
    for name in builtin_worlds():
        assert name in out
    assert "5,400" in out  # the office's area, m²


def test_worlds_describes_and_writes_one_world(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "frozen.json"
    assert main(["worlds", "random:2:20x15", "--out", str(out)]) == 0
    assert "random:2:20x15" in capsys.readouterr().out
    frozen, fresh = load_world(out), load_world("random:2:20x15")
    np.testing.assert_array_equal(frozen.segments, fresh.segments)
    assert frozen.name == "random:2:20x15"


def test_worlds_bad_input_is_one_line_exit_2(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["worlds", "nowhere"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "unknown world 'nowhere'" in err
    assert main(["worlds", "--out", str(tmp_path / "x.json")]) == 2
    assert "exactly one world" in capsys.readouterr().err
