"""Method throughput of several commits, interleaved: the steadiest speed ratio on a shared machine.

Run from the repository root::

    .venv/bin/python benchmarks/ab_trees.py carve combined --histories 250 1000 \\
        --commits 7445718 376fac2 WORKTREE

Each commit's ``src`` is exported with ``git archive`` (``WORKTREE``: this checkout's ``src``)
and every measurement runs in its own subprocess with that tree first on ``PYTHONPATH`` and its
own numba cache. The rounds go commit after commit, so a slow minute of the machine falls on all
of them alike. A subprocess feeds the benchmark stream of :mod:`synthetic` (ring corridor, 16
sonars, σ = 1 cm, 5 % spurious echoes, seed 0) through ``add_many`` and ``finish`` twice after a
2,000-reading warm-up, and reports readings per CPU second (``time.process_time``, so time the
process spends waiting for the CPU does not count). The table gives each commit's median and its
ratio to the first commit (7445718 is the all-pairs reference of issue 11's targets).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from commits import child_env, export_src

WORKTREE = "WORKTREE"
ROOT = Path(__file__).resolve().parent.parent

# Run in each subprocess: arguments method, history, readings, runs.
MEASURE = r"""
import json, sys, time
sys.path.insert(0, sys.argv[5])
from synthetic import corridor_stream
from sonarcarve import MethodConfig, make_method
name, history, n, runs = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
batch = corridor_stream(n, noise=0.01, spurious_share=0.05, seed=0).batch
def run(b):
    method = make_method(name, MethodConfig(history_size=history))
    start = time.process_time()
    method.add_many(b)
    method.finish()
    return time.process_time() - start
run(batch[:2000])
print(json.dumps([n / run(batch) for _ in range(runs)]))
"""


def tree_src(commit: str, into: Path) -> Path:
    """The ``src`` folder of ``commit`` (or of this checkout for ``WORKTREE``)."""
    if commit == WORKTREE:
        return ROOT / "src"
    return export_src(commit, into / commit)


def measure(src: Path, cache: Path, method: str, history: int, readings: int) -> list[float]:
    """Readings per CPU second of two runs in a fresh subprocess on ``src``."""
    env = child_env(src, cache)
    out = subprocess.run(
        [sys.executable, "-c", MEASURE, method, str(history), str(readings), "2",
         str(ROOT / "benchmarks")],
        env=env, capture_output=True, text=True, check=True).stdout
    return list(json.loads(out.strip().splitlines()[-1]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("methods", nargs="+")
    parser.add_argument("--histories", type=int, nargs="+", default=[250])
    parser.add_argument("--commits", nargs="+", default=["7445718", "376fac2", WORKTREE])
    parser.add_argument("--readings", type=int, default=20_000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="ab_trees_") as tmp:
        trees = {c: tree_src(c, Path(tmp)) for c in args.commits}
        print(f"load average at the start: {os.getloadavg()[0]:.1f}\n")
        print("| method | history | " + " | ".join(args.commits) + " | "
              + " | ".join(f"{c} / {args.commits[0]}" for c in args.commits[1:]) + " |")
        print("|---|---:|" + "---:|" * (2 * len(args.commits) - 1))
        for method in args.methods:
            for history in args.histories:
                rates: dict[str, list[float]] = {c: [] for c in args.commits}
                for _ in range(args.rounds):
                    for commit, src in trees.items():
                        rates[commit] += measure(src, Path(tmp) / f"cache-{commit}", method,
                                                 history, args.readings)
                med = {c: statistics.median(v) for c, v in rates.items()}
                base = med[args.commits[0]]
                print(f"| {method} | {history:,} | "
                      + " | ".join(f"{med[c]:,.0f}" for c in args.commits) + " | "
                      + " | ".join(f"{med[c] / base:.2f}" for c in args.commits[1:]) + " |")
        print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
