"""Speed of the methods against their all-pairs references, latency, cold start and memory.

Run from the repository root::

    .venv/bin/python benchmarks/speed.py                       # all sections, defaults
    .venv/bin/python benchmarks/speed.py --sections stream --stream 10000000   # the long run

Sections (``--sections``):

* ``ratio``: readings/s of each method (``add_many`` + ``finish`` over the ring-corridor stream
  of ``synthetic.py``, one core, median of ``--repeats`` after a warm-up) at each history,
  against the *all-pairs reference* in the same run: the product as it was before the spatial
  index (commit ``7445718``, loaded from git into a temporary folder and run in a subprocess:
  every reading checked against every live arc, one Python call per reading). The global maps
  of both are compared field by field: ``identical`` must say yes. The reference refuses ATM
  and combined above about 5,790 arcs (its crossing store had room for every possible crossing,
  over 1 GiB); there the reference is this commit with ATM's index switched off (ATM's
  all-pairs scan, the oracle of ``tests/methods/test_index_oracle.py``; for combined, carving
  stays indexed).
* ``latency``: ``add()`` p50/p99 (one reading at a time, after 2 x history readings) and
  ``local_map()`` time (fresh after an ``add``, and asked again with nothing new) per method.
* ``cold``: the first ``add()`` of each method in a fresh interpreter with an empty
  ``NUMBA_CACHE_DIR`` (so numba compiles), the import time, and how many functions numba
  compiled for that first ``add()`` (numba's compile events). Then the same after install:
  ``sonarcarve warm`` run once in its own process into a new ``NUMBA_CACHE_DIR`` (as ``make``
  does after ``pip install``), and each method's first ``add()`` in a further fresh
  interpreter that loads the cached machine code (it must compile 0 functions).
* ``stream``: peak RSS growth while carving ``--stream`` readings (the corridor stream
  repeated, times shifted), sampled every million: it must stay flat.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from commits import export_src

REFERENCE_COMMIT = "7445718"
ROOT = Path(__file__).resolve().parent.parent

_RUNNER = r"""
import json, statistics, sys, time
import numpy as np
sys.path.insert(0, {bench!r})
from synthetic import corridor_stream
from sonarcarve import MethodConfig, make_method
name, out = sys.argv[1], sys.argv[5]
history, readings, repeats = (int(v) for v in sys.argv[2:5])
all_pairs = sys.argv[6:] == ["all-pairs"]
batch = corridor_stream(readings, noise=0.01, spurious_share=0.05, seed=0).batch
def run(b):
    m = make_method(name, MethodConfig(history_size=history))
    for model in m.models:
        if all_pairs and hasattr(model, "_use_index"):
            model._use_index = False  # ATM's all-pairs scan, as in test_index_oracle.py
    tic = time.perf_counter(); m.add_many(b); g = m.finish()
    return time.perf_counter() - tic, g
run(batch[:2000])
times = []
for _ in range(repeats):
    seconds, g = run(batch)
    times.append(seconds)
np.savez(out, xy=g.xy, reading_id=g.reading_id, source=g.source, width=g.width,
         max_error=g.max_error)
print(json.dumps({{"rate": len(batch) / statistics.median(times)}}))
"""


def _reference_tree(folder: Path) -> Path:
    """``src`` of :data:`REFERENCE_COMMIT`, extracted into ``folder``."""
    return export_src(REFERENCE_COMMIT, folder)


def _run(src: Path, name: str, history: int, readings: int, repeats: int,
         out: Path, *, all_pairs: bool = False) -> float | None:
    """Readings/s of ``name`` from the package in ``src``, its global map saved to ``out``;
    None if that package refuses the configuration (ConfigError). ``all_pairs``: with ATM's
    index switched off (every live arc, the oracle of ``tests/methods/test_index_oracle.py``)."""
    code = _RUNNER.format(bench=str(ROOT / "benchmarks"))
    env = {**os.environ, "PYTHONPATH": str(src)}
    extra = ["all-pairs"] if all_pairs else []
    done = subprocess.run([sys.executable, "-c", code, name, str(history), str(readings),
                           str(repeats), str(out), *extra], env=env, check=False,
                          capture_output=True, text=True)
    if done.returncode and "ConfigError" in done.stderr:
        return None
    done.check_returncode()
    return float(json.loads(done.stdout.strip().splitlines()[-1])["rate"])


def ratio(args: argparse.Namespace) -> None:
    print(f"\n### Throughput against the all-pairs reference ({args.readings} readings)\n")
    print("| method | history | reference readings/s | indexed readings/s | ratio | identical |")
    print("|---|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as folder:
        ref_src = _reference_tree(Path(folder))
        for name in args.methods:
            for history in args.histories:
                a, b = Path(folder) / "ref.npz", Path(folder) / "new.npz"
                ref = _run(ref_src, name, history, args.readings, args.repeats, a)
                new = _run(ROOT / "src", name, history, args.readings, args.repeats, b)
                assert new is not None
                label = f"{ref:,.0f}" if ref is not None else ""
                if ref is None:  # refused: this commit with ATM's all-pairs scan instead
                    ref = _run(ROOT / "src", name, history, args.readings, args.repeats, a,
                               all_pairs=True)
                    assert ref is not None
                    label = f"refused; ATM all-pairs: {ref:,.0f}"
                x, y = np.load(a), np.load(b)
                same = all(np.array_equal(x[k], y[k], equal_nan=True) for k in x.files)
                print(f"| {name} | {history:,} | {label} | {new:,.0f} | {new / ref:.2f} | "
                      f"{'yes' if same else 'NO'} |", flush=True)


def latency(args: argparse.Namespace) -> None:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from sonarcarve import MethodConfig, make_method
    from synthetic import corridor_stream

    print("\n### Latency (one core; µs)\n")
    print("| method | history | add() p50 | add() p99 | local_map() | local_map() again |")
    print("|---|---:|---:|---:|---:|---:|")
    for history in args.latency_histories:
        batch = corridor_stream(2 * history + 5000, noise=0.01, spurious_share=0.05).batch
        for name in args.methods:
            method = make_method(name, MethodConfig(history_size=history))
            method.add_many(batch[: 2 * history])
            readings = [batch[i] for i in range(2 * history, len(batch))]
            times = np.empty(len(readings))
            maps = []
            for k, reading in enumerate(readings):
                tic = time.perf_counter()
                method.add(reading)
                times[k] = time.perf_counter() - tic
                if k % 50 == 0:
                    tic = time.perf_counter()
                    method.local_map()
                    fresh = time.perf_counter() - tic
                    tic = time.perf_counter()
                    method.local_map()
                    maps.append((fresh, time.perf_counter() - tic))
            p50, p99 = np.percentile(times, [50, 99]) * 1e6
            fresh = statistics.median(m[0] for m in maps) * 1e6
            again = statistics.median(m[1] for m in maps) * 1e6
            print(f"| {name} | {history:,} | {p50:.1f} | {p99:.1f} | {fresh:.0f} | {again:.1f} |",
                  flush=True)


_COLD = r"""
import time
tic = time.perf_counter()
from sonarcarve import MethodConfig, Reading, make_method
imported = time.perf_counter() - tic
import sys
m = make_method(sys.argv[1], MethodConfig(history_size=250))
from numba.core import event
compiled = []
class Count(event.Listener):
    def on_start(self, ev):
        pass
    def on_end(self, ev):
        compiled.append(ev.data["dispatcher"])
event.register("numba:compile", Count())
tic, cpu = time.perf_counter(), time.process_time()
m.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0))
first, first_cpu = time.perf_counter() - tic, time.process_time() - cpu
functions = len(compiled)
tic = time.perf_counter()
m.add(Reading(0.01, 1, 0.0, 0.1, 0.3, 1.5))
m.local_map()
m.finish()
rest = time.perf_counter() - tic
print(imported, first, rest, functions, first_cpu, len(compiled) - functions)
"""

_WARM = "from sonarcarve.cli import main; raise SystemExit(main(['warm', '--quiet']))"


def _cold_run(name: str, cache: str) -> list[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    return subprocess.run([sys.executable, "-c", _COLD, name], env=env, check=True,
                          capture_output=True, text=True).stdout.split()


def cold(args: argparse.Namespace) -> None:
    print("\n### Cold start (fresh interpreter; s)\n")
    with tempfile.TemporaryDirectory() as warmed:
        tic, cpu = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
        said = subprocess.run([sys.executable, "-c", _WARM], check=True, capture_output=True,
                              text=True, env={**os.environ, "NUMBA_CACHE_DIR": warmed}).stdout
        warm_wall = time.perf_counter() - tic
        warm_cpu = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - cpu
        print(f"`sonarcarve warm` into an empty NUMBA_CACHE_DIR, its own process: "
              f"{warm_wall:.1f} s wall, {warm_cpu:.1f} s CPU ({' '.join(said.split())})\n")
        print("| method | cache | import sonarcarve | first add() | first add() CPU | "
              "then add, local_map, finish | functions compiled by the first add() | "
              "compiled after it |")
        print("|---|---|---:|---:|---:|---:|---:|---:|")
        for name in args.methods:
            with tempfile.TemporaryDirectory() as empty:
                runs = [("empty", _cold_run(name, empty)),
                        ("after `sonarcarve warm`", _cold_run(name, warmed))]
            for cache, out in runs:
                imported, first, rest, first_cpu = (float(v) for v in (*out[:3], out[4]))
                print(f"| {name} | {cache} | {imported:.2f} | {first:.2f} | {first_cpu:.2f} | "
                      f"{rest:.2f} | {out[3]} | {out[5]} |", flush=True)


def stream(args: argparse.Namespace) -> None:
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from sonarcarve import MethodConfig, ReadingBatch, make_method
    from synthetic import corridor_stream

    print(f"\n### Memory over a {args.stream:,}-reading stream (carve, history 250)\n")
    base = corridor_stream(100_000, noise=0.01, spurious_share=0.05).batch
    span = float(base.t[-1] + 0.01)
    method = make_method("carve", MethodConfig(history_size=250))
    done = 0
    rows = []
    tic = time.perf_counter()
    while done < args.stream:
        n = min(len(base), args.stream - done)
        shift = (done // len(base)) * span
        part = base[:n]
        method.add_many(ReadingBatch(t=part.t + shift, sensor=part.sensor, x=part.x, y=part.y,
                                     theta=part.theta, range=part.range,
                                     beam_width=part.beam_width))
        method.global_map()
        method._global = type(method._global)()  # drop committed points: measure the method
        done += n
        if done % 1_000_000 == 0 or done == args.stream:
            peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
            rows.append((done, peak, done / (time.perf_counter() - tic)))
    print("| readings | peak RSS (MiB) | readings/s so far |")
    print("|---:|---:|---:|")
    for done, peak, rate in rows:
        print(f"| {done:,} | {peak:.0f} | {rate:,.0f} |")


def main(argv: list[str] | None = None) -> int:
    """Run the chosen sections and print markdown tables."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sections", nargs="+", default=["ratio", "latency", "cold", "stream"])
    parser.add_argument("--methods", nargs="+",
                        default=["carve", "atm", "combined", "evidence", "centerline"])
    parser.add_argument("--histories", type=int, nargs="+", default=[250, 1000, 10_000])
    parser.add_argument("--latency-histories", type=int, nargs="+", default=[250, 10_000])
    parser.add_argument("--readings", type=int, default=20_000, help="stream length (ratio)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--stream", type=int, default=1_000_000,
                        help="readings of the memory section (the issue's long run: 10000000)")
    args = parser.parse_args(argv)
    sections = {"ratio": ratio, "latency": latency, "cold": cold, "stream": stream}
    for name in args.sections:
        sections[name](args)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
