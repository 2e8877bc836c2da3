"""Throughput and peak memory of every registered method on a fixed synthetic stream.

Run from the repository root::

    .venv/bin/python benchmarks/throughput.py            # 20,000 readings, histories 250, 1000

Prints a markdown table: readings per second (median of ``--repeats`` timed runs of
``add_many`` over the whole stream followed by ``finish``, on one core, after a warm-up run that
compiles the numba kernels) and the peak traced memory of one more, untimed run (tracemalloc; it
sees numpy's allocations, which hold all of the methods' state).
"""

from __future__ import annotations

import argparse
import statistics
import time
import tracemalloc

from sonarcarve import METHODS, MethodConfig, ReadingBatch, make_method
from synthetic import corridor_stream


def _run(name: str, batch: ReadingBatch, history: int) -> float:
    method = make_method(name, MethodConfig(history_size=history))
    tic = time.perf_counter()
    method.add_many(batch)
    method.finish()
    return time.perf_counter() - tic


def _peak_bytes(name: str, batch: ReadingBatch, history: int) -> int:
    tracemalloc.start()
    try:
        method = make_method(name, MethodConfig(history_size=history))
        method.add_many(batch)
        method.finish()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def main(argv: list[str] | None = None) -> int:
    """Measure and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--readings", type=int, default=20_000, help="stream length")
    parser.add_argument("--histories", type=int, nargs="+", default=[250, 1000])
    parser.add_argument("--repeats", type=int, default=3, help="timed runs per cell (median)")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), help="default: all")
    args = parser.parse_args(argv)

    batch = corridor_stream(args.readings, noise=0.01, spurious_share=0.05, seed=0).batch
    warm = batch[: min(len(batch), 2000)]
    print(f"stream: ring corridor, {len(batch)} readings, 16 sensors, seed 0\n")
    print("| method | history | readings/s | peak memory (MiB) |")
    print("|---|---:|---:|---:|")
    for name in args.methods:
        for history in args.histories:
            _run(name, warm, history)  # compile and warm caches
            seconds = statistics.median(_run(name, batch, history) for _ in range(args.repeats))
            peak = _peak_bytes(name, batch, history) / 2**20
            print(f"| {name} | {history} | {len(batch) / seconds:,.0f} | {peak:.1f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
