"""How fast `sonarcarve.sim.simulate` runs: firings per second on the office tour.

For each built-in robot: the office world's built-in tour (261 m, about 690 s at the default
speed) is simulated with the default sonar physics, or with the echo model ``--physics``
names (``specular`` or ``amplitude``, both: ``all``); prints the best of ``--repeats``
wall-clock times, the firings, the readings, the echo kinds and the share of firings that
heard nothing as a markdown table.

    .venv/bin/python benchmarks/simulate_speed.py [--world office] [--repeats 3]
        [--physics specular|amplitude|all]
"""

from __future__ import annotations

import argparse
import time

from sonarcarve.robot import BUILTIN_ROBOTS, load_robot
from sonarcarve.sim import ECHO_MODELS, SonarPhysics, simulate
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.world import load_world


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--world", default="office")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--physics", choices=[*ECHO_MODELS, "all"], default="specular")
    args = parser.parse_args()
    models = ECHO_MODELS if args.physics == "all" else (args.physics,)
    world = load_world(args.world)
    if world.tour is None:
        parser.error(f"world {args.world!r} has no tour")
    trajectory = follow_waypoints(world.tour)
    print(f"world {world.name}: {len(world)} walls; tour {trajectory.path_length:.0f} m, "
          f"{trajectory.duration:.0f} s\n")
    print("| physics | robot | firings | readings | best time (s) | firings/s | direct "
          "| crosstalk | floor | multipath | no echo |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for model in models:
        physics = SonarPhysics(echo_model=model)
        for name in BUILTIN_ROBOTS:
            robot = load_robot(name)
            best = float("inf")
            for _ in range(args.repeats):
                start = time.perf_counter()
                sim = simulate(world, robot, trajectory, seed=1, physics=physics)
                best = min(best, time.perf_counter() - start)
            kinds = sim.kind_counts()
            silent = 1.0 - len(sim.readings) / len(sim.firings)
            print(f"| {model} | {name} | {len(sim.firings):,} | {len(sim.readings):,} | "
                  f"{best:.2f} | {len(sim.firings) / best:,.0f} | {kinds['direct']:,} | "
                  f"{kinds['crosstalk']:,} | {kinds['floor']:,} | {kinds['multipath']:,} | "
                  f"{silent:.1%} |")

if __name__ == "__main__":
    main()
