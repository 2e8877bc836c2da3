"""``sonarcarve process LOG --out X.mcap|X.bag``: user CPU seconds against a baseline commit,
runs alternating, and whether every message of the two bags is the same bytes.

Run from the repository root (needs the ``ros`` extra)::

    .venv/bin/python benchmarks/bag_speed.py --baseline 84a0edf
    .venv/bin/python benchmarks/bag_speed.py --baseline 84a0edf --at HEAD --pairs 3

Simulates the office tour and the t-junction (``sonarcarve simulate --world W --out W.mcap``,
with the code under test) into a temporary folder, then for every case runs the baseline and
the code under test in turn, ``--pairs`` times (after one warm-up run of each, which fills
its numba cache), each as a child process, and reads its user CPU seconds (``ru_utime``; the
command runs on one core). The cases: the office to a bare MCAP file without and with the
carved grid, to a ROS 1 ``.bag`` with the grid, the t-junction with ``--method evidence`` to a
``.bag``, and the office to a map CSV (the scale: no bag at all). For each bag case the last
pair's two bags are read with rosbags' ``AnyReader`` and every message compared: topic, type,
log time and serialised bytes.

``--at COMMIT`` and ``--baseline COMMIT`` run that commit's ``src`` (``git archive``, with its
own ``NUMBA_CACHE_DIR``); without ``--at`` the working tree is measured.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from commits import child_env, export_src

#: (label, world, process options, output suffix)
CASES = (
    ("office, .mcap, no grid", "office", ["--grid-resolution", "0"], ".mcap"),
    ("office, .mcap, grid", "office", [], ".mcap"),
    ("office, ROS 1 .bag, grid", "office", [], ".bag"),
    ("t-junction, evidence, .bag", "t-junction", ["--method", "evidence"], ".bag"),
    ("office, map CSV", "office", [], ".csv"),
)


def _env(label: str, commit: str | None, folder: Path) -> dict[str, str]:
    if commit is None:
        return {**os.environ, "SONARCARVE_COMPILE_NOTICE": "0"}
    root = folder / label
    env = child_env(export_src(commit, root), root / "numba-cache")
    return {**env, "SONARCARVE_COMPILE_NOTICE": "0"}


def _user_seconds(args: list[str], env: dict[str, str]) -> float:
    """User CPU seconds of ``sonarcarve ARGS`` in a child process."""
    child = subprocess.Popen([sys.executable, "-m", "sonarcarve", *args], env=env,
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(child.pid, 0)
    err = child.stderr.read().decode() if child.stderr is not None else ""
    if os.waitstatus_to_exitcode(status) != 0:
        msg = f"sonarcarve {' '.join(args)} failed: {err}"
        raise RuntimeError(msg)
    return usage.ru_utime


def _messages(path: Path) -> list[tuple[str, str, int, bytes]]:
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return [(c.topic, c.msgtype, t, bytes(raw)) for c, t, raw in reader.messages()]


def _same_messages(a: Path, b: Path) -> str:
    first, second = _messages(a), _messages(b)
    if len(first) != len(second):
        return f"DIFFERENT: {len(first)} against {len(second)} messages"
    differing = sum(x != y for x, y in zip(first, second, strict=True))
    return (f"all {len(first):,} messages the same bytes" if differing == 0
            else f"DIFFERENT: {differing} of {len(first):,} messages")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, help="commit to compare against")
    parser.add_argument("--at", default=None, help="commit to measure (default: working tree)")
    parser.add_argument("--pairs", type=int, default=3, help="old/new pairs per case")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="sonarcarve-bag-speed-") as tmp:
        folder = Path(tmp)
        sides = {"old": _env("old", args.baseline, folder), "new": _env("new", args.at, folder)}
        for world in {case[1] for case in CASES}:
            _user_seconds(["simulate", "--world", world, "--out", str(folder / f"{world}.mcap")],
                          sides["new"])
        print(f"baseline {args.baseline}, measured {args.at or 'working tree'}, "
              f"{args.pairs} pairs, user CPU seconds")
        print("| case | old | new | new/old | same messages |\n|---|---|---|---|---|")
        for label, world, options, suffix in CASES:
            log = str(folder / f"{world}.mcap")
            times: dict[str, list[float]] = {"old": [], "new": []}
            for k in range(args.pairs + 1):  # run 0: warm-up, not counted
                order = ("old", "new") if k % 2 else ("new", "old")
                for side in order:
                    out = folder / f"{side}{suffix}"
                    out.unlink(missing_ok=True)
                    seconds = _user_seconds(["process", log, *options, "--out", str(out)],
                                            sides[side])
                    if k:
                        times[side].append(seconds)
            same = ("-" if suffix == ".csv" else
                    _same_messages(folder / f"old{suffix}", folder / f"new{suffix}"))
            old, new = statistics.median(times["old"]), statistics.median(times["new"])
            print(f"| {label} | {' '.join(f'{t:.2f}' for t in times['old'])} "
                  f"| {' '.join(f'{t:.2f}' for t in times['new'])} | {new / old:.2f} "
                  f"| {same} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
