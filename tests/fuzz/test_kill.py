"""Hard stops lose nothing: ``kill -9`` while ``process`` writes leaves the old map or the new one.

The kill lands while the temporary file exists (polled), at a seeded random delay after; the
next run must then remove the dead writer's temporary (:func:`sonarcarve.io.atomic.remove_stale`).
"""

from __future__ import annotations

import json
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.readings import ReadingBatch

SONARCARVE = [sys.executable, "-c", "import sys; from sonarcarve.cli import main; "
                                    "sys.exit(main())"]


def _temps(folder: Path) -> list[Path]:
    return [p for p in folder.iterdir() if p.name.startswith(".map.csv.")]


def test_kill_9_while_writing(tmp_path: Path) -> None:
    rng = np.random.default_rng(0)
    n = 150_000
    batch = ReadingBatch.from_arrays(
        t=np.arange(n) * 0.01, sensor=np.arange(n) % 16, x=rng.uniform(0, 5, n),
        y=rng.uniform(0, 5, n), theta=rng.uniform(-3, 3, n), range=rng.uniform(0.5, 4, n))
    readings = tmp_path / "r.csv"
    write_readings_csv(batch, readings)
    out = tmp_path / "map.csv"
    argv = [*SONARCARVE, "process", str(readings), "--method", "centerline", "--out", str(out)]
    subprocess.run(argv, check=True, capture_output=True, timeout=120)
    new = out.read_bytes()
    old = b"old map\n"
    chooser = random.Random(14)
    kills = 0
    for _ in range(3):
        out.write_bytes(old)
        child = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 60
        while not _temps(tmp_path) and child.poll() is None and time.monotonic() < deadline:
            time.sleep(0.001)
        time.sleep(chooser.uniform(0.0, 0.05))
        if child.poll() is None:
            child.send_signal(signal.SIGKILL)
            kills += 1
        child.wait(timeout=60)
        assert out.read_bytes() in (old, new)  # never a partial file
    assert kills  # at least one kill landed mid-write
    subprocess.run(argv, check=True, capture_output=True, timeout=120)
    assert out.read_bytes() == new
    assert _temps(tmp_path) == []  # the dead writers' temporaries are gone


def _kill_at_random_moments(argv: list[str], out: Path, seed: int, *,
                            outputs: tuple[Path, ...] = (),
                            timed: tuple[Path, ...] = ()) -> None:
    """Run ``argv`` once for the complete outputs, then three times killed at a seeded moment
    of the run (before, during or after writing): each output is always its old bytes or the
    complete new ones; one more full run leaves the new bytes and no temporary file.

    ``timed`` outputs are JSON that records run times, so a complete one is one that parses
    (the other fields are checked equal)."""
    files = (out, *outputs)
    tic = time.monotonic()
    subprocess.run(argv, check=True, capture_output=True, timeout=180)
    duration = time.monotonic() - tic
    new = {f: f.read_bytes() for f in files}
    chooser = random.Random(seed)
    for _ in range(3):
        for f in files:
            f.write_bytes(b"old\n")
        child = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(chooser.uniform(0.2, 1.0) * duration)
        if child.poll() is None:
            child.send_signal(signal.SIGKILL)
        child.wait(timeout=180)
        for f in files:
            if f in timed and f.read_bytes() != b"old\n":
                assert _untimed(f.read_bytes()) == _untimed(new[f])  # whole, not partial
            else:
                assert f.read_bytes() in (b"old\n", new[f])  # never a partial file
    subprocess.run(argv, check=True, capture_output=True, timeout=180)
    for f in files:
        assert (_untimed(f.read_bytes()) == _untimed(new[f]) if f in timed
                else f.read_bytes() == new[f])
    assert [p.name for p in out.parent.iterdir() if p.name.startswith(".")] == []


def _untimed(data: bytes) -> object:
    """A results JSON without its wall-clock fields (raises if the file is not whole JSON)."""
    value = json.loads(data)
    value["meta"].pop("seconds")
    value.pop("office_runs", None)
    return value


def test_kill_9_simulate_and_grid(tmp_path: Path) -> None:
    readings = tmp_path / "r.csv"
    simulate = [*SONARCARVE, "simulate", "--world", "t-junction", "--out", str(readings)]
    _kill_at_random_moments(simulate, readings, 8, outputs=(tmp_path / "r.truth.json",))
    grid = [*SONARCARVE, "grid", str(readings), "--resolution", "0.05",
            "--out", str(tmp_path / "g.yaml")]
    _kill_at_random_moments(grid, tmp_path / "g.yaml", 9, outputs=(tmp_path / "g.pgm",))


def test_kill_9_experiments(tmp_path: Path) -> None:
    out = tmp_path / "exp"
    argv = [*SONARCARVE, "experiments", "--quick", "--only", "t-junction", "--workers", "1",
            "--out", str(out)]
    out.mkdir()
    results = out / "results.json"
    results.write_bytes(b"old\n")  # so that the first run has an old file to replace
    _kill_at_random_moments(argv, results, 10, outputs=(out / "fig04_t_junction.png",),
                            timed=(results,))
