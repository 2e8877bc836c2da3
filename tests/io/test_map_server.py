"""map_server maps: YAML fields, trinary PGM bytes, round trip, atomic writes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sonarcarve.io.errors import OutputError
from sonarcarve.io.map_server import read_map_server, write_map_server

CELLS = np.array([[100, 0, -1], [0, 0, 100]], dtype=np.int8)  # row 0 = bottom


def test_yaml_fields_and_pgm_bytes(tmp_path: Path) -> None:
    yaml_path, pgm_path = write_map_server(CELLS, 0.05, (-1.5, 2.25), tmp_path / "grid.yaml")
    assert pgm_path == tmp_path / "grid.pgm"
    meta = yaml.safe_load(yaml_path.read_text())
    assert meta == {"image": "grid.pgm", "mode": "trinary", "resolution": 0.05,
                    "origin": [-1.5, 2.25, 0.0], "negate": 0, "occupied_thresh": 0.65,
                    "free_thresh": 0.196}
    # P5, 3 columns, 2 rows; the top row first: the grid's row 1, then row 0.
    assert pgm_path.read_bytes() == b"P5\n3 2\n255\n" + bytes([254, 254, 0, 0, 254, 205])


def test_thresholds_read_the_pixels_back_as_map_server_does(tmp_path: Path) -> None:
    write_map_server(CELLS, 0.1, (0.0, 0.0), tmp_path / "g.yaml")
    occupancy = {p: (255 - p) / 255 for p in (0, 254, 205)}  # negate 0
    assert occupancy[0] > 0.65
    assert occupancy[254] < 0.196
    assert 0.196 < occupancy[205] < 0.65  # unknown: neither


def test_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    cells = rng.choice(np.array([100, 0, -1], dtype=np.int8), size=(17, 23))
    path, _ = write_map_server(cells, 0.1, (3.0, -4.0), tmp_path / "m.yaml")
    back = read_map_server(path)
    assert np.array_equal(back.cells, cells)
    assert (back.resolution, back.origin) == (0.1, (3.0, -4.0, 0.0))
    assert (back.occupied_thresh, back.free_thresh, back.image) == (0.65, 0.196, "m.pgm")


def test_an_error_writes_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "grid.yaml"
    with pytest.raises(OutputError, match="expected 100"):
        write_map_server(np.array([[100, 3]]), 0.1, (0.0, 0.0), target)
    with pytest.raises(OutputError, match="resolution"):
        write_map_server(CELLS, float("nan"), (0.0, 0.0), target)
    with pytest.raises(OutputError, match="does not exist"):
        write_map_server(CELLS, 0.1, (0.0, 0.0), tmp_path / "missing" / "grid.yaml")

    def broken(self: Path, *args: object, **kwargs: object) -> int:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Path, "write_text", broken)
    with pytest.raises(OutputError, match="No space left"):
        write_map_server(CELLS, 0.1, (0.0, 0.0), target)
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no file, no temporary


def test_a_failed_write_leaves_the_old_map(tmp_path: Path,
                                           monkeypatch: pytest.MonkeyPatch) -> None:
    target = tmp_path / "grid.yaml"
    write_map_server(CELLS, 0.1, (0.0, 0.0), target)
    before = target.read_bytes(), (tmp_path / "grid.pgm").read_bytes()

    def broken(self: Path, *args: object, **kwargs: object) -> int:
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(Path, "write_text", broken)
    with pytest.raises(OutputError):
        write_map_server(np.zeros((4, 4), dtype=np.int8), 0.2, (1.0, 1.0), target)
    assert (target.read_bytes(), (tmp_path / "grid.pgm").read_bytes()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["grid.pgm", "grid.yaml"]
