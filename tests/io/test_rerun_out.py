"""Rerun recordings: written whole, read back with rerun's own loader."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sonarcarve.errors import ConfigError
from sonarcarve.io.rerun_out import write_rerun
from sonarcarve.methods import make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch, ReadingsError

rerun_chunk = pytest.importorskip("rerun.chunk")

N = 23


def _readings() -> ReadingBatch:
    """Two sensors on a robot driving along +x past a wall at y = 2."""
    sensor = np.arange(N) % 2
    return ReadingBatch.from_arrays(t=0.1 * np.arange(N), sensor=sensor, x=0.05 * np.arange(N),
                                    y=np.zeros(N), theta=np.where(sensor == 0, math.pi / 2, 1.2),
                                    range=np.where(sensor == 0, 2.0, 2.0 / math.sin(1.2)))


def _chunks(path: Path) -> dict[str, list[Any]]:
    """Chunks of the recording by entity path, as rerun's own reader gives them."""
    by_entity: dict[str, list[Any]] = {}
    for chunk in rerun_chunk.RrdReader(path).stream().to_chunks():
        by_entity.setdefault(str(chunk.entity_path), []).append(chunk)
    return by_entity


def _rows(chunks: list[Any]) -> int:
    return sum(chunk.num_rows for chunk in chunks)


def test_recording_reads_back_with_every_entity_on_the_time_timeline(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    walls = np.array([[-1.0, 2.0, 3.0, 2.0]])
    global_map = write_rerun(path, _readings(), make_method("combined"), walls=walls, every=5)
    chunks = _chunks(path)
    for entity in ("reading", "robot/sensors", "robot/path/tail", "arcs", "map", "global_map",
                   "walls"):
        assert f"/world/{entity}" in chunks, entity
    assert _rows(chunks["/world/reading"]) == N
    assert _rows(chunks["/world/robot/sensors"]) == N
    assert _rows(chunks["/world/map"]) == math.ceil(N / 5)  # every 5 readings and the last
    assert _rows(chunks["/world/arcs"]) == math.ceil(N / 5)
    (walls_chunk,) = chunks["/world/walls"]
    assert walls_chunk.is_static
    for chunk in chunks["/world/map"]:
        assert {"time", "reading"} <= set(chunk.timeline_names)
    # The global map logged at the end is the one process would write.
    expected = process_readings(_readings(), make_method("combined")).global_map
    np.testing.assert_array_equal(global_map.xy, expected.xy)
    batch = chunks["/world/global_map"][0].to_record_batch()
    positions = batch.column("Points2D:positions").to_pylist()[0]
    np.testing.assert_allclose(np.array(positions), expected.xy, rtol=1e-6)  # float32 on disk


def test_times_are_the_readings_seconds(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    write_rerun(path, _readings(), make_method("carve"))
    (chunk,) = _chunks(path)["/world/reading"]
    times = chunk.to_record_batch().column("time").to_numpy()
    # A duration timeline, stored in nanoseconds.
    np.testing.assert_allclose(times.astype("int64") / 1e9, 0.1 * np.arange(N), atol=1e-9)


def test_given_ids_are_the_maps_ids_and_the_reading_timeline(tmp_path: Path) -> None:
    """Readings a filter kept carry their input rows (the id contract), not their positions."""
    path = tmp_path / "run.rrd"
    ids = 3 * np.arange(N) + 7
    global_map = write_rerun(path, _readings(), make_method("centerline"), ids=ids)
    np.testing.assert_array_equal(np.sort(global_map.reading_id), ids)  # centerline keeps all
    (chunk,) = _chunks(path)["/world/reading"]
    np.testing.assert_array_equal(chunk.to_record_batch().column("reading").to_numpy(), ids)
    with pytest.raises(ReadingsError, match="one per reading"):
        write_rerun(tmp_path / "bad.rrd", _readings(), make_method("carve"), ids=ids[:-1])
    with pytest.raises(ReadingsError, match="must increase"):
        write_rerun(tmp_path / "bad.rrd", _readings(), make_method("carve"), ids=ids[::-1])
    assert not (tmp_path / "bad.rrd").exists()
    # Each arc drawn about its own reading's origin: the same strips as with row positions.
    again = tmp_path / "rows.rrd"
    write_rerun(again, _readings(), make_method("centerline"))
    for entity, column in (("/world/arcs", "LineStrips2D:strips"),
                           ("/world/global_map", "Points2D:positions")):
        mine, rows = (_chunks(p)[entity][-1].to_record_batch() for p in (path, again))
        assert mine.column(column).to_pylist() == rows.column(column).to_pylist(), entity


def test_a_bad_reading_or_every_writes_nothing(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    with pytest.raises(ConfigError, match="every must be at least 1"):
        write_rerun(path, _readings(), make_method("carve"), every=0)
    readings = _readings()
    readings.range[3] = -1.0  # a batch is a value; this one is broken on purpose
    with pytest.raises(ReadingsError):
        write_rerun(path, readings, make_method("carve"))
    assert list(tmp_path.iterdir()) == []


class _Failing:
    """A method that breaks halfway through the log."""

    def __init__(self) -> None:
        self.inner = make_method("carve")

    def add(self, reading: Any, reading_id: int | None = None) -> None:
        if reading_id == N // 2:
            msg = "broken halfway"
            raise RuntimeError(msg)
        self.inner.add(reading, reading_id)

    def local_map(self) -> Any:
        return self.inner.local_map()

    def finish(self) -> Any:
        return self.inner.finish()


def test_a_run_failing_halfway_leaves_an_existing_file_as_it_was(tmp_path: Path) -> None:
    path = tmp_path / "run.rrd"
    path.write_bytes(b"old")
    with pytest.raises(RuntimeError, match="broken halfway"):
        write_rerun(path, _readings(), _Failing(), every=1)
    assert path.read_bytes() == b"old"
    assert list(tmp_path.iterdir()) == [path]


def _strips(chunks: list[Any]) -> list[list[np.ndarray]]:
    """Each logged row of a LineStrips2D entity: its strips as arrays."""
    rows = []
    for chunk in chunks:
        for row in chunk.to_record_batch().column("LineStrips2D:strips").to_pylist():
            rows.append([np.array(strip) for strip in row])
    return rows


def test_the_path_is_logged_in_pieces_that_join_into_each_sensors_path(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A straight drive of 400 readings, two sensors, a vertex every 5 cm (> the 2 cm step):
    # 200 vertices a sensor. With pieces of 60 vertices, every vertex is logged in one piece
    # (its first vertex repeated from the piece before) and in the tails until its piece is
    # cut, so what is logged grows with the log, not with its square.
    from sonarcarve.io import rerun_out

    monkeypatch.setattr(rerun_out, "PATH_PIECE", 60)
    n = 400
    sensor = np.arange(n) % 2
    readings = ReadingBatch.from_arrays(
        t=0.1 * np.arange(n), sensor=sensor, x=0.05 * (np.arange(n) // 2), y=0.3 * sensor,
        theta=np.full(n, math.pi / 2), range=np.full(n, 2.0))
    path = tmp_path / "run.rrd"
    write_rerun(path, readings, make_method("carve"), every=5)
    chunks = _chunks(path)
    names = sorted((name for name in chunks if name.startswith("/world/robot/path/")
                    and name != "/world/robot/path/tail"),
                   key=lambda name: int(name.split("/")[-1]))
    assert len(names) == 6  # 400 vertices in pieces of 60 (a piece is cut at a log, every 5)
    joined: dict[float, list[np.ndarray]] = {}
    for name in [*names, "/world/robot/path/tail"]:
        if name != "/world/robot/path/tail":
            assert _rows(chunks[name]) == 1  # a piece is logged once
        (strips,) = _strips(chunks[name])[-1:]  # the piece; the last tail
        for strip in strips:
            line = joined.setdefault(round(float(strip[0, 1]), 3), [])  # float32 on disk
            if line:
                np.testing.assert_array_equal(strip[0], line[-1][-1])  # pieces join
                strip = strip[1:]
            line.append(strip)
    for y in (0.0, 0.3):
        whole = np.vstack(joined[y])
        np.testing.assert_allclose(whole[:, 0], 0.05 * np.arange(200), atol=1e-6)
        np.testing.assert_allclose(whole[:, 1], y, atol=1e-6)
    logged = sum(len(strip) for name in chunks if name.startswith("/world/robot/path")
                 for row in _strips(chunks[name]) for strip in row)
    whole_path_every_log = sum(5 * j for j in range(1, n // 5 + 1))  # 16,200 vertices
    assert logged < whole_path_every_log / 4


def test_progress_is_reported_every_block_and_at_the_end(tmp_path: Path) -> None:
    # User review: `view` of a long log drew nothing while it worked.
    done: list[int] = []
    write_rerun(tmp_path / "p.rrd", _readings(), make_method("carve"), every=5,
                on_progress=done.append)
    assert done == [5, 10, 15, 20, N]
