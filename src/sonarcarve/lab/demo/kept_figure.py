"""Fig. 6 of the demo: which echoes paper carving and evidence carving kept, by what the
simulator knows each echo was.

The table's "spurious removed" and "true lost" columns are two numbers; this figure shows
where they are. Each kept map point is drawn blue if its reading was a direct echo off a wall
and red if it was spurious (crosstalk, floor or multipath); each direct echo a method left out
of its map is drawn as an orange cross at its true reflection point, so that the walls a
method heard and then deleted show up as orange stretches of wall. Whole map above, fig. 2's
close-up window below, as fig. 5 does.

matplotlib is imported inside the functions (Agg backend); the figure is returned and the
caller closes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sonarcarve.lab.demo.figures import map_limits, zoom_window
from sonarcarve.lab.demo.results import DemoResult, MethodSummary
from sonarcarve.plotting import new_figure
from sonarcarve.sim.sonar import EchoKind

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from sonarcarve.typing import BoolArray, IntArray

__all__ = ["KEPT_FIGURE_FILE", "KEPT_FIGURE_TEXT", "KEPT_METHODS", "EchoFates", "echo_fates",
           "kept_rows", "plot_kept_and_lost"]

#: The figure's file name in the demo's output folder.
KEPT_FIGURE_FILE = "fig6-kept-and-lost.png"
#: What it shows, in a few words (printed by the CLI, listed in ``summary.md``).
KEPT_FIGURE_TEXT = "true and spurious echoes each carving kept"
#: The methods it compares, in panel order: the paper's carving and ours.
KEPT_METHODS = ("carve", "evidence")
_KEPT_COLOR, _SPURIOUS_COLOR, _LOST_COLOR = "#1f77b4", "#d62728", "#ff7f0e"
#: The close-up row is drawn only when fig. 2's window is smaller than this share of the map
#: (as in fig. 5).
_CLOSEUP_SHARE = 0.3


@dataclass(frozen=True)
class EchoFates:
    """What became of each echo in one method's global map.

    Attributes
    ----------
    direct_point, spurious_point : ndarray of bool, shape (points,)
        Map points whose reading was a direct echo, and a spurious one (crosstalk, floor,
        multipath). A no-echo reading is neither.
    lost_direct : ndarray of bool, shape (readings,)
        Direct echoes with no point in the map.
    """

    direct_point: BoolArray
    spurious_point: BoolArray
    lost_direct: BoolArray


def echo_fates(kind: IntArray, reading_id: IntArray) -> EchoFates:
    """Sort a map's points, and the readings it left out, by the truth's ``kind`` of each
    reading (:class:`~sonarcarve.sim.sonar.EchoKind` codes, one per reading; ``reading_id``:
    the row of each map point's reading)."""
    kind = np.asarray(kind)
    rid = np.asarray(reading_id, dtype=np.int64)
    kept = np.zeros(kind.shape[0], dtype=bool)
    kept[rid] = True
    direct = kind == EchoKind.DIRECT
    return EchoFates(direct_point=direct[rid], spurious_point=kind[rid] > EchoKind.DIRECT,
                     lost_direct=direct & ~kept)


def kept_rows(result: DemoResult) -> tuple[MethodSummary, ...]:
    """The rows of the methods fig. 6 compares, of those the run mapped with (none: no fig. 6)."""
    return tuple(row for row in result.methods if row.method in KEPT_METHODS)


def plot_kept_and_lost(result: DemoResult) -> Figure:
    """Fig. 6: paper carving beside evidence carving, each map point coloured by what the
    simulator knows its echo was, and each direct echo the method deleted marked where it
    truly reflected; whole map above, fig. 2's close-up window below.

    Returns a figure with a note instead if the run mapped with neither method.
    """
    methods = kept_rows(result)
    limits = map_limits(result)
    box = zoom_window(result)
    rows = 2 if _area(box) < _CLOSEUP_SHARE * _area(limits) else 1
    cols = max(1, len(methods))
    aspects = [(lim[3] - lim[2]) / max(lim[1] - lim[0], 1e-9) for lim in (limits, box)[:rows]]
    width = 13.0 if cols == 2 else 7.0
    fig, axes = new_figure(rows, cols, width=width,
                           height=min(16.0, 2.0 + width / cols * sum(aspects)))
    if not methods:
        axes[0, 0].text(0.5, 0.5, "neither carving nor evidence carving in this run",
                        ha="center", va="center")
        for ax in axes.flat:
            ax.axis("off")
        return fig
    span = max(limits[1] - limits[0], limits[3] - limits[2])
    whole_size = float(np.clip(60.0 / span, 0.8, 8.0))  # fig. 1's dots
    for k, row in enumerate(methods):
        _panel(axes[0, k], result, row.method, limits, whole_size)
        axes[0, k].set_title(f"{row.label}\nkeeps {100.0 - row.true_lost_pct:.0f} % of the "
                             f"true echoes, removes {row.spurious_removed_pct:.0f} % of the "
                             "spurious ones", fontsize=11)
        if rows == 2:
            _panel(axes[1, k], result, row.method, box, 6.0)
            axes[1, k].set_title(f"{row.label}, close-up (fig. 2's window)", fontsize=10)
    for ax in axes[:, 0]:
        ax.set_ylabel("y (m)")
    for ax in axes.flat:
        ax.set_xlabel("x (m)")
    fig.legend(handles=_legend_handles(), loc="outside lower center", ncol=4, fontsize=10,
               frameon=False)
    fig.suptitle(f"What each carving kept of the same {len(result.simulation.readings):,} "
                 f"readings ('{result.world.name}' tour), by what the simulator knows each echo "
                 "was:\norange stretches are walls the sonars heard and the method deleted",
                 fontsize=12)
    return fig


def _panel(ax: Axes, result: DemoResult, method: str,
           limits: tuple[float, float, float, float], size: float) -> None:
    """One method's kept points and deleted direct echoes over the true walls."""
    from sonarcarve.plotting import plot_walls

    sim = result.simulation
    gmap = result.global_maps[method]
    fates = echo_fates(sim.truth.kind, gmap.reading_id)
    plot_walls(result.world.segments, ax, colors="0.6", linewidths=1.0, zorder=1)
    lost = sim.truth.reflection[fates.lost_direct]
    ax.scatter(lost[:, 0], lost[:, 1], s=2.5 * size, marker="x", c=_LOST_COLOR,
               linewidths=0.6, zorder=2)
    for mask, color in ((fates.direct_point, _KEPT_COLOR), (fates.spurious_point,
                                                           _SPURIOUS_COLOR)):
        ax.scatter(gmap.xy[mask, 0], gmap.xy[mask, 1], s=size, c=color, linewidths=0,
                   zorder=3)
    ax.set_xlim(limits[0], limits[1])
    ax.set_ylim(limits[2], limits[3])
    ax.set_aspect("equal")


def _area(limits: tuple[float, float, float, float]) -> float:
    """Area of ``(xmin, xmax, ymin, ymax)``, square metres."""
    return (limits[1] - limits[0]) * (limits[3] - limits[2])


def _legend_handles() -> list[object]:
    from matplotlib.lines import Line2D

    return [Line2D([], [], ls="", marker="o", ms=6, color=_KEPT_COLOR,
                   label="kept: a true echo"),
            Line2D([], [], ls="", marker="o", ms=6, color=_SPURIOUS_COLOR,
                   label="kept: a spurious echo"),
            Line2D([], [], ls="", marker="x", ms=7, mew=1.5, color=_LOST_COLOR,
                   label="deleted: a true echo (at its wall)"),
            Line2D([], [], color="0.6", lw=1.5, label="true walls")]
