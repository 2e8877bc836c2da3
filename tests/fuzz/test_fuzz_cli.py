"""Seeded, bounded fuzzing of every input file through the real CLI.

Each family starts from a valid file generated here (no binary fixtures), mutates its bytes
with a seeded generator and runs the command that reads it. ``make test`` runs a few hundred
cases; ``FUZZ_CASES=5000 pytest -m fuzz tests/fuzz`` runs thousands per family. A case that
ever fails is kept in ``test_regressions.py``.
"""

from __future__ import annotations

import functools
import json
import os
import random
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml

from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.readings import ReadingBatch

Case = tuple[dict[str, bytes], list[str], str | None]

#: A 6 m x 5 m box with one inner wall; its tour is a 1 m drive (a few dozen firings).
WORLD = {"name": "box", "segments": [[0, 0, 6, 0], [6, 0, 6, 5], [6, 5, 0, 5], [0, 5, 0, 0],
                                     [3, 3, 3, 5]], "tour": [[1, 1], [2, 1]]}
ROBOT = {"name": "duo", "robot_radius": 0.2, "range_resolution": 0.01, "min_range": 0.1,
         "max_range": 4.0, "firing_period": 0.05, "beam_width_deg": 25,
         "sensors": [{"x": 0.2, "y": 0.0, "bearing_deg": 0},
                     {"x": 0.0, "y": 0.2, "bearing_deg": 90}]}


def _readings_csv() -> bytes:
    rng = np.random.default_rng(0)
    n = 40
    theta = rng.uniform(-np.pi, np.pi, n)
    batch = ReadingBatch.from_arrays(
        t=np.arange(n) * 0.04, sensor=np.arange(n) % 8, x=rng.uniform(0, 1, n),
        y=rng.uniform(0, 1, n), theta=theta, range=rng.uniform(0.5, 4.0, n),
        beam_width=np.full(n, 0.39))
    return _written(lambda path: write_readings_csv(batch, path), "r.csv")


def _written(write: Callable[[Path], object], name: str) -> bytes:
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        write(path)
        return path.read_bytes()


@functools.cache
def _bags() -> dict[str, bytes]:
    """A 1 s drive of scout2 in a box (23 echoes) as a ROS 1 bag and as an MCAP file."""
    from sonarcarve.robot import load_robot
    from sonarcarve.sim.bag import write_simulation_bag
    from sonarcarve.sim.motion import Trajectory
    from sonarcarve.sim.simulate import simulate
    from sonarcarve.sim.world import World

    box = World(np.array(WORLD["segments"][:4], dtype=float), name="box")
    t = np.linspace(0.0, 1.0, 11)
    drive = Trajectory(t, 1.0 + 0.5 * t, np.full(t.size, 1.0), np.full(t.size, 0.3))
    sim = simulate(box, load_robot("scout2"), drive, seed=1)
    return {name: _written(lambda path: write_simulation_bag(path, sim), name)
            for name in ("run.bag", "run.mcap")}


def _pgm() -> bytes:
    pixels = np.full((20, 30), 254, dtype=np.uint8)
    pixels[0, :] = pixels[-1, :] = pixels[:, 0] = pixels[:, -1] = 0
    return b"P5\n30 20\n255\n" + pixels.tobytes()


MAP_YAML = yaml.safe_dump({"image": "m.pgm", "resolution": 0.2, "origin": [0.0, 0.0, 0.0],
                           "negate": 0, "occupied_thresh": 0.65, "free_thresh": 0.196}).encode()
WAYPOINTS = b"x,y\n1,1\n2,1\n"
SIM = ["simulate", "--clean", "--out", "out.csv"]


def _families() -> dict[str, Callable[[random.Random, Callable[..., bytes]], Case]]:
    csv = _readings_csv()
    world = json.dumps(WORLD).encode()
    robot = yaml.safe_dump(ROBOT).encode()

    def readings(rng: random.Random, mutate: Callable[..., bytes]) -> Case:
        method = rng.choice(["centerline", "carve", "atm", "combined"])
        # Half the cases through the occlusion map filter: the whole map held, origins kept.
        occlusion = rng.choice([[], ["--occlusion-depth", "0.5"]])
        return ({"r.csv": mutate(csv, rng)},
                ["process", "r.csv", "--method", method, *occlusion, "--out", "out.csv"],
                "out.csv")

    def world_json(rng: random.Random, mutate: Callable[..., bytes]) -> Case:
        return ({"w.json": mutate(world, rng), "p.csv": WAYPOINTS},
                [*SIM, "--world", "w.json", "--robot", "roboND-8", "--path", "p.csv"], "out.csv")

    def robot_yaml(rng: random.Random, mutate: Callable[..., bytes]) -> Case:
        return ({"w.json": world, "r.yaml": mutate(robot, rng)},
                [*SIM, "--world", "w.json", "--robot", "r.yaml"], "out.csv")

    def map_yaml(rng: random.Random, mutate: Callable[..., bytes]) -> Case:
        files = {"m.yaml": MAP_YAML, "m.pgm": _pgm(), "p.csv": b"x,y\n2,2\n3,2\n"}
        key = rng.choice(["m.yaml", "m.pgm"])
        files[key] = mutate(files[key], rng)
        return files, [*SIM, "--world", "m.yaml", "--robot", "roboND-8", "--path", "p.csv"], \
            "out.csv"

    def waypoints(rng: random.Random, mutate: Callable[..., bytes]) -> Case:
        name = rng.choice(["p.csv", "p.json"])
        text = WAYPOINTS if name == "p.csv" else b"[[1, 1], [2, 1]]"
        return ({"w.json": world, name: mutate(text, rng)},
                [*SIM, "--world", "w.json", "--robot", "roboND-8", "--path", name], "out.csv")

    def rosbag(rng: random.Random, mutate: Callable[..., bytes]) -> Case:
        name = rng.choice(["run.bag", "run.mcap"])
        command = rng.choice([["convert", "rosbag"], ["process"]])
        return ({name: mutate(_bags()[name], rng)}, [*command, name, "--out", "out.csv"],
                "out.csv")

    return {"readings": readings, "world_json": world_json, "robot_yaml": robot_yaml,
            "map_yaml": map_yaml, "waypoints": waypoints, "rosbag": rosbag}


FAMILIES = _families()
#: Cases per family in ``make test``: about 250 in all, well under a minute.
QUICK = {"readings": 100, "world_json": 40, "robot_yaml": 40, "map_yaml": 35, "waypoints": 35,
         "rosbag": 40}
#: Crashes the fuzzer finds that are still open, by family: the exception that escapes and
#: why. Every case still runs; the family's test is marked xfail (visibly, not skipped) if one
#: of these was met and nothing else went wrong, and passes once it is fixed (then remove it).
OPEN_CRASHES: dict[str, tuple[type[BaseException], str]] = {}


def _fuzz(family: str, cases: int, seed: int, tmp_path: Path, run_cli: Callable[..., object],
          mutator: Callable[..., bytes]) -> None:
    make = FAMILIES[family]
    rng = random.Random(f"{family}:{seed}")
    known, reason = OPEN_CRASHES.get(family, (None, ""))
    met = 0
    for i in range(cases):
        files, argv, out = make(rng, mutator)
        try:
            run_cli(tmp_path / f"case{i}", files, argv, out)
        except BaseException as err:
            if known is None or not isinstance(err, known):
                raise
            met += 1
    if met:
        pytest.xfail(f"{met} of {cases} cases: {reason}")


@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_fuzz_quick(family: str, tmp_path: Path, run_cli: Callable[..., object],
                    mutator: Callable[..., bytes]) -> None:
    _fuzz(family, QUICK[family], 0, tmp_path, run_cli, mutator)


@pytest.mark.fuzz
@pytest.mark.parametrize("family", sorted(FAMILIES))
def test_fuzz_long(family: str, tmp_path: Path, run_cli: Callable[..., object],
                   mutator: Callable[..., bytes]) -> None:
    cases = int(os.environ.get("FUZZ_CASES", "0"))
    if not cases:
        pytest.skip("the long run: FUZZ_CASES=5000 pytest -m fuzz tests/fuzz (make fuzz)")
    _fuzz(family, cases, int(os.environ.get("FUZZ_SEED", "1")), tmp_path, run_cli, mutator)
