"""map_server maps: YAML fields, trinary PGM bytes, round trip, atomic writes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from sonarcarve.io import map_server
from sonarcarve.io.errors import InputError, OutputError
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


@pytest.mark.parametrize("resolution", [0.0, -0.05, float("inf")])
def test_write_rejects_a_resolution_that_is_not_positive_and_finite(
        tmp_path: Path, resolution: float) -> None:
    with pytest.raises(OutputError, match="resolution must be a finite number > 0"):
        write_map_server(CELLS, resolution, (0.0, 0.0), tmp_path / "grid.yaml")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("origin", [(float("nan"), 0.0), (0.0, float("inf"))])
def test_write_rejects_an_origin_that_is_not_finite(tmp_path: Path,
                                                    origin: tuple[float, float]) -> None:
    with pytest.raises(OutputError, match="origin must be two finite numbers"):
        write_map_server(CELLS, 0.1, origin, tmp_path / "grid.yaml")
    assert list(tmp_path.iterdir()) == []


def test_write_needs_a_yaml_file_name(tmp_path: Path) -> None:
    # The PGM goes beside the YAML under the same stem: "grid.pgm" as the YAML name would make
    # both files the same path.
    with pytest.raises(OutputError, match=r"needs a \.yaml file name"):
        write_map_server(CELLS, 0.1, (0.0, 0.0), tmp_path / "grid.pgm")
    assert list(tmp_path.iterdir()) == []
    yml, _ = write_map_server(CELLS, 0.1, (0.0, 0.0), tmp_path / "grid.YML")  # either spelling
    assert yml.name == "grid.YML"


def _write_by_hand(folder: Path, pgm: bytes, **fields: object) -> Path:
    """A map_server pair written without write_map_server: the YAML fields as given."""
    meta: dict[str, object] = {"image": "m.pgm", "resolution": 0.1, "origin": [0.0, 0.0, 0.0],
                               "negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196}
    meta.update(fields)
    (folder / "m.pgm").write_bytes(pgm)
    path = folder / "m.yaml"
    path.write_text(yaml.safe_dump(meta), encoding="utf-8")
    return path


# A 2 x 2 image by hand, top row first: occupied, free / unknown, free.
PGM_2X2 = b"P5\n2 2\n255\n" + bytes([0, 254, 205, 254])


def test_read_a_map_written_by_hand(tmp_path: Path) -> None:
    m = read_map_server(_write_by_hand(tmp_path, PGM_2X2, resolution=0.25,
                                       origin=[-1.0, 2.0, 0.0]))
    # Row 0 of the cells is the bottom of the image.
    assert m.cells.tolist() == [[-1, 0], [100, 0]]
    assert (m.resolution, m.origin, m.image) == (0.25, (-1.0, 2.0, 0.0), "m.pgm")


@pytest.mark.parametrize("pgm", [
    # map_saver writes a comment line into the header; PGM allows one between any two fields.
    b"P5\n# CREATOR: map_saver.cpp 0.100 m/pix\n2 2\n255\n" + bytes([0, 254, 205, 254]),
    b"P5 2 # width\n2 255\n" + bytes([0, 254, 205, 254]),
    # Bytes after the raster (a trailing newline, a second image) are not pixels of this one:
    # a trailing 205 byte once shifted the whole image by one pixel, silently.
    PGM_2X2 + b"\n",
    PGM_2X2 + bytes([205]),
])
def test_read_takes_the_raster_right_after_the_header(tmp_path: Path, pgm: bytes) -> None:
    m = read_map_server(_write_by_hand(tmp_path, pgm))
    assert m.cells.tolist() == [[-1, 0], [100, 0]]


def test_read_calls_a_short_raster_truncated(tmp_path: Path) -> None:
    # One pixel short: it used to be read as if the header's last byte were a pixel.
    with pytest.raises(InputError, match=r"2 x 2 pixels but 3 bytes of them \(truncated\?\)"):
        read_map_server(_write_by_hand(tmp_path, PGM_2X2[:-1]))


@pytest.mark.parametrize(("fields", "pgm", "match"), [
    ({"resolution": 0.0}, PGM_2X2, "resolution must be > 0"),
    ({"resolution": -0.1}, PGM_2X2, "resolution must be > 0"),
    ({"origin": [0.0, 0.0, 0.5]}, PGM_2X2, "origin yaw must be 0"),
    ({"origin": [0.0, 0.0]}, PGM_2X2, r"origin must be \[x, y, yaw\]"),
    ({}, PGM_2X2.replace(b"\xcd", b"\x80"), "not trinary"),  # a grey pixel, 128
    ({}, b"P5\n2 2\n65535\n" + bytes(8), "not a binary 8-bit PGM"),  # 16-bit pixels
    ({}, b"P2\n2 2\n255\n0 254 205 254\n", "not a binary 8-bit PGM"),  # ASCII PGM
    # 10 x 10 pixels announced, 50 there.
    ({}, b"P5\n10 10\n255\n" + bytes([254]) * 50, "truncated"),
])
def test_read_rejects_what_map_server_would_misread(tmp_path: Path, fields: dict[str, object],
                                                    pgm: bytes, match: str) -> None:
    with pytest.raises(InputError, match=match):
        read_map_server(_write_by_hand(tmp_path, pgm, **fields))


@pytest.mark.parametrize("key", ["image", "resolution", "origin", "occupied_thresh",
                                 "free_thresh"])
def test_read_names_a_missing_key(tmp_path: Path, key: str) -> None:
    path = _write_by_hand(tmp_path, PGM_2X2)
    meta = yaml.safe_load(path.read_text())
    del meta[key]
    path.write_text(yaml.safe_dump(meta), encoding="utf-8")
    with pytest.raises(InputError, match=f"missing key '{key}'"):
        read_map_server(path)


def test_read_refuses_an_image_over_the_size_limit(tmp_path: Path,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    path = _write_by_hand(tmp_path, PGM_2X2)  # 15 bytes
    monkeypatch.setattr(map_server, "MAX_PGM_BYTES", 14)
    with pytest.raises(InputError, match="larger than the limit of 14 bytes"):
        read_map_server(path)
    monkeypatch.setattr(map_server, "MAX_PGM_BYTES", 15)
    assert read_map_server(path).cells.shape == (2, 2)
