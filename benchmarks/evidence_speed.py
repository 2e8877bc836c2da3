"""Evidence carving against carving, readings per CPU second, in the same run (issue 9's
throughput target: evidence at least 0.5x carving).

Run from the repository root::

    .venv/bin/python benchmarks/evidence_speed.py                     # this checkout
    .venv/bin/python benchmarks/evidence_speed.py --commits 7745291 WORKTREE
    .venv/bin/python benchmarks/evidence_speed.py --carve-at 69efe2f   # issue 9's own baseline

For each commit (its ``src`` exported as :mod:`ab_trees` does, ``WORKTREE``: this checkout's),
history and round, ``carve`` and ``evidence`` are measured one right after the other, each
in its own subprocess on the benchmark stream (ring corridor, 16 sonars, σ = 1 cm, 5 %
spurious echoes, seed 0; ``add_many`` and ``finish`` twice after a 2,000-reading warm-up,
readings per CPU second): :mod:`ab_trees` interleaves the commits but measures one method
after the other, so a busy minute of the shared machine falls on one method only and moves
their ratio. The table gives per commit and history the median and the best of each method
and the ratio evidence / carve of the medians and of the bests (the best run is the one
least slowed by other processes).

``--carve-at COMMIT`` also measures carving in that commit's tree, in every round right after
the others, and adds its medians and the ratio of each commit's evidence to it. Issue 9 asks
for evidence "within 2x of today's carving throughput", written when carving was the all-pairs
kernel of 69efe2f (the commit before evidence carving landed); issue 11 then made carving itself
4-9x faster. RESULTS reports both ratios: against that baseline (the target as written) and
against carving now (the stricter reading).
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
from pathlib import Path

from ab_trees import WORKTREE, measure, tree_src

METHODS = ("carve", "evidence")


def main() -> None:
    """Measure and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--commits", nargs="+", default=[WORKTREE])
    parser.add_argument("--histories", type=int, nargs="+", default=[250, 1000])
    parser.add_argument("--readings", type=int, default=20_000)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--carve-at", metavar="COMMIT",
                        help="also measure carving in this commit's tree (the issue's baseline)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="evidence_speed_") as tmp:
        trees = {c: tree_src(c, Path(tmp)) for c in args.commits}
        baseline = tree_src(args.carve_at, Path(tmp)) if args.carve_at else None
        then: dict[int, list[float]] = {h: [] for h in args.histories}
        rates: dict[tuple[str, int, str], list[float]] = {
            (c, h, m): [] for c in args.commits for h in args.histories for m in METHODS}
        print(f"load average at the start: {os.getloadavg()[0]:.1f}\n")
        for _ in range(args.rounds):
            for history in args.histories:
                for commit, src in trees.items():
                    for method in METHODS:
                        rates[commit, history, method] += measure(
                            src, Path(tmp) / f"cache-{commit}", method, history, args.readings)
                if baseline is not None:
                    then[history] += measure(baseline, Path(tmp) / f"cache-{args.carve_at}",
                                             "carve", history, args.readings)
        print("| commit | history | carve median | carve best | evidence median | "
              "evidence best | evidence / carve (medians) | evidence / carve (bests) |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
        for commit in args.commits:
            for history in args.histories:
                carve = rates[commit, history, "carve"]
                evidence = rates[commit, history, "evidence"]
                med_c, med_e = statistics.median(carve), statistics.median(evidence)
                print(f"| {commit} | {history:,} | {med_c:,.0f} | {max(carve):,.0f} | "
                      f"{med_e:,.0f} | {max(evidence):,.0f} | {med_e / med_c:.2f} | "
                      f"{max(evidence) / max(carve):.2f} |")
        if baseline is not None:
            _print_baseline(args.carve_at, then, {
                (c, h): rates[c, h, "evidence"] for c in args.commits for h in args.histories})
        print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")


def _print_baseline(commit: str, then: dict[int, list[float]],
                    evidence: dict[tuple[str, int], list[float]]) -> None:
    """Evidence of every commit against carving at ``commit`` (medians and bests)."""
    print(f"\n| evidence at | history | carve at {commit}, median | evidence median | "
          "evidence / that carve (medians) | (bests) |")
    print("|---|---:|---:|---:|---:|---:|")
    for (tree, history), rates in evidence.items():
        base = then[history]
        print(f"| {tree} | {history:,} | {statistics.median(base):,.0f} | "
              f"{statistics.median(rates):,.0f} | "
              f"{statistics.median(rates) / statistics.median(base):.2f} | "
              f"{max(rates) / max(base):.2f} |")


if __name__ == "__main__":
    main()
