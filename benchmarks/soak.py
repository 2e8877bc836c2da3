"""Memory soak: a long stream through every method with the global map streamed to a sink.

Run from the repository root::

    .venv/bin/python benchmarks/soak.py                        # 2,000,000 readings per method
    .venv/bin/python benchmarks/soak.py --readings 10000000    # the long run (issue 14)
    .venv/bin/python benchmarks/soak.py --sink memory          # the in-memory map, to compare

Each method runs in a child process of its own (so one method's freed memory cannot hide
another's growth): ``process_chunks`` over the fixed synthetic stream of ``synthetic.py`` (ring
corridor, σ = 1 cm, 5 % spurious echoes, seed 0), with the global map sent to a
:class:`~sonarcarve.maps.CountingSink` (counts the points, keeps none) or, with ``--sink
memory``, kept in memory as before issue 14. The stream is generated once (``--base`` readings)
and replayed with its times shifted, a block at a time, so the log itself is never held. Resident
memory (``/proc/self/statm``) is sampled before the first reading, then every ``--every``
readings. Before that, the method's kernels are compiled on 2,000 readings of a throw-away
method.

The table: resident memory at the start, after ``--warmup`` readings, at the end, the growth
from warm-up to end per million readings, the spread (max - min) after warm-up, the points
committed and the rate (sampling for the unprocessed share included, as ``process`` does).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from sonarcarve.maps import CountingSink
from sonarcarve.methods import make_method
from sonarcarve.pipeline import process_chunks
from sonarcarve.readings import ReadingBatch
from synthetic import PERIOD, corridor_stream

METHODS = ("centerline", "carve", "atm", "combined", "evidence")
BLOCK = 10_000  # readings per batch handed to process_chunks (as iter_readings_csv does)
_PAGE = os.sysconf("SC_PAGE_SIZE")


def rss_mib() -> float:
    """Resident memory of this process now, MiB."""
    with Path("/proc/self/statm").open() as statm:
        return int(statm.read().split()[1]) * _PAGE / 2**20


def replayed(base: ReadingBatch, n: int) -> Iterator[ReadingBatch]:
    """``n`` readings: ``base`` over and over, times shifted so that they never go back."""
    span = float(base.t[-1] - base.t[0]) + PERIOD
    done = 0
    lap = 0
    while done < n:
        for start in range(0, len(base), BLOCK):
            part = base[start : min(start + BLOCK, len(base), start + n - done)]
            if not len(part):
                return
            yield ReadingBatch(t=part.t + lap * span, sensor=part.sensor, x=part.x, y=part.y,
                               theta=part.theta, range=part.range, beam_width=part.beam_width)
            done += len(part)
            if done >= n:
                return
        lap += 1


def child(method_name: str, readings: int, base_size: int, every: int, sink: str) -> None:
    """One method's soak; prints one JSON line."""
    base = corridor_stream(base_size, noise=0.01, spurious_share=0.05, seed=0).batch
    warm = make_method(method_name)  # compile numba's kernels outside the measurement
    warm.add_many(base[:2000])
    warm.finish()
    del warm
    method = make_method(method_name)
    counter = CountingSink() if sink == "count" else None
    samples = [(0, rss_mib())]
    next_sample = every

    def on_progress(rows: int) -> None:
        nonlocal next_sample
        if rows >= next_sample:
            samples.append((rows, rss_mib()))
            next_sample = (rows // every + 1) * every

    tic = time.perf_counter()
    result = process_chunks(replayed(base, readings), method, on_progress=on_progress,
                            sink=counter)
    seconds = time.perf_counter() - tic
    if samples[-1][0] != readings:
        samples.append((readings, rss_mib()))
    print(json.dumps({"method": method_name, "samples": samples, "points": result.points,
                      "seconds": seconds}))


def _row(record: dict[str, object], warmup: int) -> str:
    samples = np.array(record["samples"], dtype=np.float64)
    done, rss = samples[:, 0], samples[:, 1]
    after = done >= warmup
    first = int(np.argmax(after)) if after.any() else len(done) - 1
    growth = (rss[-1] - rss[first]) / max(done[-1] - done[first], 1) * 1e6
    spread = float(np.ptp(rss[first:]))
    rate = done[-1] / float(record["seconds"])  # type: ignore[arg-type]
    return (f"| {record['method']} | {rss[0]:.0f} | {rss[first]:.0f} | {rss[-1]:.0f} | "
            f"{growth:+.2f} | {spread:.1f} | {record['points']:,} | {rate:,.0f} |")


def main(argv: list[str] | None = None) -> int:
    """Run the soak and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--readings", type=int, default=2_000_000, help="readings per method")
    parser.add_argument("--methods", nargs="+", default=list(METHODS), choices=METHODS)
    parser.add_argument("--base", type=int, default=100_000,
                        help="readings of the stream generated once and replayed")
    parser.add_argument("--every", type=int, default=100_000, help="readings between samples")
    parser.add_argument("--warmup", type=int, default=500_000,
                        help="readings before the 'after warm-up' sample")
    parser.add_argument("--sink", choices=("count", "memory"), default="count",
                        help="count: stream the map to a counting sink; memory: keep it")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.child, args.readings, args.base, args.every, args.sink)
        return 0
    command = " ".join(["benchmarks/soak.py", *(argv if argv is not None else sys.argv[1:])])
    print(f"`.venv/bin/python {command}`: {args.readings:,} readings per method (ring corridor "
          f"of benchmarks/synthetic.py, {args.base:,} readings replayed, seed 0), global map "
          f"to {'a counting sink' if args.sink == 'count' else 'memory'}, resident memory "
          f"sampled every {args.every:,} readings; {os.cpu_count()} CPUs\n")
    print(f"| method | RSS start (MiB) | after {args.warmup:,} (MiB) | end (MiB) | growth after "
          "warm-up (MiB per million readings) | spread after warm-up (MiB) | map points | "
          "readings/s |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    here = Path(__file__).resolve()
    for name in args.methods:
        out = subprocess.run(
            [sys.executable, str(here), "--child", name, "--readings", str(args.readings),
             "--base", str(args.base), "--every", str(args.every), "--sink", args.sink],
            check=True, capture_output=True, text=True, cwd=here.parent)
        print(_row(json.loads(out.stdout.splitlines()[-1]), args.warmup), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
