"""``sonarcarve worlds``: list the built-in simulator worlds, describe or convert any world."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich import box
from rich.table import Table

from sonarcarve.cli.app import app, console
from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import check_output_file
from sonarcarve.sim.world import World, builtin_worlds, load_world, write_world_json

__all__ = ["worlds"]

#: The seed whose numbers stand for ``random:SEED`` in the listing.
_EXAMPLE_SEED = 0


class WorldsUsageError(SonarcarveError):
    """``--out`` given with other than exactly one world."""


@app.command()
def worlds(
    specs: Annotated[list[str] | None, typer.Argument(
        metavar="WORLD",
        help="Worlds to describe: built-in names, random:SEED[:WIDTHxHEIGHT], world .json files "
             "or ROS map .yaml files. Default: every built-in world.",
        show_default=False)] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", metavar="WORLD.json",
        help="Write the one world given as world JSON (walls, tour, openings), e.g. to convert "
             "a ROS map or to freeze a random world.")] = None,
) -> None:
    """List the simulator's worlds: size, walls, area, gaps (doors, openings), tour length.

    Without arguments, lists the built-in worlds (the paper's Fig. 2, 4, 7 and 9 scenes and
    the seeded random floors). With arguments, describes those worlds instead.

    Examples:

    - `sonarcarve worlds`: the built-in worlds.
    - `sonarcarve worlds random:7:40x30 my_map.yaml`: a seeded random floor and a ROS map.
    - `sonarcarve worlds my_map.yaml --out my_map.json`: convert a ROS map to world JSON.
    """
    if out is not None and len(specs or []) != 1:
        msg = "--out needs exactly one world, e.g. `sonarcarve worlds map.yaml --out map.json`"
        raise WorldsUsageError(msg)
    if out is not None:
        source = Path((specs or [""])[0])
        check_output_file(out, inputs=[source] if source.is_file() else [],
                          label=f"--out {out}")
    rows: list[tuple[str, World, str | None]]
    if specs:
        rows = [(spec, load_world(spec), None) for spec in specs]
    else:
        rows = [(name, _example(name), description)
                for name, description in builtin_worlds().items()]
    table = Table(title="sonarcarve worlds", box=box.SIMPLE_HEAD, pad_edge=False)
    table.add_column("name", style="bold", no_wrap=True)
    table.add_column("size m", justify="right", no_wrap=True)
    table.add_column("walls", justify="right", no_wrap=True)
    table.add_column("area m²", justify="right", no_wrap=True)
    table.add_column("gaps", justify="right", no_wrap=True)
    table.add_column("tour m", justify="right", no_wrap=True)
    table.add_column("description", ratio=1)
    for name, world, description in rows:
        width, height = world.size
        text = description if description is not None else world.description
        if name.startswith("random:SEED"):
            text = f"{text} (numbers shown: seed {_EXAMPLE_SEED})"
        table.add_row(name, f"{width:g} x {height:g}", f"{len(world):,}", f"{world.area:,.0f}",
                      f"{world.openings.shape[0]:,}",
                      f"{world.tour_length:,.0f}" if world.tour is not None else "-", text)
    console.print(table)
    if out is not None:
        write_world_json(rows[0][1], out)
        console.print(f"world written to {out}")


def _example(name: str) -> World:
    return load_world(f"random:{_EXAMPLE_SEED}" if name == "random:SEED" else name)
