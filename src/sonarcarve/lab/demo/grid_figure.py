"""Fig. 5 of the demo: the carved grid beside ROS's range sensor layer over the true walls.

Both grids were built from the same readings (:mod:`~sonarcarve.lab.demo.costmaps`); each is
drawn as the trinary map a robot's planner would read (black occupied, white free, grey
unknown) with the true walls on top, the whole building above and fig. 2's close-up window
below. :func:`grid_verdict` says in words which grid is better and by how much; the figure's
title and the printed caption use it.

matplotlib is imported inside the functions (Agg backend); the figure is returned and the
caller closes it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from sonarcarve.lab.demo.figures import map_limits, zoom_window
from sonarcarve.lab.demo.results import DemoResult, GridSummary
from sonarcarve.lab.grid_measures import NEAR_PATH, GridMeasures
from sonarcarve.plotting import TRINARY_COLORS, new_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["GRID_FIGURE_FILE", "GRID_FIGURE_TEXT", "free_verdict", "grid_verdict",
           "plot_occupancy_grids"]

#: The figure's file name in the demo's output folder.
GRID_FIGURE_FILE = "fig5-occupancy-grids.png"
#: What it shows, in a few words (printed by the CLI, listed in ``summary.md``).
GRID_FIGURE_TEXT = "carved grid beside ROS's layer, over true walls"
_WALL_COLOR = "#e8000b"
#: The close-up row is drawn only when fig. 2's window is smaller than this share of the map.
_CLOSEUP_SHARE = 0.3
#: Space between rows of panels and below the figure's title, inches (constrained layout's
#: ``h_pad``; its default, 3 points, let the upper panels' "x (m)" touch the close-ups' titles
#: and the two-line figure title touch the panel titles).
_ROW_PAD = 0.12
#: What the numbers in the panel titles mean (the legend's title).
_MEASURES_TEXT = ("precision: share of the occupied cells within one cell of a true wall; "
                  "recall: share of the walls the sonars saw that have an occupied cell;\n"
                  "phantoms: share of the truly free cells marked occupied; free: share of the "
                  f"truly free floor within {NEAR_PATH:g} m of the path marked free")


def _compare(ours: float, theirs: float, better: str, worse: str, same: str) -> tuple[str, int]:
    """The phrase for one measure (higher is better) and its sign: +1 ours better, -1 worse.

    Compared as shown, to two decimals, so that the words agree with the numbers beside them.
    """
    a, b = round(ours, 2), round(theirs, 2)
    if a > b:
        return better, 1
    if a < b:
        return worse, -1
    return same, 0


def _carved_and_layer(result: DemoResult) -> tuple[GridMeasures, GridMeasures] | None:
    """The measures of the carved grid and of ROS's layer; None unless the run built both."""
    kinds = {g.kind for g in result.grids}
    if not {"carved", "range-sensor-layer"} <= kinds:
        return None
    return result.grid("carved").measures, result.grid("range-sensor-layer").measures


def grid_verdict(result: DemoResult) -> str:
    """Which grid is better, in one sentence with the numbers; empty without both grids.

    Precision (the share of occupied cells on a true wall) and recall (the share of the seen
    walls marked) decide, compared to two decimals as the table shows them.

    Examples: "the carved grid is better: it is more precise (precision 0.83 against 0.67)
    and finds as much of the walls (recall 0.95 against 0.95)".
    """
    both = _carved_and_layer(result)
    if both is None:
        return ""
    ours, theirs = both
    if np.isnan([ours.precision, ours.recall, theirs.precision, theirs.recall]).any():
        return "the grids cannot be compared: one marks no cell occupied or saw no wall"
    precise, p = _compare(ours.precision, theirs.precision, "more precise", "less precise",
                          "as precise")
    finds, r = _compare(ours.recall, theirs.recall, "finds more of the walls",
                        "finds less of the walls", "finds as much of the walls")
    if p >= 0 and r >= 0 and p + r > 0:
        lead, join = "the carved grid is better: it is", "and"
    elif p <= 0 and r <= 0 and p + r < 0:
        lead, join = "ROS's layer is better: the carved grid is", "and"
    elif p == r == 0:
        lead, join = "the two grids are as good: the carved grid is", "and"
    else:
        lead, join = "neither grid is better on both: the carved grid is", "but"
    return (f"{lead} {precise} (precision {ours.precision:.2f} against "
            f"{theirs.precision:.2f}) {join} {finds} (recall {ours.recall:.2f} against "
            f"{theirs.recall:.2f})")


def free_verdict(result: DemoResult) -> str:
    """Which grid leaves more of the floor near the robot's path free, in one sentence with the
    numbers (whole percent, as compared); empty without both grids or the measure.

    Examples: "ROS's layer marks more of the floor near the path free (97 against 94 %)".
    """
    both = _carved_and_layer(result)
    if both is None:
        return ""
    ours, theirs = (100.0 * m.free_near_path for m in both)
    if np.isnan([ours, theirs]).any():
        return ""
    a, b = round(ours), round(theirs)
    who = ("the carved grid marks more of" if a > b else "ROS's layer marks more of" if a < b
           else "both grids mark as much of")
    first, second = (a, b) if a >= b else (b, a)
    return f"{who} the floor near the path free ({first} against {second} %)"


def plot_occupancy_grids(result: DemoResult) -> Figure:
    """Fig. 5: each grid's trinary map over the true walls; whole map above, and below, fig.
    2's close-up window (left out when that window shows most of the map anyway).

    Returns an empty figure with a note if the run built no grids.
    """
    grids = result.grids
    cols = max(1, len(grids))
    limits = map_limits(result)
    box = zoom_window(result)
    rows = 2 if _area(box) < _CLOSEUP_SHARE * _area(limits) else 1
    aspects = [(lim[3] - lim[2]) / max(lim[1] - lim[0], 1e-9) for lim in (limits, box)[:rows]]
    width = 13.0 if cols == 2 else 7.0
    fig, axes = new_figure(rows, cols, width=width,
                           height=min(16.0, 1.6 + rows * 3 * _ROW_PAD
                                      + width / cols * sum(aspects)))
    _pad_rows(fig)
    if not grids:
        axes[0, 0].text(0.5, 0.5, "no grids in this run", ha="center", va="center")
        for ax in axes.flat:
            ax.axis("off")
        return fig
    for k, grid in enumerate(grids):
        m = grid.measures
        _grid_panel(axes[0, k], result, grid, limits, linewidth=0.5,
                    box=box if rows == 2 else None)
        axes[0, k].set_title(f"{grid.label}\nprecision {m.precision:.2f}, recall "
                             f"{m.recall:.2f}, phantoms {100.0 * m.phantoms:.2f} %, free "
                             f"{100.0 * m.free_near_path:.0f} %", fontsize=11)
        if rows == 2:
            _grid_panel(axes[1, k], result, grid, box, linewidth=1.0)
            axes[1, k].set_title(f"{grid.label}, close-up (dashed box above; fig. 2's window)",
                                 fontsize=10)
    for ax in axes[:, 0]:
        ax.set_ylabel("y (m)")
    for ax in axes.flat:
        ax.set_xlabel("x (m)")
    # Below the panels, so that it hides no cell; its title says what the numbers mean.
    fig.legend(handles=_legend_handles(), loc="outside lower center", ncol=4, fontsize=10,
               title=_MEASURES_TEXT, title_fontsize=9, frameon=False)
    verdict = grid_verdict(result)
    fig.suptitle(
        f"Occupancy grids from the same {len(result.simulation.readings):,} readings "
        f"('{result.world.name}' tour, {grids[0].resolution:.2f} m cells), as a robot's planner "
        "reads them" + (f":\n{verdict}" if verdict else ""), fontsize=12)
    return fig


def _pad_rows(fig: Figure) -> None:
    """Leave :data:`_ROW_PAD` between the rows of panels and below the figure's title."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    engine = fig.get_layout_engine()
    if isinstance(engine, ConstrainedLayoutEngine):
        engine.set(h_pad=_ROW_PAD)


def _area(limits: tuple[float, float, float, float]) -> float:
    """Area of ``(xmin, xmax, ymin, ymax)``, square metres."""
    return (limits[1] - limits[0]) * (limits[3] - limits[2])


def _grid_panel(ax: Axes, result: DemoResult, grid: GridSummary,
                limits: tuple[float, float, float, float], linewidth: float,
                box: tuple[float, float, float, float] | None = None) -> None:
    """One grid's trinary cells with the true walls on top, inside ``limits``."""
    from matplotlib.patches import Rectangle

    from sonarcarve.plotting import plot_trinary, plot_walls

    plot_trinary(grid.cells, grid.extent, ax, zorder=1)
    plot_walls(result.world.segments, ax, colors=_WALL_COLOR, linewidths=linewidth,
               alpha=0.8, zorder=3)
    if box is not None:
        ax.add_patch(Rectangle((box[0], box[2]), box[1] - box[0], box[3] - box[2],
                               fill=False, ls="--", lw=1.2, color="#1f77b4", zorder=4))
    ax.set_xlim(limits[0], limits[1])
    ax.set_ylim(limits[2], limits[3])
    ax.set_aspect("equal")


def _legend_handles() -> list[object]:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    free, unknown, occupied = TRINARY_COLORS
    return [Patch(facecolor=occupied, edgecolor="k", label="occupied"),
            Patch(facecolor=free, edgecolor="k", label="free"),
            Patch(facecolor=unknown, edgecolor="k", label="unknown"),
            Line2D([], [], color=_WALL_COLOR, lw=1.5, label="true walls")]
