"""``sonarcarve process`` end to end on a large log: readings/s and peak memory per method, the
parse and write rates on their own, and the cold start of ``--version`` and ``--help``.

Run from the repository root::

    .venv/bin/python benchmarks/process_speed.py                 # 1,000,000 readings

Writes the fixed synthetic stream of ``synthetic.py`` (ring corridor, σ = 1 cm, 5 % spurious
echoes, seed 0) as a readings CSV in a temporary folder, then:

- runs ``sonarcarve process READINGS.csv --method M --out MAP.csv`` once per method as a child
  process (after a warm-up run on the first 2,000 readings, which compiles numba's kernels)
  and reports its wall time as readings/s end to end, its CPU time (user + system: the same
  on an idle machine, as the command runs on one core; steadier on a busy one), its peak
  resident memory (the child's own ``ru_maxrss`` from ``os.wait4``) and the method's own rate
  as the command's summary prints it (method only: no parsing, sampling or writing);
- times, in this process, reading and validating the CSV alone (``iter_readings_csv``, best of
  ``--repeats``) and writing the largest map alone (``write_map_csv``, best of ``--repeats``);
- times ``sonarcarve --version`` and ``sonarcarve --help`` in fresh processes (median of 9,
  after one warm-up run).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from sonarcarve.io import read_map_csv, write_map_csv, write_readings_csv
from sonarcarve.io.readings_csv import iter_readings_csv
from sonarcarve.maps import GlobalMap
from synthetic import corridor_stream

METHODS = ("centerline", "carve", "atm", "combined")


def _cli() -> str:
    return shutil.which("sonarcarve") or str(Path(sys.executable).with_name("sonarcarve"))


def _run_child(command: list[str]) -> tuple[float, float, int, str]:
    """Wall seconds, CPU seconds, peak RSS in bytes and stdout of one child process."""
    tic = time.perf_counter()
    with tempfile.TemporaryFile() as out:
        child = subprocess.Popen(command, stdout=out, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(child.pid, 0)
        seconds = time.perf_counter() - tic
        child.returncode = os.waitstatus_to_exitcode(status)
        err = child.stderr.read().decode() if child.stderr is not None else ""
        if child.returncode != 0:
            msg = f"{' '.join(command)} failed ({child.returncode}): {err}"
            raise RuntimeError(msg)
        out.seek(0)
        text = out.read().decode()
    cpu = usage.ru_utime + usage.ru_stime
    return seconds, cpu, usage.ru_maxrss * 1024, text  # ru_maxrss is in KiB on Linux


def _method_rate(summary: str) -> float:
    match = re.search(r"readings per second\D*([\d,]+)", summary)
    return float(match.group(1).replace(",", "")) if match else float("nan")


def _best(seconds: list[float]) -> float:
    return min(seconds)


def _median_seconds(command: list[str], repeats: int = 9) -> float:
    subprocess.run(command, check=True, capture_output=True)  # warm-up: bytecode, disk cache
    times = []
    for _ in range(repeats):
        tic = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - tic)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    """Measure and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--readings", type=int, default=1_000_000, help="log length")
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of the parse and the write timing (best)")
    args = parser.parse_args(argv)
    cli = _cli()

    with tempfile.TemporaryDirectory(prefix="sonarcarve-bench-") as folder:
        readings = Path(folder) / "readings.csv"
        write_readings_csv(corridor_stream(args.readings, noise=0.01, spurious_share=0.05,
                                           seed=0).batch, readings)
        size = readings.stat().st_size
        print(f"log: ring corridor (benchmarks/synthetic.py), {args.readings:,} readings, seed 0; "
              f"CSV {size / 2**20:.1f} MiB; {os.cpu_count()} CPUs\n")
        short = Path(folder) / "short.csv"
        with readings.open() as full, short.open("w") as part:
            part.writelines(line for _, line in zip(range(2001), full, strict=False))

        print("| method | end to end (readings/s) | wall (s) | CPU (s) | end to end per CPU "
              "second (readings/s) | peak RSS (MiB) | method alone (readings/s, from the "
              "summary) | map rows |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|")
        largest = None
        for method in args.methods:
            out = Path(folder) / f"map-{method}.csv"
            # Warm-up on 2,000 readings: numba's kernels compiled and cached, files in cache.
            _run_child([cli, "process", str(short), "--method", method, "--out", str(out)])
            seconds, cpu, peak, summary = _run_child(
                [cli, "process", str(readings), "--method", method, "--out", str(out)])
            rows = sum(1 for _ in out.open()) - 1
            if largest is None or rows > largest[1]:
                largest = (out, rows)
            print(f"| {method} | {args.readings / seconds:,.0f} | {seconds:.1f} | {cpu:.1f} | "
                  f"{args.readings / cpu:,.0f} | {peak / 2**20:.0f} | "
                  f"{_method_rate(summary):,.0f} | {rows:,} |")

        parse = _best([_timed_parse(readings) for _ in range(args.repeats)])
        print(f"\n| stage (in process, best of {args.repeats}) | rows/s | seconds | MiB/s |")
        print("|---|---:|---:|---:|")
        print(f"| parse + validate readings CSV (`iter_readings_csv`) | "
              f"{args.readings / parse:,.0f} | {parse:.2f} | {size / 2**20 / parse:.0f} |")
        if largest is not None:
            points = read_map_csv(largest[0])
            target = Path(folder) / "rewrite.csv"
            write = _best([_timed_write(points, target) for _ in range(args.repeats)])
            map_size = target.stat().st_size
            print(f"| write map CSV (`write_map_csv`, {len(points):,} rows) | "
                  f"{len(points) / write:,.0f} | {write:.2f} | {map_size / 2**20 / write:.0f} |")

    print("\n| command | median of 9 runs (s) |")
    print("|---|---:|")
    for label, command in {"python -c pass": [sys.executable, "-c", "pass"],
                           "sonarcarve --version": [cli, "--version"],
                           "sonarcarve --help": [cli, "--help"]}.items():
        print(f"| `{label}` | {_median_seconds(command):.3f} |")
    return 0


def _timed_parse(path: Path) -> float:
    tic = time.perf_counter()
    for _ in iter_readings_csv(path):
        pass
    return time.perf_counter() - tic


def _timed_write(points: GlobalMap, path: Path) -> float:
    tic = time.perf_counter()
    write_map_csv(points, path)
    return time.perf_counter() - tic


if __name__ == "__main__":
    sys.exit(main())
