"""How ATM's minimum transversal angle ψ trades accuracy for latency, on a synthetic log.

Several logs (seeds) of a robot with a ring of 16 sonars (22.5° beams, radius 0.2 m) driving
a loop through a corridor world with a T junction and two pillars. A firing's echo is the
nearest wall over 31 rays spread across the beam (no specular loss), plus Gaussian range noise,
quantised to one inch.
For each ψ the logs are run through ATM (and, for comparison, the combined carving+ATM
method) and the script prints a markdown table, errors pooled over all logs:

* ``ATM pts``: share of ATM's global map placed by ATM (the rest fell back to centerline);
* ``ATM err p50 / p90``: median and 90th percentile distance of those points to the nearest
  wall, metres;
* ``all err p50``: median over every point of ATM's global map (fallbacks included);
* ``unproc.``: mean share of the history with no kept crossing (Table I's measure);
* ``bound``: ATM's error bound δ(1/sin ψ + 1/tan ψ) (eq. 5.4 times δ), metres;
* ``comb. err p50 / p90`` and ``comb. unproc.``: the same for carving+ATM (ε = 0.025 m).

Run: ``.venv/bin/python benchmarks/min_transversal.py`` (under 10 s on one core).
"""

from __future__ import annotations

import argparse
import itertools
import math

import numpy as np

from sonarcarve.maps import GlobalMap, PointSource
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.world import World

INCH = 0.0254
PHI = math.radians(22.5)

#: A corridor 2 m wide running east, with a branch north at x = 10-12 m, and two pillars.
WALLS = np.array([
    [0.0, 0.0, 20.0, 0.0],  # south wall
    [20.0, 0.0, 20.0, 2.0],  # east end
    [0.0, 2.0, 10.0, 2.0],  # north wall, west of the branch
    [12.0, 2.0, 20.0, 2.0],  # north wall, east of the branch
    [10.0, 2.0, 10.0, 10.0],  # branch, west wall
    [12.0, 2.0, 12.0, 10.0],  # branch, east wall
    [10.0, 10.0, 12.0, 10.0],  # branch end
    [0.0, 0.0, 0.0, 2.0],  # west end
    [5.0, 0.6, 5.3, 0.6], [5.3, 0.6, 5.3, 0.9], [5.3, 0.9, 5.0, 0.9], [5.0, 0.9, 5.0, 0.6],
    [15.0, 1.2, 15.3, 1.2], [15.3, 1.2, 15.3, 1.5], [15.3, 1.5, 15.0, 1.5], [15.0, 1.5, 15.0, 1.2],
])

#: The robot's route: east along the corridor, up the branch and back, on to the east end.
ROUTE = np.array([[1.0, 1.3], [11.0, 1.3], [11.0, 8.5], [11.0, 1.0], [19.0, 1.0]])


def simulate(seed: int, noise: float, step: float, max_range: float) -> tuple[World, ReadingBatch]:
    """Fire the 16 sensors in turn while driving ``ROUTE``, ``step`` metres per firing."""
    world = World(WALLS, "corridor-T")
    rng = np.random.default_rng(seed)
    poses = []
    for start, end in itertools.pairwise(ROUTE):
        heading = math.atan2(end[1] - start[1], end[0] - start[0])
        n = int(np.linalg.norm(end - start) / step)
        for k in range(n):
            poses.append((*(start + (end - start) * k / n), heading))
    pose = np.array(poses)
    sensor = np.arange(len(pose)) % 16
    theta = pose[:, 2] + sensor * 2.0 * math.pi / 16
    origin = pose[:, :2] + 0.2 * np.column_stack((np.cos(theta), np.sin(theta)))
    fan = np.linspace(-PHI / 2, PHI / 2, 31)
    rays = (theta[:, None] + fan[None, :]).ravel()
    distance, _ = world.cast_rays(np.repeat(origin, fan.size, axis=0), rays, max_range)
    r = distance.reshape(-1, fan.size).min(axis=1)
    r = np.round((r + rng.normal(0.0, noise, r.shape)) / INCH) * INCH
    echo = np.isfinite(r) & (r > 0.1) & (r < max_range)
    batch = ReadingBatch.from_arrays(
        t=np.arange(len(pose))[echo] * 0.04, sensor=sensor[echo], x=origin[echo, 0],
        y=origin[echo, 1], theta=theta[echo], range=r[echo], beam_width=np.full(echo.sum(), PHI),
    )
    return world, batch


def _errors(world: World, points: GlobalMap) -> np.ndarray:
    return world.distance_to_walls(points.xy)


def _pct(errors: list[np.ndarray], q: float) -> float:
    pooled = np.concatenate(errors)
    return float(np.percentile(pooled, q)) if pooled.size else math.nan


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5, help="number of logs (seeds 0..n-1)")
    parser.add_argument("--noise", type=float, default=0.01, help="range noise σ, metres")
    parser.add_argument("--step", type=float, default=0.012, help="travel per firing, metres")
    parser.add_argument("--history", type=int, default=250)
    parser.add_argument("--max-range", type=float, default=6.0)
    parser.add_argument("--psi", type=float, nargs="+", default=[10.0, 20.0, 30.0, 45.0],
                        help="ψ values, degrees")
    args = parser.parse_args()
    logs = [simulate(seed, args.noise, args.step, args.max_range) for seed in range(args.seeds)]
    print(f"{args.seeds} logs, {sum(len(b) for _, b in logs)} readings, history {args.history}, "
          f"noise {args.noise} m, step {args.step} m/firing\n")
    print("| ψ (°) | ATM pts | ATM err p50 | ATM err p90 | all err p50 | unproc. | bound "
          "| comb. err p50 | comb. err p90 | comb. unproc. |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for psi_deg in args.psi:
        config = MethodConfig(history_size=args.history, beam_width=PHI,
                              min_transversal=math.radians(psi_deg), range_resolution=INCH,
                              range_tolerance=0.025)
        placed, every, combined = [], [], []
        shares, shares_combined, n_points = [], [], 0
        for world, batch in logs:
            atm = process_readings(batch, make_method("atm", config))
            both = process_readings(batch, make_method("combined", config))
            is_atm = atm.global_map.source == PointSource.ATM
            placed.append(_errors(world, atm.global_map.select(is_atm)))
            every.append(_errors(world, atm.global_map))
            combined.append(_errors(world, both.global_map))
            shares.append(atm.mean_unprocessed_share)
            shares_combined.append(both.mean_unprocessed_share)
            n_points += len(atm.global_map)
        psi = config.min_transversal
        bound = INCH * (1.0 / math.sin(psi) + 1.0 / math.tan(psi))
        print(f"| {psi_deg:g} | {sum(map(len, placed)) / n_points:.1%} "
              f"| {_pct(placed, 50):.3f} | {_pct(placed, 90):.3f} | {_pct(every, 50):.3f} "
              f"| {np.mean(shares):.1%} | {bound:.3f} "
              f"| {_pct(combined, 50):.3f} | {_pct(combined, 90):.3f} "
              f"| {np.mean(shares_combined):.1%} |")
    centerline = [
        _errors(world, process_readings(batch, make_method(
            "centerline", MethodConfig(args.history))).global_map)
        for world, batch in logs
    ]
    print(f"\ncenterline: err p50 {_pct(centerline, 50):.3f} m, p90 {_pct(centerline, 90):.3f} m")


if __name__ == "__main__":
    main()
