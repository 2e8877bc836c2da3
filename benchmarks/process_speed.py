"""``sonarcarve process`` end to end on a large log: readings/s and peak memory per method, the
parse and write rates on their own, and the cold start of ``--version`` and ``--help``; against
a baseline commit in the same run.

Run from the repository root::

    .venv/bin/python benchmarks/process_speed.py                  # 1,000,000 readings
    .venv/bin/python benchmarks/process_speed.py --at HEAD --baseline 1f0092d

Writes the fixed synthetic stream of ``synthetic.py`` (ring corridor, σ = 1 cm, 5 % spurious
echoes, seed 0) as a readings CSV in a temporary folder, then, for the code under test and for
the baseline (if given):

- runs ``sonarcarve process READINGS.csv --method M --out MAP.csv`` once per method as a child
  process (after a warm-up run on the first 2,000 readings, which compiles numba's kernels)
  and reports its wall time as readings/s end to end, its CPU time (user + system: the command
  runs on one core, so on an idle machine the two agree, and on a busy one CPU time is the
  steadier), its peak resident memory (the child's own VmHWM, read at its exit), the
  method's own rate and the unprocessed share as the command's summary prints them (method
  only: no parsing, sampling or writing), and whether the map is byte-identical to the
  baseline's;
- times (CPU seconds), in a child process, reading and validating the CSV alone
  (``iter_readings_csv``, best of ``--repeats``) and writing the largest map alone
  (``write_map_csv``, best of ``--repeats``);
- times ``sonarcarve --version`` and ``sonarcarve --help`` in fresh processes (median of 9,
  after one warm-up run).

``--at COMMIT`` and ``--baseline COMMIT`` run the ``src`` tree of that commit (``git archive``
into the temporary folder, with its own ``NUMBA_CACHE_DIR``), so that other edits in the
working tree do not change the numbers; without ``--at`` the working tree is measured.
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
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

from commits import child_env, export_src

METHODS = ("centerline", "carve", "atm", "combined", "evidence")
_REPO = Path(__file__).resolve().parent.parent
#: ``sonarcarve`` in a child that writes its peak resident memory (VmHWM, KiB) at exit to the
#: file named by ``$BENCH_PEAK_FILE``. Not ``ru_maxrss``: Linux carries the parent's resident
#: size over the fork into the child's ``ru_maxrss``, so every child would read at least the
#: benchmark's own size (the 1M-reading stream it generated).
_CLI = """\
import atexit, os, sys

def _peak():
    if "BENCH_PEAK_FILE" in os.environ:
        with open("/proc/self/status") as status:
            kib = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
        with open(os.environ["BENCH_PEAK_FILE"], "w") as out:
            out.write(kib)

atexit.register(_peak)
from sonarcarve.cli import main
sys.argv[0] = "sonarcarve"
sys.exit(main())
"""


@dataclass(frozen=True)
class Side:
    """One version of the code: a label and the environment its children run in."""

    label: str
    env: dict[str, str]

    def cli(self) -> list[str]:
        return [sys.executable, "-c", _CLI]


def _side(label: str, commit: str | None, folder: Path) -> Side:
    """The working tree (``commit`` None), or ``commit``'s ``src`` exported to ``folder``."""
    env = dict(os.environ)
    if commit is None:
        return Side(label, env)
    root = folder / label
    return Side(f"{label} ({commit})", child_env(export_src(commit, root), root / "numba-cache"))


def _run_child(command: list[str], env: dict[str, str]) -> tuple[float, float, int, str]:
    """Wall seconds, CPU seconds, peak RSS in bytes (the child's own VmHWM, 0 if it wrote
    none) and stdout of one child process."""
    peak_file = Path(tempfile.mkstemp(prefix="sonarcarve-bench-peak-")[1])
    env = {**env, "BENCH_PEAK_FILE": str(peak_file)}
    tic = time.perf_counter()
    with tempfile.TemporaryFile() as out:
        child = subprocess.Popen(command, stdout=out, stderr=subprocess.PIPE, env=env)
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
    kib = peak_file.read_text().strip()
    peak_file.unlink()
    return seconds, cpu, int(kib or 0) * 1024, text


def _summary_number(summary: str, label: str) -> float:
    match = re.search(re.escape(label) + r"\D*([\d,.]+)", summary)
    return float(match.group(1).replace(",", "")) if match else float("nan")


def _median_seconds(command: list[str], env: dict[str, str], repeats: int = 9) -> float:
    subprocess.run(command, check=True, capture_output=True, env=env)  # warm-up: bytecode, cache
    times = []
    for _ in range(repeats):
        tic = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, env=env)
        times.append(time.perf_counter() - tic)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    """Measure and print the tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--readings", type=int, default=1_000_000, help="log length")
    parser.add_argument("--methods", nargs="+", default=list(METHODS))
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of the parse and the write timing (best)")
    parser.add_argument("--at", metavar="COMMIT", help="measure this commit's src, not the "
                        "working tree")
    parser.add_argument("--baseline", metavar="COMMIT", help="also measure this commit")
    parser.add_argument("--stages", metavar="FOLDER", help=argparse.SUPPRESS)  # a child's job
    args = parser.parse_args(argv)
    if args.stages is not None:
        return _stages(Path(args.stages), args.repeats)
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from sonarcarve.io import write_readings_csv
    from synthetic import corridor_stream

    with tempfile.TemporaryDirectory(prefix="sonarcarve-bench-") as name:
        folder = Path(name)
        sides = [_side("after", args.at, folder)]
        if args.baseline is not None:
            sides.insert(0, _side("before", args.baseline, folder))
        readings = folder / "readings.csv"
        write_readings_csv(corridor_stream(args.readings, noise=0.01, spurious_share=0.05,
                                           seed=0).batch, readings)
        size = readings.stat().st_size
        print(f"log: ring corridor (benchmarks/synthetic.py), {args.readings:,} readings, seed 0; "
              f"CSV {size / 2**20:.1f} MiB; {os.cpu_count()} CPUs; load average "
              f"{os.getloadavg()[0]:.1f} at the start\n")
        short = folder / "short.csv"
        with readings.open() as full, short.open("w") as part:
            part.writelines(line for _, line in zip(range(2001), full, strict=False))

        print("| code | method | end to end (readings/s) | wall (s) | CPU (s) | end to end per "
              "CPU second (readings/s) | peak RSS (MiB) | method alone (readings/s, from the "
              "summary) | unprocessed (%, summary) | map rows | map identical to the first |")
        print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
        for method in args.methods:
            first: bytes | None = None
            for side in sides:
                out = folder / f"map-{method}-{side.label.split()[0]}.csv"
                # Warm-up on 2,000 readings: numba's kernels compiled and cached, files in cache.
                command = [*side.cli(), "process", str(short), "--method", method, "--out",
                           str(out)]
                _run_child(command, side.env)
                command[command.index(str(short))] = str(readings)
                seconds, cpu, peak, summary = _run_child(command, side.env)
                data = out.read_bytes()
                first = data if first is None else first
                same = "yes" if data == first else "**no**"
                rows = data.count(b"\n") - 1
                print(f"| {side.label} | {method} | {args.readings / seconds:,.0f} | "
                      f"{seconds:.1f} | {cpu:.1f} | {args.readings / cpu:,.0f} | "
                      f"{peak / 2**20:.0f} | "
                      f"{_summary_number(summary, 'readings per second'):,.0f} | "
                      f"{_summary_number(summary, 'unprocessed (mean % of history rows)'):.1f}"
                      f" | {rows:,} | {same} |", flush=True)

        print(f"\n| code | stage (in a child, best of {args.repeats}) | rows per CPU second | "
              "CPU seconds | MiB per CPU second |")
        print("|---|---|---:|---:|---:|")
        largest = max(folder.glob("map-*-after.csv"), key=lambda path: path.stat().st_size)
        shutil.copy(largest, folder / "largest-map.csv")
        for side in sides:
            _, _, _, table = _run_child([sys.executable, __file__, "--stages", str(folder),
                                         "--repeats", str(args.repeats)], side.env)
            for row in table.splitlines():
                print(f"| {side.label} {row}")

        print("\n| code | command | median of 9 runs (s) |")
        print("|---|---|---:|")
        for side in sides:
            for label, command in {"python -c pass": [sys.executable, "-c", "pass"],
                                   "sonarcarve --version": [*side.cli(), "--version"],
                                   "sonarcarve --help": [*side.cli(), "--help"]}.items():
                print(f"| {side.label} | `{label}` | {_median_seconds(command, side.env):.3f} |")
    print(f"\nload average at the end: {os.getloadavg()[0]:.1f}")
    return 0


def _stages(folder: Path, repeats: int) -> int:
    """The parse and write rows of the stage table, for the ``sonarcarve`` on the path."""
    from sonarcarve.io import read_map_csv, write_map_csv
    from sonarcarve.io.readings_csv import iter_readings_csv

    readings = folder / "readings.csv"
    rows = sum(1 for _ in readings.open()) - 1
    parse = min(_timed(lambda: _drain(iter_readings_csv(readings))) for _ in range(repeats))
    print(f"| parse + validate readings CSV (`iter_readings_csv`) | {rows / parse:,.0f} | "
          f"{parse:.2f} | {readings.stat().st_size / 2**20 / parse:.0f} |")
    points = read_map_csv(folder / "largest-map.csv")
    target = folder / "rewrite.csv"
    write_map_csv(points, target)  # warm-up: the writer's kernel compiled or loaded
    write = min(_timed(lambda: write_map_csv(points, target)) for _ in range(repeats))
    print(f"| write map CSV (`write_map_csv`, {len(points):,} rows) | {len(points) / write:,.0f}"
          f" | {write:.2f} | {target.stat().st_size / 2**20 / write:.0f} |")
    return 0


def _drain(batches: Iterable[object]) -> None:
    for _ in batches:
        pass


def _timed(action: Callable[[], object]) -> float:
    """CPU seconds of ``action`` (one thread: steadier than wall time on a shared machine)."""
    tic = time.process_time()
    action()
    return time.process_time() - tic


if __name__ == "__main__":
    sys.exit(main())
