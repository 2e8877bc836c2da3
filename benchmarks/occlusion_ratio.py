"""The occlusion map filter's line test (``geometry/occluded.py``, ``LINE_RATIO``) at several
ratios, on held-out floors and on a dense map, each map made once and filtered per ratio.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/occlusion_ratio.py --robot p3dx-front --physics specular
    nice .venv/bin/python benchmarks/occlusion_ratio.py --dense

A point makes up a surface when its neighbourhood's scatter has its larger eigenvalue at least
``ratio`` times the smaller (4: spread along twice that across; 9: three times; 16: four).
Without ``--dense``: evidence carving's global map of each floor of ``heldout.py`` (or
``--worlds``), seeds 0-1, the ``--robot``'s sonars under ``--physics`` (one of ``heldout.py``'s
models), filtered with ``MapFilter(occlusion_depth=0.5)`` at each ratio; per ratio the means
over runs of direct echoes kept and of spurious and multipath echoes removed (%), and the runs
that keep and remove at least 85 % (issue 9's first two targets). With ``--dense``: combined,
evidence and centerline on ``synthetic.py``'s corridor loop (no multipath there, so every true
echo dropped is a loss), the share of true and spurious echoes each ratio drops.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

import heldout
from sonarcarve import MethodConfig, make_method
from sonarcarve.filters import OCCLUSION_DEPTH, MapFilter, filter_map, point_origins
from sonarcarve.geometry import occluded
from sonarcarve.maps import GlobalMap
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.sonar import EchoKind
from synthetic import corridor_stream

RATIOS = (4.0, 9.0, 16.0)


def _dropped(points: GlobalMap, readings: ReadingBatch, ratio: float) -> npt.NDArray[np.bool_]:
    """Per reading, whether the filter at line ratio ``ratio`` dropped its point."""
    defaults = occluded.occluded_points.__kwdefaults__
    assert defaults is not None
    saved = defaults["line_ratio"]
    defaults["line_ratio"] = ratio  # the filter passes no ratio: it takes this default
    try:
        kept = filter_map(points, MapFilter(occlusion_depth=OCCLUSION_DEPTH),
                          point_origins(points, readings)).points
    finally:
        defaults["line_ratio"] = saved
    gone = np.zeros(len(readings), dtype=bool)
    gone[points.reading_id] = True
    gone[kept.reading_id] = False
    return gone


def _floors(robot: str, physics: str, worlds: Sequence[str], seeds: int,
            ratios: Sequence[float]) -> None:
    runs: dict[float, list[tuple[float, float, float]]] = {r: [] for r in ratios}
    for world in worlds:
        for seed in range(seeds):
            sim = heldout._simulate(world, seed, heldout.PHYSICS[physics], robot)
            kind = sim.truth.kind
            direct, multipath = kind == EchoKind.DIRECT, kind == EchoKind.MULTIPATH
            points = process_readings(sim.readings,
                                      make_method("evidence", MethodConfig())).global_map
            kept = np.zeros(len(kind), dtype=bool)
            kept[points.reading_id] = True
            for ratio in ratios:
                now = kept & ~_dropped(points, sim.readings, ratio)
                runs[ratio].append((float(np.mean(now[direct])), float(np.mean(~now[~direct])),
                                    float(np.mean(~now[multipath])) if multipath.any()
                                    else np.nan))
    print(f"evidence carving, {robot}, {physics}; {', '.join(worlds)}; seeds 0-{seeds - 1}\n")
    print("| line ratio | direct kept (%) | spurious removed (%) | multipath removed (%) | "
          "runs keeping and removing ≥ 85 % |")
    print("|---:|---:|---:|---:|---:|")
    for ratio, rows in runs.items():
        a = np.array(rows)
        met = int(np.sum((a[:, 0] >= 0.85) & (a[:, 1] >= 0.85)))
        kept_pc, removed_pc, multipath_pc = 100 * np.nanmean(a, axis=0)
        print(f"| {ratio:g} | {kept_pc:.1f} | {removed_pc:.1f} | {multipath_pc:.1f} | "
              f"{met} of {len(a)} |")


def _dense(ratios: Sequence[float]) -> None:
    print("| map | method | readings | line ratio | true echoes dropped (%) | spurious dropped "
          "(%) |")
    print("|---|---|---:|---:|---:|---:|")
    for n, method in ((200_000, "evidence"), (200_000, "combined"), (50_000, "centerline")):
        stream = corridor_stream(n, noise=0.01, spurious_share=0.05, seed=0)
        spurious = np.asarray(stream.spurious)
        points = process_readings(stream.batch, make_method(method, MethodConfig())).global_map
        mapped = np.zeros(len(spurious), dtype=bool)
        mapped[points.reading_id] = True
        for ratio in ratios:
            gone = _dropped(points, stream.batch, ratio)
            print(f"| corridor loop | {method} | {n:,} | {ratio:g} | "
                  f"{100 * gone[mapped & ~spurious].mean():.2f} | "
                  f"{100 * gone[mapped & spurious].mean():.2f} |", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="scout2")
    parser.add_argument("--physics", default="specular", choices=list(heldout.PHYSICS))
    parser.add_argument("--worlds", nargs="+", default=list(heldout.WORLDS))
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--ratios", type=float, nargs="+", default=list(RATIOS))
    parser.add_argument("--dense", action="store_true",
                        help="the synthetic corridor loop instead of the floors")
    args = parser.parse_args(argv)
    if args.dense:
        _dense(args.ratios)
    else:
        _floors(args.robot, args.physics, args.worlds, args.seeds, args.ratios)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
