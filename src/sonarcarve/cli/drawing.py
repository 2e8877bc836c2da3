"""The matplotlib backend of the commands that draw: Agg, chosen here and not by the library.

:mod:`sonarcarve.plotting` and the lab leave the backend to their caller (a notebook keeps its
inline one). The commands write figures to files, never show a window and must run without a
display, so each command that draws calls :func:`draw_offscreen` before it does. Kept out of
:mod:`sonarcarve.cli.app`, whose imports the CLI's cold start keeps to the standard library,
typer and rich.
"""

from __future__ import annotations

__all__ = ["draw_offscreen"]


def draw_offscreen() -> None:
    """Draw with matplotlib's Agg backend: figures to files, no window, no display needed."""
    import matplotlib

    matplotlib.use("Agg")
