"""Changing scenes: how fast each method and grid follows obstacles that appear, vanish, move.

Run from the repository root::

    .venv/bin/python benchmarks/changing_scenes.py     # tables, docs/figures/changing-scenes.png

Three scenes of :mod:`sonarcarve.sim.scene` (Scout2 ring, default physics, 0.4 m/s, seeds 0-2):
a person (0.4 m disc) crossing a corridor 3.2-4.2 m ahead of the robot at 1 m/s; a door that
shuts 4.8 m ahead of the approaching robot and opens when it is 2.4 m away; a box removed while
the robot is in a side room, driven past again on the way back. Every method's local map and
every grid's occupied cells (0.10 m, and 0.05 m with ``--resolutions 0.1 0.05``) are read every
0.2 s and measured as :mod:`sonarcarve.lab.changing_scenes` defines: seconds from each change
(or from when the robot could first see the place again) until the map is right again (gone:
no unexplained point within 0.25 m of where the obstacle was, for good; appeared: a point within
0.25 m of it away from the walls), and the phantom share over time.

By default the firings that heard nothing are recorded and fed too (range inf, free space up to
the robot's max range), as a real driver publishes them (ROS REP 117: +Inf), and the range
sensor layer with +Inf clearing (``inf_is_max_reading`` and ``clear_on_max_reading``) joins the
grids; the layer with ROS's defaults drops them. ``--echoes-only`` feeds the echoes alone (the
default before issue 10's clearing work; a log that drops silent firings)::

    .venv/bin/python benchmarks/changing_scenes.py --echoes-only --no-figure

``--no-echo`` is accepted and means the default. ``--physics amplitude`` simulates the second
sonar model (:mod:`sonarcarve.sim.amplitude`) instead of the default one::

    .venv/bin/python benchmarks/changing_scenes.py --physics amplitude --no-figure
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from sonarcarve.grids import CarvedGrid, CarvedGridParams
from sonarcarve.lab.changing_scenes import (
    GRID_KINDS,
    METHOD_NAMES,
    NO_ECHO_GRID_KINDS,
    SceneRun,
    plot_changing_scene,
    run_changing_scene,
)
from sonarcarve.lab.drawing import save_pngs
from sonarcarve.sim.sonar import DEFAULT_PHYSICS, SonarPhysics

SCENES = ("person", "door", "box")
FIGURE = Path("docs/figures/changing-scenes.png")
FIGURE_MAPS = ("carve", "carved grid", "range sensor layer", "elfes grid")
TARGET_SECONDS = 3.0


def _cell(values: Sequence[float]) -> str:
    """Mean over seeds, with the spread, and how many seeds never got right."""
    v = np.asarray(values, dtype=np.float64)
    done = v[np.isfinite(v)]
    never = v.size - done.size
    if done.size == 0:
        return "never"
    text = f"{done.mean():.1f}"
    if done.size > 1:
        text += f" ({done.min():.1f}-{done.max():.1f})"
    if never:
        text += f", never x{never}"
    return text


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.1])
    parser.add_argument("--figure", type=Path, default=FIGURE)
    parser.add_argument("--no-figure", action="store_true")
    echoes = parser.add_mutually_exclusive_group()
    echoes.add_argument("--no-echo", action="store_true",
                        help="also feed the firings that heard nothing (the default)")
    echoes.add_argument("--echoes-only", action="store_true",
                        help="feed only the firings that heard an echo")
    parser.add_argument("--physics", choices=("specular", "amplitude"), default="specular",
                        help="echo model simulated, as in the other benchmarks (default: "
                             "specular, the simulator's default physics)")
    parser.add_argument("--mark-length", type=float, default=None, metavar="M",
                        help="add a row for the carved grid whose newest echo's mark is M "
                             "metres long (CarvedGridParams.mark_length; 0: the point's cell)")
    args = parser.parse_args(argv)
    args.no_echo = not args.echoes_only
    physics = (DEFAULT_PHYSICS if args.physics == DEFAULT_PHYSICS.echo_model
               else SonarPhysics(echo_model=args.physics))
    seeds = range(args.seeds)
    if args.mark_length is not None:
        _add_mark_length_row(args.mark_length)
    grids = (*GRID_KINDS, *(NO_ECHO_GRID_KINDS if args.no_echo else ()))
    if args.no_echo:
        print("\nWith no-echo readings (every firing that heard nothing: free space up to the "
              "robot's max range).")
    else:
        print("\nEchoes only (the firings that heard nothing are not fed).")
    if args.physics != DEFAULT_PHYSICS.echo_model:
        print(f"Physics: {args.physics}.")
    for h_index, h in enumerate(args.resolutions):
        methods = METHOD_NAMES if h_index == 0 else ()
        runs = {name: [run_changing_scene(name, seed, h, methods=methods, grids=grids,
                                          no_echo=args.no_echo, physics=physics)
                       for seed in seeds]
                for name in SCENES}
        _print_tables(runs, h, seeds, with_methods=h_index == 0)
        if h_index == 0 and not args.no_figure:
            import matplotlib

            matplotlib.use("Agg")  # a script writing a PNG: no window, no display needed
            box = runs["box"][0]
            change = next(i for i, c in enumerate(box.changes) if c.label == "box gone")
            fig = plot_changing_scene(box, FIGURE_MAPS, change, after=TARGET_SECONDS)
            save_pngs({args.figure.name: fig}, args.figure.parent)
            print(f"\nwrote {args.figure}")
    return 0


def _add_mark_length_row(length: float) -> None:
    """Add a carved grid with ``CarvedGridParams(mark_length=length)`` to the grids every scene
    maps (this process's registry only)."""
    params = CarvedGridParams(mark_length=length)

    def make(resolution: float, bounds: tuple[float, float, float, float]) -> CarvedGrid:
        return CarvedGrid(resolution, bounds, params=params)

    GRID_KINDS[f"carved grid, mark_length {length:g}"] = make


def _print_tables(runs: dict[str, list[SceneRun]], h: float, seeds: range,
                  with_methods: bool) -> None:
    labels = [t.label for t in runs[SCENES[0]][0].tracks]
    columns = [(name, k, c.label) for name in SCENES
               for k, c in enumerate(runs[name][0].changes)]
    what = "methods (local map) and grids" if with_methods else "grids"
    print(f"\n### Changing scenes: {what} at {h:.2f} m, seeds 0-{len(seeds) - 1}\n")
    print("Seconds from the change (or from when the robot could first see the place again) "
          "until the map is right again: mean (min-max) over seeds; never: not by the end "
          "(gone) or while it was there (appeared).\n")
    print("| map | " + " | ".join(label for _, _, label in columns) + " |")
    print("|---|" + "---:|" * len(columns))
    for label in labels:
        cells = [_cell([r.track(label).latency[k] for r in runs[name]])
                 for name, k, _ in columns]
        print(f"| {label} | " + " | ".join(cells) + " |")

    print("\nReference times (seed 0): "
          + "; ".join(f"{c.label} at {c.t:.1f} s, counted from {c.t_ref:.1f} s"
                      for name in SCENES for c in runs[name][0].changes))

    print(f"\nTarget: the removed box cleared within {TARGET_SECONDS:g} s of the robot driving "
          "past it (closest approach on the way back). Seconds after passing, per seed "
          "(negative: cleared before passing):\n")
    print("| map | " + " | ".join(f"seed {s}" for s in seeds) + " | met |")
    print("|---|" + "---:|" * len(seeds) + "---|")
    for label in labels:
        after = []
        for run in runs["box"]:
            k = next(i for i, c in enumerate(run.changes) if c.label == "box gone")
            after.append(run.track(label).cleared_at[k] - run.changes[k].t_past)
        met = all(np.isfinite(a) and a <= TARGET_SECONDS for a in after)
        cells = ["never" if not np.isfinite(a) else f"{a:+.1f}" for a in after]
        print(f"| {label} | " + " | ".join(cells) + f" | {'yes' if met else 'no'} |")

    print("\nPhantom share (%): points or occupied cells farther than the tolerance (0.1 m for "
          "points, 1.5 cells for grids) from every wall and obstacle present at the time; mean "
          "over the 0.2 s snapshots (and over seeds).\n")
    print("| map | " + " | ".join(SCENES) + " |")
    print("|---|" + "---:|" * len(SCENES))
    for label in labels:
        cells = [f"{100.0 * np.nanmean([r.track(label).mean_phantom for r in runs[name]]):.1f}"
                 for name in SCENES]
        print(f"| {label} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    raise SystemExit(main())
