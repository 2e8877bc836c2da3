"""Which echoes evidence carving gets wrong, against a signal it does not use yet: repeats.

Run from the repository root (on a shared machine, with ``nice``)::

    .venv/bin/python benchmarks/repeat_echoes.py            # 4 world/physics pairs, seeds 0-2

A sonar that drives towards (or away from) the point it hears hears it again at a range that
changes by exactly the distance it drove: two echoes of one sensor whose circles are internally
tangent (``| |P2 - P1| - |r1 - r2| | <= ε``), at a point inside both beams, can both come from
that point, on the line of motion. Echoes off a wall approached at an angle, crosstalk (another
sensor's ping, whose path length changes differently) and floor echoes (a constant range) do not
line up so. The carved grid uses the same test to stop counting such repeats as independent
evidence (``CarvedGridParams.repeat_weight``). Evidence carving's *localised* support counts
tangent circles as nothing, on purpose (they say nothing about *where* on the arc the echo came
from); since this measure its confidence has a ``repeated`` feature
(:mod:`sonarcarve.geometry.repeats`: the same test against the sensor's other echoes in the
history, origins more than 2ε apart), so the fates below are those of the refitted default.

For each world and physics model (seeds 0-2, evidence carving with its defaults) this prints how
many echoes of each fate there are and the share of them with such a repeat (another echo of the
same sensor within ``--window`` seconds, its origin at least ``--min-travel`` away, ``ε`` =
``--tolerance``): direct echoes lost (not in the global map), direct kept, spurious kept,
spurious removed. A repeat that is common among lost direct echoes and rare among spurious
ones is a candidate feature of the confidence model (measured before the feature: spurious
0-4 %, lost direct 19-33 %; the refit and the ablation are ``benchmarks/fit_confidence.py`` and
``benchmarks/evidence.py``).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.sonar import EchoKind

PAIRS = (("doorway", "amplitude"), ("t-junction", "specular"), ("office", "specular"),
         ("office", "amplitude"))
FATES = ("direct lost", "direct kept", "spurious kept", "spurious removed")


def _inside_beam(px: float, py: float, rd: ReadingBatch, k: int, width: float) -> bool:
    bearing = math.atan2(py - rd.y[k], px - rd.x[k])
    off = (bearing - rd.theta[k] + math.pi) % (2.0 * math.pi) - math.pi
    return abs(off) <= width / 2.0


def _tangent_point(rd: ReadingBatch, i: int, j: int, tolerance: float,
                   min_travel: float) -> tuple[float, float] | None:
    """Where echoes ``i`` (older) and ``j`` of one sensor both come from if their circles are
    internally tangent, else None."""
    dx, dy = rd.x[j] - rd.x[i], rd.y[j] - rd.y[i]
    travel = math.hypot(dx, dy)
    ri, rj = rd.range[i], rd.range[j]
    if travel < min_travel or abs(travel - abs(ri - rj)) > tolerance:
        return None
    if ri > rj:  # drove towards it: ahead of j on the line from i through j
        return rd.x[i] + ri * dx / travel, rd.y[i] + ri * dy / travel
    return rd.x[j] - rj * dx / travel, rd.y[j] - rj * dy / travel  # drove away: behind


def has_repeat(rd: ReadingBatch, window: float, tolerance: float,
               min_travel: float) -> npt.NDArray[np.bool_]:
    """Per reading: True if it and another echo of its sensor are a tangent repeat."""
    width = np.where(np.isnan(rd.beam_width), math.radians(22.5), rd.beam_width)
    echo = np.isfinite(rd.range)
    found = np.zeros(len(rd), dtype=bool)
    for sensor in np.unique(rd.sensor):
        rows = np.flatnonzero((rd.sensor == sensor) & echo)
        for a, i in enumerate(rows):
            for j in rows[a + 1:]:
                if rd.t[j] - rd.t[i] > window:
                    break
                point = _tangent_point(rd, i, j, tolerance, min_travel)
                if point is not None and all(_inside_beam(*point, rd, q, width[q])
                                             for q in (i, j)):
                    found[i] = found[j] = True
    return found


def _fates(world: str, physics: str, seed: int, args: argparse.Namespace
           ) -> list[tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]]:
    overrides = () if physics == "specular" else (("echo_model", physics),)
    sim = run_simulation(Scenario(world, seed, physics=overrides))  # type: ignore[arg-type]
    result = process_readings(sim.readings, make_method("evidence"))
    kept = np.zeros(len(sim.readings), dtype=bool)
    kept[result.global_map.reading_id] = True
    direct = sim.truth.kind == EchoKind.DIRECT
    repeat = has_repeat(sim.readings, args.window, args.tolerance, args.min_travel)
    masks = (direct & ~kept, direct & kept, ~direct & kept, ~direct & ~kept)
    return [(mask, repeat) for mask in masks]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--window", type=float, default=6.0, help="seconds (default 6)")
    parser.add_argument("--tolerance", type=float, default=0.05, help="ε, metres (0.05)")
    parser.add_argument("--min-travel", type=float, default=0.15, help="metres (0.15)")
    args = parser.parse_args(argv)
    print(f"\nevidence carving's echoes by fate, seeds 0-{args.seeds - 1}: count "
          "(share with a tangent repeat)\n")
    print("| world | physics | " + " | ".join(FATES) + " |")
    print("|---|---|" + "---:|" * len(FATES))
    for world, physics in PAIRS:
        runs = [_fates(world, physics, seed, args) for seed in range(args.seeds)]
        cells = []
        for f in range(len(FATES)):
            mask = np.concatenate([run[f][0] for run in runs])
            repeat = np.concatenate([run[f][1] for run in runs])
            share = f" ({100.0 * float(repeat[mask].mean()):.0f} %)" if mask.any() else ""
            cells.append(f"{int(mask.sum()):,}{share}")
        print(f"| {world} | {physics} | " + " | ".join(cells) + " |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
