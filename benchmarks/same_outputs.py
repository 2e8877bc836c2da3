"""Do two commits give the same bits? Methods' maps and the grids, old code against new.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/same_outputs.py --commits 7bc4ab6 WORKTREE
    nice .venv/bin/python benchmarks/same_outputs.py --commits 7bc4ab6 /tmp/tree  # a folder
    nice .venv/bin/python benchmarks/same_outputs.py --methods --worlds office doorway \
        --resolutions 0.05 0.10  # the grids alone

For a speed change that must not change any output. Each commit's ``src`` is exported with
``git archive`` (``WORKTREE``: this checkout's ``src``) and run in a child process with its own
numba cache. A child simulates the logs of ``--worlds`` (``--seeds``, both echo models), each
also with its no-echo readings (the same firings, those that heard nothing kept as readings of
range inf: the only path to evidence carving's ``evidence_free``; ``--no-no-echo`` leaves them
out, for commits whose simulator cannot make them), and feeds each log to every ``--methods``
method three ways: the whole log in one ``add_many``, blocks of 5 readings, and one ``add`` per
reading (``--singles`` readings of it). It hashes (SHA-256 of the raw bytes) every field of the
global map that ``finish`` returns and of the local map at the end of the stream and after every
1000 readings of the blocks (``evidence`` is among the default methods: no grid runs it by
default). At each of ``--resolutions`` it feeds the log to the carved grid (its default method)
and the Elfes grid, each made ``around`` the world, whole and in blocks of 5 readings, and
hashes the log-odds at the end, and the carved grid's after each 25-reading block read. The
parent prints each hash key's verdict: the same in every commit, or which differ.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from commits import child_env, export_src

WORKTREE = "WORKTREE"
ROOT = Path(__file__).resolve().parent.parent

# Run in each subprocess: arguments seeds, methods, worlds, resolutions (each comma-separated),
# singles, silent (1: also the logs with no-echo readings).
CHILD = r"""
import hashlib, json, math, sys
import numpy as np
from sonarcarve.grids import CarvedGrid, OccupancyGrid
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.sim.simulate import simulate

seeds = [int(s) for s in sys.argv[1].split(",")]
methods = [m for m in sys.argv[2].split(",") if m]
worlds = sys.argv[3].split(",")
resolutions = [float(h) for h in sys.argv[4].split(",")]
singles = int(sys.argv[5])
silent = sys.argv[6] == "1"
out = {}

def digest(value):
    return hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()[:16]

def put(key, points):
    for field, value in sorted(vars(points).items()):
        if isinstance(value, np.ndarray):
            out[f"{key} {field}"] = digest(value)

def method(name):
    config = MethodConfig(max_incidence=math.radians(20.0)) if name != "atm" else None
    return make_method(name, config)

def grids(log, bounds, batch):
    for h in resolutions:
        for label, kind in (("carved grid", CarvedGrid), ("elfes grid", OccupancyGrid)):
            whole = kind.around(bounds, h)
            whole.add_many(batch)
            out[f"{log} {label} {h:g} m whole"] = digest(whole.log_odds)
            blocks = kind.around(bounds, h)
            for start in range(0, len(batch), 5):
                blocks.add_many(batch[start:start + 5])
            out[f"{log} {label} {h:g} m blocks of 5"] = digest(blocks.log_odds)
        grid = CarvedGrid.around(bounds, h)
        reads = []
        for start in range(0, len(batch), 25):
            grid.add_many(batch[start:start + 25])
            reads.append(digest(grid.log_odds))
        out[f"{log} carved grid {h:g} m reads every 25"] = digest(np.array(reads))

def logs(world, seed, physics):
    # The scenario's log, and with silent the same firings with the no-echo readings too
    # (the echoes are the same; the firings that heard nothing add free space only).
    override = () if physics == "specular" else (("echo_model", physics),)
    sim = run_simulation(Scenario(world, seed, physics=override))
    yield f"{world} {seed} {physics}", sim.readings, sim.world.bounds
    if silent:
        heard_all = simulate(sim.world, sim.robot, sim.trajectory, sim.seed, physics=sim.physics,
                             odometry=sim.odometry, no_echo=True)
        yield f"{world} {seed} {physics} no-echo", heard_all.readings, sim.world.bounds

def feed_methods(log, batch):
    for name in methods:
        whole = method(name)
        whole.add_many(batch)
        put(f"{log} {name} whole local", whole.local_map())
        put(f"{log} {name} whole global", whole.finish())
        blocks = method(name)
        for start in range(0, len(batch), 5):
            blocks.add_many(batch[start:start + 5])
            if (start + 5) % 1000 == 0:
                put(f"{log} {name} blocks local at {start + 5}", blocks.local_map())
        put(f"{log} {name} blocks global", blocks.finish())
        one = method(name)
        for k in range(min(singles, len(batch))):
            one.add(batch[k])
        put(f"{log} {name} singles local", one.local_map())
        put(f"{log} {name} singles global", one.finish())

for world in worlds:
    for physics in ("specular", "amplitude"):
        for seed in seeds:
            for log, batch, bounds in logs(world, seed, physics):
                feed_methods(log, batch)
                grids(log, bounds, batch)
print(json.dumps(out))
"""


def tree_src(commit: str, into: Path) -> Path:
    """The ``src`` folder of ``commit`` (of this checkout for ``WORKTREE``, of a folder given
    by its path: a copy of the tree with some files changed)."""
    if commit == WORKTREE:
        return ROOT / "src"
    if Path(commit).is_dir():
        return Path(commit) / "src"
    return export_src(commit, into / commit)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--commits", nargs="+", default=["HEAD", WORKTREE])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--methods", nargs="*", default=["combined", "atm", "carve", "evidence"],
                        help="methods to compare (none: the grids alone)")
    parser.add_argument("--worlds", nargs="+", default=["office"])
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.1],
                        help="cell sizes of the grids, metres")
    parser.add_argument("--singles", type=int, default=3000,
                        help="readings fed one add() at a time (the start of each log)")
    parser.add_argument("--no-echo", action=argparse.BooleanOptionalAction, default=True,
                        help="also each log with its no-echo readings (firings that heard "
                             "nothing: range inf, free space up to max_range)")
    args = parser.parse_args(argv)
    hashes: dict[str, dict[str, str]] = {}
    with tempfile.TemporaryDirectory(prefix="sonarcarve-same-") as name:
        for commit in args.commits:
            src = tree_src(commit, Path(name))
            env = child_env(src, Path(name) / f"{len(hashes)}-numba")
            child = subprocess.run(
                [sys.executable, "-c", CHILD, ",".join(map(str, args.seeds)),
                 ",".join(args.methods), ",".join(args.worlds),
                 ",".join(map(str, args.resolutions)), str(args.singles),
                 "1" if args.no_echo else "0"],
                env=env, check=True, capture_output=True, text=True)
            hashes[commit] = json.loads(child.stdout)
    first, *others = args.commits
    differ = 0
    for key, value in hashes[first].items():
        changed = [c for c in others if hashes[c].get(key) != value]
        differ += bool(changed)
        print(f"{'DIFFERS in ' + ', '.join(changed) if changed else 'same'}: {key}")
    print(f"\n{len(hashes[first])} outputs, {differ} differ between {', '.join(args.commits)}")
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
