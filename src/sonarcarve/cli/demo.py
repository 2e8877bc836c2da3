"""``sonarcarve demo``: simulate a tour, map it with every method and two occupancy grids, print
the tables, write figures and the grids."""

from __future__ import annotations

import time
from typing import Annotated

import typer
from rich import box
from rich.progress import TaskID
from rich.table import Table
from rich.text import Text

from sonarcarve.cli.app import app, console, flag_message, progress
from sonarcarve.cli.drawing import draw_offscreen
from sonarcarve.errors import ConfigError
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.io.atomic import check_output_dir
from sonarcarve.lab.demo import (
    APPROACH_DISTANCE,
    GRID_RESOLUTION,
    METHOD_COLORS,
    TABLE_COLUMNS,
    DemoResult,
    caption,
    demo_config,
    door_note,
    grid_caption,
    grid_table_rows,
    load_demo_world,
    method_verdict,
    output_captions,
    run_demo,
    table_rows,
    write_demo_outputs,
)
from sonarcarve.lab.grid_measures import NEAR_PATH

__all__ = ["demo"]

#: Progress labels of the steps.
_STEPS = {"simulate": "simulating the tour", "centerline": "centerline", "atm": "ATM",
          "carve": "arc carving", "combined": "carving + ATM", "evidence": "evidence carving",
          "grid:carved": "carved grid", "grid:range-sensor-layer": "ROS range layer",
          "door scene": "Fig. 2's doorway"}


@app.command(help=(
    "Simulate a robot touring a building, map its sonar readings with every method, and "
    "compare the maps with the true walls.\n\n"
    "A Scout2-like robot (16 sonars, 22.5° beams) drives the world's built-in tour; its "
    "readings include spurious echoes (crosstalk, floor, multipath) as real sonars do. "
    "Centerline, ATM, arc carving, carving + ATM (combined) and evidence carving (beyond "
    "the paper) each map the same readings with a history of --history arcs. The table has "
    "one row per method:\n\n"
    "- **unprocessed %**: mean share of the history still waiting for another reading to "
    "sharpen it (the paper's Table I: latency; centerline is always 0).\n"
    "- **median / p90 error cm**: distance of the final map's points to the true walls "
    "(50th and 90th percentile; lower is better).\n"
    "- **fully carved %**: readings whose whole arc newer readings showed to be free space.\n"
    "- **spurious removed %**: of the spurious readings, the share left out of the map "
    "(carving removed them); **true lost %**: the same for true wall echoes.\n"
    "- **map points**: points in the final map; **readings per s**: processing speed.\n\n"
    f"A second table compares two occupancy grids of {GRID_RESOLUTION:g} m cells built from "
    "the same readings: the carved grid and ROS's RangeSensorLayer (its defaults). "
    "**occupied precision**: share of occupied cells on a true wall (within one cell); "
    "**recall**: share of the walls the sonars saw that are marked; **phantom %**: free "
    "space marked occupied; **free near path %**: the truly free floor within "
    f"{NEAR_PATH:g} m of the robot's path marked free, where a planner may drive; **CPU µs per "
    "reading**: processor time.\n\n"
    "Writes into --out: fig1-global-maps.png (each method's map over the true walls), "
    "fig2-global-maps-zoom.png (a close-up of the same maps), fig3-error-vs-range.png "
    "(error against the reading's range), fig4-door-local-maps.png (what the robot's local "
    f"map shows {APPROACH_DISTANCE:g} m before a door; when every door of the tour stays open "
    "in every local map, as on the office tour, the 0.85 m door of the paper's Fig. 2 from a "
    "short drive in the doorway world), approach.gif (the same, animated), "
    "fig5-occupancy-grids.png (both grids over the true walls), fig6-kept-and-lost.png "
    "(paper carving beside evidence carving: which true and spurious echoes each kept, and "
    "the true echoes each deleted), carved-grid.yaml/.pgm and "
    "range-sensor-layer.yaml/.pgm (the grids as ROS map_server maps), summary.md and "
    "summary.json. Takes about 20 s for the office tour on 2 cores (longer on a loaded "
    "machine, and the first time, while numba compiles).\n\n"
    "Example: `sonarcarve demo --world t-junction --seed 3 --out /tmp/demo`"
))
def demo(
    world: Annotated[str, typer.Option(
        "--world", "-w", metavar="WORLD",
        help="Built-in world (office, doorway, t-junction, narrow-hallway), random:SEED, or "
             "a walls .json / ROS map .yaml file; it must have a tour.")] = "office",
    seed: Annotated[int, typer.Option(
        help="Seeds the simulated noise and spurious echoes: same seed, same numbers.")] = 0,
    out: Annotated[str, typer.Option(
        "--out", "-o", metavar="FOLDER",
        help="Folder for the figures, the grid maps, summary.md and summary.json (created "
             "with its missing parents; files of the same names are replaced).")] = "demo-output",
    history: Annotated[int, typer.Option(
        metavar="ARCS", help="Arcs kept in each method's history (paper: 250).")
    ] = DEFAULT_HISTORY_SIZE,
) -> None:
    """Simulate a tour; compare the methods' maps, and the carved grid with ROS's layer."""
    # Every bad option fails here, in one line, before a progress bar or a file appears.
    folder = check_output_dir(out, label=f"--out {out}")  # a str: "" is not "."
    try:
        demo_config(history)
    except ConfigError as err:
        raise ConfigError(flag_message(str(err), {"history_size": "--history"})) from None
    the_world = load_demo_world(world)
    draw_offscreen()
    tic = time.perf_counter()
    with progress(label_width=20, elapsed=True) as bar:
        tasks: dict[str, TaskID] = {}

        def on_progress(step: str, done: int, total: int) -> None:
            if step not in tasks:
                tasks[step] = bar.add_task(_STEPS.get(step, step), total=total)
            bar.update(tasks[step], completed=done, total=total)

        result = run_demo(the_world, seed, history_size=history, on_progress=on_progress)
        figures = bar.add_task("drawing figures", total=None)
        written = write_demo_outputs(result, folder, animation=True)
        bar.update(figures, total=1, completed=1)
    console.print(_table(result))
    console.print()
    verdict = method_verdict(result)
    if verdict:  # the answer first, then how to read the table
        console.print(Text(verdict, style="bold"), width=min(console.width, 110))
        console.print()
    console.print(Text(caption(result)), width=min(console.width, 110))
    if result.grids:
        console.print()
        console.print(_grid_table(result))
        console.print()
        console.print(Text(grid_caption(result)), width=min(console.width, 110))
    note = door_note(result)
    if note:
        console.print()
        console.print(Text(note), width=min(console.width, 110))
    console.print()
    console.print(f"[bold]Wrote {len(written)} files to {out}/[/bold], look at them in order:")
    for name, text in output_captions(result, animation=True):
        console.print(f"  {name:<28} {text}", highlight=False)
    console.print(f"[dim]done in {time.perf_counter() - tic:.1f} s (simulation "
                  f"{result.seconds['simulate']:.1f} s).[/dim]")


def _table(result: DemoResult) -> Table:
    header, rows = table_rows(result)
    sim = result.simulation
    # Compact enough for an 80-column terminal: no vertical rules, one space between columns,
    # and the readings column (the same number in every row) moved into the title, which
    # leaves room for "evidence carving / (beyond the paper)" on two lines.
    keep = [k for k, (key, _, _) in enumerate(TABLE_COLUMNS) if key != "readings"]
    table = Table(title=f"sonarcarve demo: '{result.world.name}' tour, "
                        f"{sim.trajectory.path_length:.0f} m, {len(sim.readings):,} readings, "
                        f"seed {result.seed}, history {result.config.history_size}",
                  header_style="bold", title_style="bold", box=box.SIMPLE_HEAD,
                  show_edge=False, padding=0)
    for k in keep:
        table.add_column(header[k], justify="left" if k == 0 else "right", no_wrap=True)
    for row, cells in zip(result.methods, rows, strict=True):
        color = METHOD_COLORS.get(row.method)
        label = cells[0].replace(" (", "\n(")
        shown = [cells[k] for k in keep]
        table.add_row(f"[{color}]{label}[/]" if color else label, *shown[1:])
    return table


def _grid_table(result: DemoResult) -> Table:
    header, rows = grid_table_rows(result)
    grids = result.grids
    table = Table(title=f"occupancy grids of the same readings, {grids[0].resolution:.2f} m "
                        "cells, against the true walls",
                  header_style="bold", title_style="bold", box=box.SIMPLE_HEAD,
                  show_edge=False, padding=(0, 1, 0, 0))
    for k, name in enumerate(header):
        table.add_column(name, justify="left" if k == 0 else "right", no_wrap=True)
    for cells in rows:
        table.add_row(*cells)
    return table

