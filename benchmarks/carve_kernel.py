"""Time the carving kernels against the single-file geometry of commit bf5ea05, in one process.

Run from the repository root (needs ``git`` to read the old source)::

    .venv/bin/python benchmarks/carve_kernel.py

The old ``sonarcarve/geometry/__init__.py`` of commit ``bf5ea05`` (before the geometry was split
into modules) is written to a temporary folder and imported as a module of its own, so both
versions are compiled by numba in the same process. The script then

* checks that both give bit-identical results: ``carve_arc`` and ``arc_remainder`` on random arcs
  and sectors (paper and specular-aware, with and without a range tolerance), and a whole replay
  of the ring-corridor stream of ``synthetic.py`` through ``carve_arcs`` at history 250 (every
  interval, bounding circle, status and count);
* times, interleaved old / new / old / new ... (``--repeats`` rounds, medians): the replay, per
  ``carve_arcs`` call, driven from a compiled loop (no Python dispatch); ``carve_arc`` over the
  random cases from a compiled loop; and one ``carve_arc`` called from Python.

Timing noise on a shared machine is large; only the medians of interleaved rounds compare.
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from numba import njit

import sonarcarve.geometry as new_geometry
from synthetic import corridor_stream

OLD_COMMIT = "bf5ea05"
OLD_PATH = "src/sonarcarve/geometry/__init__.py"


def load_old_geometry(folder: Path) -> ModuleType:
    """The single-file geometry of :data:`OLD_COMMIT`, imported as ``old_geometry``."""
    source = subprocess.run(["git", "show", f"{OLD_COMMIT}:{OLD_PATH}"], check=True,
                            capture_output=True, text=True).stdout
    path = folder / "old_geometry.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("old_geometry", path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["old_geometry"] = module
    spec.loader.exec_module(module)
    return module


# -- random single arcs ------------------------------------------------------------------------


def random_cases(n: int, seed: int = 1) -> np.ndarray:
    """``n`` rows of carve_arc's 12 arguments: arcs near sectors, so most need the exact path."""
    rng = np.random.default_rng(seed)
    ox, oy = rng.uniform(-1.0, 1.0, (2, n))
    r = rng.uniform(0.2, 3.0, n)
    lo = rng.uniform(-math.pi, math.pi, n)
    width = np.where(rng.random(n) < 0.05, 0.0, rng.uniform(0.0, 0.6, n))
    fx, fy = rng.uniform(-1.0, 1.0, (2, n))
    same = rng.random(n) < 0.05  # coincident origins
    fx[same], fy[same] = ox[same], oy[same]
    fr = rng.uniform(0.1, 4.0, n)
    f_lo = rng.uniform(-math.pi, math.pi, n)
    f_width = rng.uniform(0.0, 0.8, n)
    tolerance = rng.choice([0.0, 0.0254], n)
    max_incidence = rng.choice([0.5 * math.pi, 0.5 * math.pi, 0.3, 1.0, 0.0], n)
    return np.column_stack((ox, oy, r, lo, lo + width, fx, fy, fr, f_lo, f_lo + f_width,
                            tolerance, max_incidence))


def make_case_loop(carve_arc: Callable[..., Any]) -> Callable[..., Any]:
    """A compiled loop calling ``carve_arc`` on every row of :func:`random_cases`."""

    @njit
    def run(cases: np.ndarray, fates: np.ndarray, out: np.ndarray) -> None:
        for i in range(cases.shape[0]):
            c = cases[i]
            fate, new_lo, new_hi = carve_arc(c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7],
                                             c[8], c[9], c[10], c[11])
            fates[i] = fate
            out[i, 0] = new_lo
            out[i, 1] = new_hi

    return run


# -- a replay of the corridor stream through carve_arcs ----------------------------------------


def make_replay(carve_arcs: Callable[..., Any],
                bounding: Callable[..., Any]) -> Callable[..., Any]:
    """A compiled replay: each reading starts as its full beam, then carves the previous ones."""

    @njit
    def replay(x: np.ndarray, y: np.ndarray, r: np.ndarray, t1: np.ndarray, t2: np.ndarray,
               lo: np.ndarray, hi: np.ndarray, bounds: np.ndarray, status: np.ndarray,
               carved: np.ndarray, rows: np.ndarray, history: int, tolerance: float,
               max_incidence: float) -> tuple[int, int]:
        fully = 0
        split = 0
        for i in range(x.shape[0]):
            lo[i] = t1[i]
            hi[i] = t2[i]
            bounds[i, 0], bounds[i, 1], bounds[i, 2] = bounding(x[i], y[i], r[i], t1[i], t2[i])
            status[i] = 0
            carved[i] = False
            f, s = carve_arcs(rows[max(0, i - history):i], x, y, r, lo, hi, bounds, status,
                              carved, x[i], y[i], r[i], t1[i], t2[i], tolerance, max_incidence)
            fully += f
            split += s
        return fully, split

    return replay


class Replay:
    """The stream's arrays and one replay function per geometry."""

    def __init__(self, readings: int, history: int, tolerance: float,
                 max_incidence: float) -> None:
        batch = corridor_stream(readings, spurious_share=0.05).batch
        self.x, self.y, self.r = batch.x, batch.y, batch.range
        half = 0.5 * np.where(np.isnan(batch.beam_width), math.radians(22.5), batch.beam_width)
        self.t1 = batch.theta - half
        self.t2 = batch.theta + half
        self.history = history
        self.tolerance = tolerance
        self.max_incidence = max_incidence

    @property
    def n(self) -> int:
        return int(self.x.shape[0])

    def run(self, replay: Callable[..., Any]) -> tuple[float, tuple[Any, ...]]:
        """Seconds per carve_arcs call, and every output."""
        n = self.n
        lo, hi = np.empty(n), np.empty(n)
        bounds = np.empty((n, 3))
        status = np.zeros(n, dtype=np.int8)
        carved = np.zeros(n, dtype=np.bool_)
        rows = np.arange(n, dtype=np.int64)
        start = time.perf_counter()
        counts = replay(self.x, self.y, self.r, self.t1, self.t2, lo, hi, bounds, status, carved,
                        rows, self.history, self.tolerance, self.max_incidence)
        seconds = time.perf_counter() - start
        return seconds / n, (counts, lo, hi, bounds, status, carved)


def same(a: Any, b: Any) -> bool:
    """Bit-identical, element by element (NaN equal to NaN)."""
    if isinstance(a, tuple):
        return len(a) == len(b) and all(same(p, q) for p, q in zip(a, b, strict=True))
    return bool(np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True))


def check_identical(old: ModuleType, cases: np.ndarray) -> None:
    for row in cases:
        args = tuple(float(v) for v in row)
        a, b = old.carve_arc(*args), new_geometry.carve_arc(*args)
        if not same(a, b):
            raise SystemExit(f"carve_arc differs on {args}: old {a}, new {b}")
        a, b = old.arc_remainder(*args), new_geometry.arc_remainder(*args)
        if not same(a, b):
            raise SystemExit(f"arc_remainder differs on {args}: old {a}, new {b}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readings", type=int, default=6000)
    parser.add_argument("--history", type=int, default=250)
    parser.add_argument("--cases", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory() as folder:
        old = load_old_geometry(Path(folder))
        cases = random_cases(args.cases)
        check_identical(old, cases)
        print(f"carve_arc, arc_remainder: {args.cases} random cases bit-identical")

        replays = {
            "old": make_replay(old.carve_arcs, old.arc_bounding_circle),
            "new": make_replay(new_geometry.carve_arcs, new_geometry.arc_bounding_circle),
        }
        loops = {"old": make_case_loop(old.carve_arc),
                 "new": make_case_loop(new_geometry.carve_arc)}
        singles = {"old": old.carve_arc, "new": new_geometry.carve_arc}
        streams = [Replay(args.readings, args.history, 0.0254, 0.5 * math.pi),
                   Replay(args.readings, args.history, 0.0254, math.radians(17.5))]
        for stream in streams:
            outputs = [stream.run(replays[name])[1] for name in ("old", "new")]
            if not same(*outputs):
                raise SystemExit(f"carve_arcs replay differs (β = {stream.max_incidence})")
        print(f"carve_arcs replay of {streams[0].n} readings at history {args.history}: "
              "bit-identical (β = 90°, 17.5°)")

        # One undecided arc (needs the exact path), called from Python.
        single = (0.0, 0.0, 2.0, -0.4, 0.4, 1.0, 0.0, 5.0, -0.05, 0.05, 0.0, 0.5 * math.pi)
        fates = np.empty(cases.shape[0], dtype=np.int64)
        out = np.empty((cases.shape[0], 2))
        for name in ("old", "new"):  # compile
            loops[name](cases, fates, out)
            singles[name](*single)

        timings: dict[str, dict[str, list[float]]] = {
            key: {"old": [], "new": []}
            for key in ("carve_arcs β=90°", "carve_arcs β=17.5°", "carve_arc loop",
                        "carve_arc from Python")
        }
        calls = 20_000
        for _ in range(args.repeats):
            for name in ("old", "new"):
                for stream, key in zip(streams, ("carve_arcs β=90°", "carve_arcs β=17.5°"),
                                       strict=True):
                    timings[key][name].append(stream.run(replays[name])[0])
                start = time.perf_counter()
                loops[name](cases, fates, out)
                timings["carve_arc loop"][name].append(
                    (time.perf_counter() - start) / cases.shape[0])
                fn = singles[name]
                start = time.perf_counter()
                for _ in range(calls):
                    fn(*single)
                timings["carve_arc from Python"][name].append(
                    (time.perf_counter() - start) / calls)

        print(f"\nmedians of {args.repeats} interleaved rounds, per call")
        print("\n| kernel | old (bf5ea05) | new | new / old |")
        print("|---|---:|---:|---:|")
        for key, by_name in timings.items():
            o = statistics.median(by_name["old"])
            n = statistics.median(by_name["new"])
            print(f"| {key} | {o * 1e9:,.0f} ns | {n * 1e9:,.0f} ns | {n / o:.2f} |")


if __name__ == "__main__":
    main()
