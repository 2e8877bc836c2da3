"""Evidence carving against carving, readings per CPU second, in the same run (issue 9's
throughput target: evidence at least 0.5x carving).

Run from the repository root::

    .venv/bin/python benchmarks/evidence_speed.py                     # this checkout
    .venv/bin/python benchmarks/evidence_speed.py --commits 7745291 WORKTREE
    .venv/bin/python benchmarks/evidence_speed.py --carve-at 69efe2f   # issue 9's own baseline
    .venv/bin/python benchmarks/evidence_speed.py --cull-counts        # what reaches the arcs
    .venv/bin/python benchmarks/evidence_speed.py --floor              # without the weighing
    .venv/bin/python benchmarks/evidence_speed.py --split              # where the time goes

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

``--cull-counts`` measures no speed: it feeds this checkout's evidence carving the same stream
one reading at a time and counts, per reading after the warm-up, the older arcs that reach each
part of the weighing's per-arc work (``geometry/evidence/beam.py``): those whose bounding
circle passes the cull, those of them whose bounding circle meets the new echo circle (ATM's
crossings sought), whose live bins' circle is within reach too (pass 1 run), and those with
bins to weigh; and the bins weighed, those on the echo circle (support) among them.

``--floor`` bounds what any speed-up of the weighing can reach: in this process, on this
checkout, round after round, it measures carving, evidence carving, and evidence carving with
every new arc weighed against no older arc (the kernel called with a history of one arc; the
repeats, the watch, the estimates, the confidence and the commits run as always), readings per
CPU second after the same warm-up. Nothing is carved then, so the rest runs on other arcs than
in the real run: it is the cost of everything but the weighing of the older arcs, not an
exact part of the real run's time. The table gives the medians, the ratios to carving and the
share of evidence carving's time that the weighing of the older arcs takes
(``1 - floor time / evidence time``).

``--split`` times evidence carving's parts on this checkout (after the same warm-up, CPU time,
each part's calls timed where the model makes them): the weighing kernel, the watch and repeat
marking, and the commit path (the estimates, the confidence and the points of the arcs that
leave the history); µs a reading, the median of ``--rounds`` runs, and "rest" for what is left
(the history, the checks, Python between the parts).
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numba import njit

from ab_trees import WORKTREE, measure, tree_src
from sonarcarve import MethodConfig, make_method
from sonarcarve.geometry.evidence import evidence_add_many
from sonarcarve.geometry.evidence.arrays import ArcShapes, ReadingRows
from sonarcarve.geometry.evidence.beam import clear_of_beam, meets_echo_circle, new_beam
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE, EvidenceParams
from sonarcarve.methods import evidence as evidence_module
from sonarcarve.methods.evidence import EvidenceMethod, EvidenceModel
from sonarcarve.readings import ReadingBatch
from synthetic import corridor_stream

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
    parser.add_argument("--cull-counts", action="store_true",
                        help="count the arcs reaching each part of the weighing instead")
    parser.add_argument("--floor", action="store_true",
                        help="measure evidence carving without the weighing of older arcs too")
    parser.add_argument("--split", action="store_true",
                        help="time evidence carving's parts instead")
    args = parser.parse_args()
    if args.cull_counts:
        _print_cull_counts(args.histories, args.readings)
        return
    if args.floor:
        _print_floor(args.histories, args.readings, args.rounds)
        return
    if args.split:
        _print_split(args.histories, args.readings, args.rounds)
        return
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


COUNTS = ("culled in", "crossings sought", "pass 1 run", "bins to weigh", "bins weighed",
          "on the echo circle")


@njit
def _count_cull(slot: int, first: int, n_older: int, readings: ReadingRows, shapes: ArcShapes,
                live: np.ndarray, free: np.ndarray, status: np.ndarray, params: EvidenceParams,
                out: np.ndarray) -> None:
    """Add to ``out`` (:data:`COUNTS`) the older arcs of reading ``slot`` that reach each part
    of the weighing, from the state before it was added (``live``, ``free``, ``status``)."""
    beam = new_beam(slot, readings, shapes, params)
    storage = status.shape[0]
    circle = shapes.circle
    for q in range(n_older):
        i = (first + q) % storage
        if status[i] != EVIDENCE_ALIVE or clear_of_beam(circle[0, i], circle[1, i],
                                                        circle[2, i], beam):
            continue
        out[0] += 1
        out[1] += meets_echo_circle(circle[0, i], circle[1, i], circle[2, i], beam)
        if clear_of_beam(live[0, i], live[1, i], live[2, i], beam):
            continue
        out[2] += 1
        weighed = 0
        for k in range(free.shape[1]):
            vx = shapes.bx[i, k] - beam.x
            vy = shapes.by[i, k] - beam.y
            d2 = vx * vx + vy * vy
            along = vx * beam.cos_axis + vy * beam.sin_axis
            if free[i, k] >= params.threshold or d2 >= beam.reach2 or along <= 0.0 or (
                    along * along < d2 * beam.cos_half2):
                continue
            weighed += 1
            out[5] += abs(np.sqrt(d2) - beam.r) <= params.support_tolerance and not (
                np.sqrt(d2) < beam.free_r)
        out[3] += weighed > 0
        out[4] += weighed


def _print_cull_counts(histories: list[int], readings: int) -> None:
    """The table of ``--cull-counts`` (module docstring)."""
    batch = corridor_stream(readings, noise=0.01, spurious_share=0.05, seed=0).batch
    warm_up = min(2_000, readings // 2)
    print("| history | " + " | ".join(COUNTS) + " |")
    print("|---:|" + "---:|" * len(COUNTS))
    for history in histories:
        method = make_method("evidence", MethodConfig(history_size=history))
        model = method.models[0]
        assert isinstance(model, EvidenceModel)
        h = method.history
        method.add_many(batch[:warm_up])
        out = np.zeros(len(COUNTS))
        for s in range(warm_up, readings):
            live, free, status = model.live_circle.copy(), model.free.copy(), model.status.copy()
            method.add_many(batch[s : s + 1])
            sequence = h.appended - 1
            older = min(sequence, history - 1)
            _count_cull(sequence % h.storage_size, (sequence - older) % h.storage_size, older,
                        ReadingRows(h.x, h.y, h.r, h.theta, h.beam_width, h.sensor),
                        ArcShapes(model.cos_axis, model.sin_axis, model.cos_half, model.circle,
                                  model.bx, model.by, model.ex, model.ey),
                        live, free, status, model.params, out)
        per = out / (readings - warm_up)
        print(f"| {history:,} | " + " | ".join(f"{v:.1f}" for v in per) + " |")


FLOOR_KINDS = ("carve", "evidence", "floor")


def _weighing_no_older_arc(model: EvidenceModel) -> Callable[[int, int], None]:
    """``model.on_add_many`` with each new arc weighed against no older arc: the kernel is
    called with a history of one arc (its own row); the rest as ``on_add_many`` does it."""

    def on_add_many(first: int, count: int) -> None:
        end = first + count
        model.mark_repeats(first, count)
        bundles = model._bundles()  # the kernel's arguments, as on_add_many passes them
        while first < end:  # no older arc: no crossing, so no spill
            _, _, _, first, _ = evidence_add_many(first, end - first, 1, *bundles)
        model.mark_watch(end - count, count)

    return on_add_many


def _floor_rate(kind: str, history: int, batch: ReadingBatch) -> float:
    """Readings per CPU second of :data:`FLOOR_KINDS` ``kind`` on ``batch`` at ``history``,
    after a warm-up on its first 2,000 readings (as :mod:`ab_trees` measures)."""
    _cpu_seconds(kind, history, batch[:2000])
    return len(batch) / _cpu_seconds(kind, history, batch)


def _cpu_seconds(kind: str, history: int, readings: ReadingBatch) -> float:
    """CPU seconds of a new method of :data:`FLOOR_KINDS` ``kind`` at ``history`` adding
    ``readings`` in one ``add_many`` and finishing."""
    method = make_method("carve" if kind == "carve" else "evidence",
                         MethodConfig(history_size=history))
    if kind == "floor":
        model = method.models[0]
        assert isinstance(model, EvidenceModel)
        model.on_add_many = _weighing_no_older_arc(model)  # type: ignore[method-assign]
    start = time.process_time()
    method.add_many(readings)
    method.finish()
    return time.process_time() - start


def _print_floor(histories: list[int], readings: int, rounds: int) -> None:
    """The table of ``--floor`` (module docstring)."""
    batch = corridor_stream(readings, noise=0.01, spurious_share=0.05, seed=0).batch
    rates: dict[tuple[int, str], list[float]] = {
        (h, kind): [] for h in histories for kind in FLOOR_KINDS}
    print(f"load average at the start: {os.getloadavg()[0]:.1f}\n")
    for _ in range(rounds):
        for history in histories:
            for kind in FLOOR_KINDS:
                rates[history, kind].append(_floor_rate(kind, history, batch))
    print("| history | carve median | evidence median | evidence / carve | without the weighing "
          "| that / carve | weighing's share of evidence's time |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for history in histories:
        carve, evidence, floor = (statistics.median(rates[history, kind])
                                  for kind in FLOOR_KINDS)
        print(f"| {history:,} | {carve:,.0f} | {evidence:,.0f} | {evidence / carve:.2f} | "
              f"{floor:,.0f} | {floor / carve:.2f} | {1.0 - evidence / floor:.0%} |")
    print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")


#: The parts ``--split`` times: the names the model calls them by in
#: :mod:`sonarcarve.methods.evidence`, and how the table heads them.
SPLIT_PARTS = {"evidence_add_many": "weighing kernel", "mark_watch": "watch",
               "mark_repeats": "repeats"}


def _print_split(histories: list[int], readings: int, rounds: int) -> None:
    """The table of ``--split`` (module docstring)."""
    batch = corridor_stream(readings, noise=0.01, spurious_share=0.05, seed=0).batch
    spent: dict[str, float] = {}

    def timed(name: str, part: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: Any) -> Any:
            start = time.process_time()
            out = part(*args)
            spent[name] = spent.get(name, 0.0) + time.process_time() - start
            return out
        return call

    heads = [*SPLIT_PARTS.values(), "commit path", "rest", "total"]
    saved = {name: getattr(evidence_module, name) for name in SPLIT_PARTS}
    saved_commit = EvidenceMethod._commit
    print("| history | " + " | ".join(f"{h} (µs a reading)" for h in heads) + " |")
    print("|---:|" + "---:|" * len(heads))
    try:
        for name, head in SPLIT_PARTS.items():
            setattr(evidence_module, name, timed(head, saved[name]))
        EvidenceMethod._commit = timed("commit path", saved_commit)  # type: ignore[method-assign]
        for history in histories:
            runs: dict[str, list[float]] = {h: [] for h in heads}
            for _ in range(rounds):
                _cpu_seconds("evidence", history, batch[:2000])  # the warm-up
                spent.clear()
                total = _cpu_seconds("evidence", history, batch)
                spent["rest"] = total - sum(spent.values())
                spent["total"] = total
                for head in heads:
                    runs[head].append(spent.get(head, 0.0) / len(batch) * 1e6)
            print(f"| {history:,} | "
                  + " | ".join(f"{statistics.median(runs[h]):.2f}" for h in heads) + " |")
    finally:
        for name, part in saved.items():
            setattr(evidence_module, name, part)
        EvidenceMethod._commit = saved_commit  # type: ignore[method-assign]


if __name__ == "__main__":
    main()
