"""The watch kernel of evidence carving alone (``geometry/evidence/watch.py``), microseconds a
reading, beside the repeat marking that runs on the same rows (``geometry/repeats.py``).

Run from the repository root::

    .venv/bin/python benchmarks/watch_kernel.py

A ring of twice the history's rows, random origins, ranges, axes and 16 sensors; each kernel
marks the whole ring's second half after a warm-up pass over all of it (compiled, cache warm),
best of 5. Both scan every row of the history for every reading, so their cost grows with it.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from sonarcarve.geometry.evidence import mark_watch
from sonarcarve.geometry.repeats import mark_repeats
from timing import best_seconds


def _measure(capacity: int, repeats: int) -> tuple[float, float]:
    """Seconds a reading of the watch and the repeat marking at history ``capacity``."""
    storage = 2 * capacity
    rng = np.random.default_rng(0)
    x, y = rng.uniform(0, 10, storage), rng.uniform(0, 10, storage)
    r, theta = rng.uniform(0.2, 5, storage), rng.uniform(-4, 4, storage)
    width = np.full(storage, math.radians(22.5))
    cos_axis, sin_axis, cos_half = np.cos(theta), np.sin(theta), np.cos(0.5 * width)
    sensor = rng.integers(0, 16, storage)
    watched = np.zeros(storage, dtype=bool)
    repeated = np.zeros(storage)

    def watch(first: int) -> None:
        mark_watch(first, storage - first, capacity, x, y, r, cos_axis, sin_axis, cos_half,
                   sensor, watched, 0.25, math.radians(30.0))

    def repeat(first: int) -> None:
        mark_repeats(first, storage - first, capacity, x, y, r, theta, width, sensor,
                     repeated, 0.05)

    watch(0)
    repeat(0)
    half = storage // 2
    rows = storage - half
    # Wall time, already warm (the calls above): the kernels run in one thread.
    return (best_seconds(lambda: watch(half), repeats, clock=time.perf_counter,
                         warm_up=False) / rows,
            best_seconds(lambda: repeat(half), repeats, clock=time.perf_counter,
                         warm_up=False) / rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--histories", type=int, nargs="+", default=[250, 1000])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    print("| history | watch µs a reading | ns a row | repeats µs a reading |")
    print("|---:|---:|---:|---:|")
    for capacity in args.histories:
        watch_s, repeat_s = _measure(capacity, args.repeats)
        print(f"| {capacity:,} | {1e6 * watch_s:.2f} | {1e9 * watch_s / capacity:.2f} | "
              f"{1e6 * repeat_s:.2f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
