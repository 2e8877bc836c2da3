"""Firing periods on the real roboND log, and what ending stale marks changes in its grid.

Run from the repository root::

    .venv/bin/python benchmarks/stale_marks.py

The carved grid ends a newest echo's mark after ``fresh_periods`` of its sensor's firing period,
learnt from the log (:class:`~sonarcarve.grids.carved.periods.FiringPeriods`;
``docs/carved-grid.md``, "Stale marks"). The simulator fires its ring like clockwork, so this
checks the rule on real firing times: the bundled roboND log (8 sensors, no-echo values and
stale repeats dropped, :func:`~sonarcarve.io.roboND.read_robond`). It prints each sensor's
period and how its gaps fall against it (a gap between 1.1 and 2 periods would end a mark
before the sensor's next echo), then the carved grid's occupied cells with the rule off
(``inf``), at 1.1 (the default) and at 1.5 periods: read at the end of the log, and the mean
over reads every 5 readings (what a costmap reader sees as the robot drives). There is no
ground truth: the numbers say how much the rule changes, not whether the map is right.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from sonarcarve.grids import OCCUPIED, CarvedGrid, CarvedGridParams, trinary
from sonarcarve.grids.carved.periods import FiringPeriods
from sonarcarve.io.roboND import read_robond
from sonarcarve.readings import ReadingBatch

#: Metres around the path: the log's sonars reach 5 m.
MARGIN = 5.5


def _gap_table(batch: ReadingBatch) -> None:
    """Each gap against the period the grid knew when the gap ended (causal, reading by
    reading), so a gap above 1.1 periods is a time the mark of the sensor's previous echo ended
    before its next reading came."""
    periods = FiringPeriods()
    ratios: dict[int, list[float]] = {}
    last: dict[int, float] = {}
    for s, t in zip(batch.sensor.tolist(), batch.t.tolist(), strict=True):
        known = periods.period(s)
        if s in last and t > last[s] and known < math.inf:
            ratios.setdefault(s, []).append((t - last[s]) / known)
        last[s] = t
        periods.note(np.array([s]), np.array([t]))
    print("| sensor | gaps (period known) | period at the end (s) | ≤ 1.1 periods | 1.1-1.5 "
          "| 1.5-2 | > 2 |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for s in sorted(ratios):
        ratio = np.array(ratios[s])
        bins = [np.count_nonzero(ratio <= 1.1),
                np.count_nonzero((ratio > 1.1) & (ratio <= 1.5)),
                np.count_nonzero((ratio > 1.5) & (ratio <= 2.0)),
                np.count_nonzero(ratio > 2.0)]
        print(f"| {s} | {len(ratio)} | {periods.period(s):.3f} | "
              + " | ".join(str(b) for b in bins) + " |")


def _occupied(batch: ReadingBatch, resolution: float, fresh_periods: float,
              every: int) -> tuple[int, float]:
    extent = (float(batch.x.min()), float(batch.y.min()),
              float(batch.x.max()), float(batch.y.max()))
    grid = CarvedGrid.around(extent, resolution, MARGIN,
                             params=CarvedGridParams(fresh_periods=fresh_periods))
    counts = []
    for start in range(0, len(batch), every):
        grid.add_many(batch[start:start + every])
        counts.append(int(np.count_nonzero(trinary(grid) == OCCUPIED)))
    return counts[-1], float(np.mean(counts))


def main(argv: list[str] | None = None) -> int:
    """Print the gap table and the occupied-cell table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--every", type=int, default=5, help="readings between two reads")
    args = parser.parse_args(argv)
    if args.every < 1:
        parser.error(f"--every must be a whole number >= 1, got {args.every}")
    batch = read_robond().batch
    print(f"\nroboND log: {len(batch)} readings; gaps between two readings of one sensor "
          "against its period as the grid knew it then (rank n/4 of its newest 16 gaps, when "
          "they fit one period; gaps while it had none are not counted)\n")
    _gap_table(batch)
    print(f"\nCarved grid, occupied cells: at the end of the log / mean over reads every "
          f"{args.every} readings\n")
    print("| resolution (m) | off (inf) | 1.1 periods (default) | 1.5 periods |")
    print("|---:|---:|---:|---:|")
    for h in (0.05, 0.10):
        cells = [_occupied(batch, h, k, args.every) for k in (math.inf, 1.1, 1.5)]
        print(f"| {h:.2f} | " + " | ".join(f"{end:,} / {mean:,.1f}" for end, mean in cells)
              + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
