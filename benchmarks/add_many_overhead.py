"""The per-call overhead of ``SonarMethod.add_many`` for the small batches of a robot's costmap.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/add_many_overhead.py                    # the working tree
    nice .venv/bin/python benchmarks/add_many_overhead.py --trees 9938dc0 HEAD

A robot reading its costmap at 5 Hz calls ``add_many`` with a few readings (``--batch``, 5 by
default) and then asks for every arc that left the history to be final
(``history.flush_retired()``, what :class:`~sonarcarve.grids.CarvedGrid` does after each batch).
Fed the fixed corridor stream of ``synthetic.py`` (``--readings`` readings, history 250) that
way, with the grid's kind of global sink (:class:`~sonarcarve.maps.CountingSink`) and a commit
listener that does nothing, this measures per call (µs, CPU time, median of ``--repeats`` runs):

- ``validate``: :meth:`~sonarcarve.readings.ReadingBatch.validate` of the batch alone, as
  ``add_many`` calls it;
- ``add_many``: the whole call (validation, storing, the models' kernels);
- ``flush_retired``: committing the arcs that left the history (estimates, listener, sink);
- ``total``: both calls.

``--trees`` measures several commits' ``src`` (``git archive``, each with its own numba cache)
in child processes, their runs interleaved, so that their numbers are comparable; without it
the working tree is measured in this process. Each child warms up on the stream first (numba's
kernels compiled or loaded).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from commits import child_env, export_src

_HERE = Path(__file__).resolve().parent
_REPO = _HERE.parent
STAGES = ("validate", "add_many", "flush_retired", "total")


def measure(method_name: str, readings: int, batch_size: int) -> dict[str, float]:
    """µs per call of each stage over the stream (one run, CPU time)."""
    sys.path.insert(0, str(_HERE))
    from sonarcarve.maps import CountingSink
    from sonarcarve.methods import make_method
    from synthetic import corridor_stream

    stream = corridor_stream(readings, noise=0.01, spurious_share=0.05, seed=0).batch
    batches = [stream[k : k + batch_size] for k in range(0, len(stream), batch_size)]
    for _ in range(2):  # the first run loads (or compiles) the kernels
        method = make_method(method_name)
        method.set_global_sink(CountingSink())
        method.add_commit_listener(lambda history, slots, est: None)
        spent = dict.fromkeys(STAGES, 0.0)
        clock = time.process_time
        for batch in batches:
            tic = clock()
            batch.validate(first_id=method.readings, previous_t=-float("inf"))
            mid = clock()
            method.add_many(batch)
            after = clock()
            method.history.flush_retired()
            end = clock()
            spent["validate"] += mid - tic
            spent["add_many"] += after - mid
            spent["flush_retired"] += end - after
        spent["total"] = spent["add_many"] + spent["flush_retired"]
    return {stage: 1e6 * seconds / len(batches) for stage, seconds in spent.items()}


def _export(commit: str, folder: Path) -> dict[str, str]:
    root = folder / commit
    return child_env(export_src(commit, root), root / "numba-cache")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--methods", nargs="+", default=["carve", "combined"])
    parser.add_argument("--readings", type=int, default=20_000)
    parser.add_argument("--batch", type=int, default=5, help="readings per add_many")
    parser.add_argument("--repeats", type=int, default=5, help="runs per tree (median)")
    parser.add_argument("--trees", nargs="+", metavar="COMMIT",
                        help="measure these commits' src, interleaved, in child processes")
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)  # method readings batch
    args = parser.parse_args(argv)
    if args.child is not None:
        name, readings, batch = args.child
        print(json.dumps(measure(name, int(readings), int(batch))))
        return 0
    print(f"corridor stream, {args.readings:,} readings in batches of {args.batch}, history "
          f"250, CPU µs per call (median of {args.repeats}); load average "
          f"{os.getloadavg()[0]:.1f} at the start\n")
    print(f"| code | method | {' | '.join(STAGES)} |")
    print(f"|---|---|{'---:|' * len(STAGES)}")
    with tempfile.TemporaryDirectory(prefix="sonarcarve-add-many-") as name:
        trees = {commit: _export(commit, Path(name)) for commit in args.trees or []}
        for method in args.methods:
            if not trees:
                runs = [measure(method, args.readings, args.batch) for _ in range(args.repeats)]
                _row("working tree", method, runs)
                continue
            results: dict[str, list[dict[str, float]]] = {commit: [] for commit in trees}
            for _ in range(args.repeats):
                for commit, env in trees.items():
                    child = subprocess.run(
                        [sys.executable, __file__, "--child", method, str(args.readings),
                         str(args.batch)], env=env, check=True, capture_output=True, text=True)
                    results[commit].append(json.loads(child.stdout))
            for commit, runs in results.items():
                _row(commit, method, runs)
    print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")
    return 0


def _row(label: str, method: str, runs: list[dict[str, float]]) -> None:
    cells = " | ".join(f"{statistics.median(run[s] for run in runs):.1f}" for s in STAGES)
    print(f"| {label} | {method} | {cells} |", flush=True)


if __name__ == "__main__":
    sys.exit(main())
