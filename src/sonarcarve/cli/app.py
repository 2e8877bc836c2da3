"""The typer application every command module registers on."""

from __future__ import annotations

import typer
from rich.console import Console

__all__ = ["app", "console", "err_console"]

app = typer.Typer(
    name="sonarcarve",
    help=(
        "Accurate, low-latency maps from ultrasonic range sensors.\n\n"
        "Arc carving (Silver et al.) removes from each sonar arc the parts that newer readings "
        "prove to be free space, so the map point of an echo gets sharper with every reading "
        "instead of waiting for enough readings to intersect (ATM).\n\n"
        "Start with `sonarcarve demo`; map your own readings with `sonarcarve process`."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="markdown",
)

console = Console()
err_console = Console(stderr=True)


def _show_version(value: bool) -> None:
    if value:
        from sonarcarve import __version__

        console.print(f"sonarcarve {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_show_version, is_eager=True,
        help="Print the version and exit.",
    ),
) -> None:
    """Accurate, low-latency maps from ultrasonic range sensors."""
