"""Measure arc carving's range tolerance ε on noisy synthetic data (choose the default by this).

Run from the repository root::

    .venv/bin/python benchmarks/range_tolerance.py

For each range-noise level σ and tolerance ε, the carving method maps the ring-corridor stream of
``synthetic.py`` (16 sensors, 1-inch quantisation, 5 % spurious short echoes) and the script
prints a markdown table of:

* the median (and 90th percentile) distance of the global map's points to the true walls;
* the share of all readings that were fully carved, and that were split (section 3);
* the share of *true* echoes (not spurious) that were fully carved: carving away a real
  obstacle is the error ε guards against (a split true echo is dropped by the paper's rule, on
  purpose: a closer reading of the same obstacle exists);
* the share of spurious echoes removed (fully carved or split).

Centerline rows (no carving) give the baseline for the distances.
"""

from __future__ import annotations

import argparse

import numpy as np

from sonarcarve import CarvingMethod, CenterlineMethod, GlobalMap, SonarHistory, SonarMethod
from sonarcarve.methods.base import ArcFate, Estimates, SlotArray
from synthetic import Stream, corridor_stream


def _row(label: str, noise: float, stream: Stream, method: SonarMethod) -> str:
    n = len(stream.batch)
    removal = np.zeros(n, dtype=np.int8)

    def record(history: SonarHistory, slots: SlotArray, est: Estimates) -> None:
        if est.fate is not None:
            removal[history.reading_id[slots]] = est.fate

    method.add_commit_listener(record)
    method.add_many(stream.batch)
    global_map: GlobalMap = method.finish()
    distance = stream.world.distance_to_walls(global_map.xy)
    true = ~stream.spurious
    fully = removal == ArcFate.FULLY_CARVED
    split = removal == ArcFate.SPLIT
    true_fully = np.count_nonzero(true & fully) / max(1, np.count_nonzero(true))
    removed_spurious = (np.count_nonzero(stream.spurious & (removal != ArcFate.ALIVE))
                        / max(1, np.count_nonzero(stream.spurious)))
    return (f"| {noise * 100:.1f} | {label} | {np.median(distance) * 100:.2f} | "
            f"{np.percentile(distance, 90) * 100:.1f} | {np.mean(fully):.3f} | "
            f"{np.mean(split):.3f} | {true_fully:.3f} | {removed_spurious:.3f} |")


def main(argv: list[str] | None = None) -> int:
    """Measure and print the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--readings", type=int, default=20_000)
    parser.add_argument("--noise", type=float, nargs="+", default=[0.0, 0.01, 0.025],
                        help="range noise σ, metres")
    parser.add_argument("--tolerance", type=float, nargs="+",
                        default=[0.0, 0.01, 0.025, 0.05, 0.1], help="ε values, metres")
    parser.add_argument("--spurious", type=float, default=0.05, help="share of spurious echoes")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    print(f"ring corridor, {args.readings} readings, 16 sensors, 1-inch quantisation, "
          f"{args.spurious:.0%} spurious echoes, history 250, seed {args.seed}\n")
    print("| σ (cm) | method | median dist. to wall (cm) | p90 (cm) | fully carved | split | "
          "true echoes fully carved | spurious removed |")
    print("|---:|---|---:|---:|---:|---:|---:|---:|")
    for noise in args.noise:
        stream = corridor_stream(args.readings, noise=noise, spurious_share=args.spurious,
                                 seed=args.seed)
        print(_row("centerline", noise, stream, CenterlineMethod()))
        for tolerance in args.tolerance:
            label = f"carve ε={tolerance * 100:g} cm"
            print(_row(label, noise, stream, CarvingMethod(range_tolerance=tolerance)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
