"""What the occlusion map filter costs (``MapFilter(occlusion_depth=0.5)``, ``process
--occlusion-depth``), beside the method that made the map, in the same run.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/occlusion_filter.py

Evidence carving's global map of the office tour (seed 0, specular physics, the Scout2 ring),
and the maps of combined, evidence and centerline of ``synthetic.py``'s corridor stream: a 2 m
wide loop driven round and round, so the longer the log the denser the map, the case where a
map's own misplaced points could pose as walls. For each, the CPU seconds of making the map
(``process_readings``, no filter) and of the filter alone (origins looked up and the mask), best
of ``--repeats``, after one warm-up call (compiled, cache warm); the filter's microseconds a
point and its share of the method's time; and, from the stream's truth, the share of its true
(wall) echoes and of its spurious (cross-talk, short) ones the filter drops: it should drop
neither, the corridor having no multipath.
"""

from __future__ import annotations

import argparse
import math

import numpy as np
import numpy.typing as npt

from sonarcarve import MethodConfig, ReadingBatch, make_method
from sonarcarve.filters import OCCLUSION_DEPTH, MapFilter, filter_map, point_origins
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import GlobalMap
from sonarcarve.pipeline import process_readings
from synthetic import corridor_stream
from timing import best_seconds


def _row(name: str, method: str, batch: ReadingBatch, repeats: int,
         spurious: npt.NDArray[np.bool_] | None = None) -> None:
    def make() -> GlobalMap:
        return process_readings(batch, make_method(method, MethodConfig())).global_map

    points = make()
    spec = MapFilter(occlusion_depth=OCCLUSION_DEPTH)
    method_s = best_seconds(make, repeats)
    filter_s = best_seconds(lambda: filter_map(points, spec, point_origins(points, batch)), repeats)
    kept = filter_map(points, spec, point_origins(points, batch)).points
    shares = "– | –"
    if spurious is not None:
        gone = ~np.isin(points.reading_id, kept.reading_id)
        false = spurious[points.reading_id]
        shares = (f"{100 * np.mean(gone[~false]):.2f} | "
                  f"{100 * np.mean(gone[false]) if false.any() else math.nan:.2f}")
    print(f"| {name} | {method} | {len(batch):,} | {len(points):,} | {len(points) - len(kept):,} "
          f"| {shares} | {method_s:.3f} | {filter_s:.3f} | "
          f"{1e6 * filter_s / max(len(points), 1):.2f} | {100 * filter_s / method_s:.1f} |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--corridor", type=int, nargs="+", default=[50_000, 200_000],
                        help="readings of the synthetic corridor stream")
    args = parser.parse_args(argv)
    office = run_simulation(Scenario("office", 0)).readings
    print("| map | method | readings | points | dropped | true echoes dropped (%) | spurious "
          "dropped (%) | method CPU s | filter CPU s | filter µs a point | filter / method (%) |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    _row("office tour, seed 0", "evidence", office, args.repeats)
    for n in args.corridor:
        stream = corridor_stream(n, noise=0.01, spurious_share=0.05, seed=0)
        for method in ("combined", "evidence", "centerline"):
            _row("synthetic corridor loop", method, stream.batch, args.repeats,
                 np.asarray(stream.spurious))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
