"""Every crash the fuzzing of issue 14 found, kept as a case: inputs made by code, not files.

Each gave a traceback, a hang or a changed file before; each must now give exactly one
``sonarcarve: error:`` line, exit code 2 and leave the old output as it was.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from sonarcarve.geometry.index import arc_box

SCOUT = (Path(__file__).parents[2] / "src/sonarcarve/robots/scout2.yaml").read_bytes()
BOX = b'{"segments": [[0,0,6,0],[6,0,6,5],[6,5,0,5],[0,5,0,0]], "tour": [[1,1],[2,1]]}'
READINGS = b"t,sensor,x,y,theta,range\n0,0,0,0,0,1\n0.1,1,0,0,1,2\n"


def _bomb(last: bytes) -> bytes:
    levels = b"".join(f"{k}: &{k} [{', '.join([f'*{p}'] * 9)}]\n".encode()
                      for p, k in zip("abcdefgh", "bcdefghi", strict=True))
    return b'a: &a ["lol","lol","lol","lol","lol","lol","lol","lol","lol"]\n' + levels + last


SIM = ["simulate", "--clean", "--out", "out.csv"]
CASES: dict[str, tuple[dict[str, bytes], list[str], str]] = {
    "robot yaml bomb (name)": ({"r.yaml": _bomb(b"name: *i\n"), "w.json": BOX},
                               [*SIM, "--world", "w.json", "--robot", "r.yaml"], "alias"),
    "map.yaml bomb (image)": ({"m.yaml": _bomb(b"image: *i\nresolution: 0.1\norigin: [0,0,0]\n")},
                              [*SIM, "--world", "m.yaml"], "alias"),
    "map.yaml bomb (resolution)": ({"m.yaml": _bomb(b"image: m.pgm\nresolution: *i\n"
                                                    b"origin: [0,0,0]\n")},
                                   [*SIM, "--world", "m.yaml"], "alias"),
    "robot firing_order 10**20": ({"r.yaml": SCOUT.replace(b"firing_order: [0,",
                                                          b"firing_order: [99999999999999999999,"),
                                   "w.json": BOX},
                                  [*SIM, "--world", "w.json", "--robot", "r.yaml"],
                                  "firing_order"),
    "robot firing_order of 2 million": ({"r.yaml": SCOUT.replace(
        b"firing_order: [0,", b"firing_order: [" + b"0," * 2_000_000), "w.json": BOX},
        [*SIM, "--world", "w.json", "--robot", "r.yaml"], "larger than the limit"),
    "world 1e300 with tour": ({"w.json": b'{"segments": [[0,0,1e300,0],[0,3,1e300,3]], '
                                         b'"tour": [[1,1.5],[5,1.5]]}'},
                              [*SIM, "--world", "w.json"], "MAX_WORLD_COORDINATE"),
    "world 1e300 explored": ({"w.json": b'{"segments": [[0,0,1e300,1e300],[0,1,1e300,-1e300]]}'},
                             [*SIM, "--world", "w.json", "--explore", "5"],
                             "MAX_WORLD_COORDINATE"),
    "waypoints 100 km": ({"p.csv": b"x,y\n0,0\n100000,0\n"},
                         [*SIM, "--world", "doorway", "--path", "p.csv"],
                         # refused before simulating since the UX review (finding 6); the
                         # firing limit itself is tested in tests/test_robot.py
                         "p.csv: line 3, waypoint (100000, 0) lies outside world 'doorway'"),
    "readings header of 100 kB": ({"r.csv": b"t,sensor,x,y,theta," + b"r" * 100_000
                                   + b"\n1,0,0,0,0,1\n"},
                                  ["process", "r.csv", "--out", "out.csv"], "missing column"),
    "--out name too long": ({"r.csv": READINGS},
                            ["process", "r.csv", "--out", "x" * 300 + ".csv"], "too long"),
    "--out with a trailing slash": ({"r.csv": READINGS},
                                    ["process", "r.csv", "--out", "out.csv/"], "ends in '/'"),
    "readings theta 1e20 (hung carve, atm, combined)": (
        {"r.csv": READINGS + b"0.2,0,0,0,1e20,1\n"}, ["process", "r.csv", "--out", "out.csv"],
        "line 4, column 'theta' must lie within ±1,000,000 rad"),
    "readings theta -1.7e308": ({"r.csv": READINGS + b"0.2,0,0,0,-1.7e308,1\n"},
                                ["process", "r.csv", "--method", "atm", "--out", "out.csv"],
                                "line 4, column 'theta' must lie within ±1,000,000 rad"),
    "readings range 1.7e308 (NaN points, RuntimeWarnings)": (
        {"r.csv": READINGS + b"0.2,0,0,0,0,1.7e308\n"}, ["process", "r.csv", "--out", "out.csv"],
        "line 4, column 'range' must be at most 10,000 m"),
    "readings x 1e300": ({"r.csv": READINGS + b"0.2,0,1e300,0,0,1\n"},
                         ["process", "r.csv", "--out", "out.csv"],
                         "line 4, column 'x' must lie within ±1,000,000 m"),
    "readings from /dev/zero (read until memory ran out)": (
        {}, ["process", "/dev/zero", "--out", "out.csv"],
        "/dev/zero: not text (NUL byte at line 1)"),
    "readings without line breaks": ({"r.csv": b"t,sensor" + b"x" * (2**20 + 5)},
                                     ["grid", "r.csv", "--out", "out.yaml"],
                                     "line 1 is longer than 1 MiB: not a readings CSV"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_regression(name: str, tmp_path: Path, run_cli: Callable[..., tuple[int, str]]) -> None:
    files, argv, words = CASES[name]
    code, err = run_cli(tmp_path, files, argv, "out.csv")
    assert code == 2
    assert words in err


def test_out_through_a_dangling_link(tmp_path: Path,
                                     run_cli: Callable[..., tuple[int, str]]) -> None:
    tmp_path.mkdir(exist_ok=True)
    (tmp_path / "link.csv").symlink_to("nowhere.csv")
    code, err = run_cli(tmp_path, {"r.csv": READINGS},
                        ["process", "r.csv", "--out", "link.csv"], None)
    assert code == 2
    assert "is a symbolic link to nowhere.csv, which does not exist" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.csv", "r.csv"]


@pytest.mark.parametrize("method", ["carve", "atm", "combined"])
def test_huge_theta_ends_within_a_timeout(method: str, tmp_path: Path) -> None:
    """theta = 1e20 hung these methods (arc_box's loop over multiples of π/2 never ended); run
    in a process of its own, so that a hang fails the test instead of stalling the suite."""
    (tmp_path / "r.csv").write_bytes(READINGS + b"0.2,0,0,0,1e20,1\n0.3,0,0,0,0.5,1\n")
    argv = ["process", "r.csv", "--method", method, "--out", "out.csv"]
    done = subprocess.run(
        [sys.executable, "-c", "import sys; from sonarcarve.cli import main; "
                               "sys.exit(main(sys.argv[1:]))", *argv],
        cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False,
        env={**os.environ, "COLUMNS": "200"})
    assert done.returncode == 2, done.stderr
    assert done.stderr.splitlines() == [
        "sonarcarve: error: r.csv: line 4, column 'theta' must lie within ±1,000,000 rad"]
    assert not (tmp_path / "out.csv").exists()


@pytest.mark.parametrize("lo", [1e20, -1e20, 1.7e308, -1.7e308, 2.0**53 * math.pi / 2])
def test_arc_box_ends_for_any_angle(lo: float) -> None:
    """The loop itself is bounded, even for angles validation refuses (it never ended at
    1e20), and its box still holds the arc's ends."""
    xmin, xmax, ymin, ymax = arc_box(0.0, 0.0, 1.0, lo, lo + 0.4)
    for angle in (lo, lo + 0.4):
        assert xmin <= math.cos(angle) <= xmax
        assert ymin <= math.sin(angle) <= ymax


def _mcap_with_a_huge_summary_record() -> bytes:
    """The fuzz suite's MCAP bag with the length of its first summary record set beyond any
    index (found by `make fuzz`: rosbags' read raised OverflowError, a traceback)."""
    import struct

    from tests.fuzz.test_fuzz_cli import _bags

    data = bytearray(_bags()["run.mcap"])
    # The footer record ends the file before the 8-byte magic: opcode 0x02, length (u64),
    # then summary_start (u64), where the summary's first record (opcode, length) begins.
    footer = len(data) - 8 - (1 + 8 + 8 + 8 + 4)
    assert data[footer] == 0x02
    (summary_start,) = struct.unpack_from("<Q", data, footer + 9)
    assert 0 < summary_start < footer
    struct.pack_into("<Q", data, summary_start + 1, 15925584226954786420)
    return bytes(data)


@pytest.mark.parametrize("command", [["convert", "rosbag"], ["process"]])
def test_mcap_with_a_record_length_beyond_any_index(
        command: list[str], tmp_path: Path, run_cli: Callable[..., tuple[int, str]]) -> None:
    files = {"run.mcap": _mcap_with_a_huge_summary_record()}
    code, err = run_cli(tmp_path, files, [*command, "run.mcap", "--out", "out.csv"], "out.csv")
    assert code == 2
    assert "run.mcap" in err
