"""Figures of the demo (``sonarcarve demo``), drawn from a
:class:`~sonarcarve.lab.demo.results.DemoResult`.

Figures 1-3 show the paper's four methods (:data:`~sonarcarve.lab.demo.scenario.PAPER_METHODS`);
evidence carving, beyond the paper, is in the table only.

1. :func:`plot_global_maps`: each method's whole global map over the true walls;
2. :func:`plot_map_zoom`: the same maps in a window where single points can be seen;
3. :func:`plot_error_by_range`: distance of map points to the true walls against range;
4. :func:`plot_door_closeup`: the local maps of centerline, carving and combined just before a
   door on the tour, with the robot, the door's jambs and the true walls.

matplotlib is imported inside the functions (Agg backend); each returns its figure and the
caller closes it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import GAP_DEPTH, RANGE_EDGES, passage_clearance
from sonarcarve.lab.demo.doors import DoorApproach, LocalView
from sonarcarve.lab.demo.results import DemoResult, MethodSummary
from sonarcarve.lab.demo.scenario import (
    APPROACH_DISTANCE,
    CLOSEUP_METHODS,
    METHOD_COLORS,
    METHOD_LABELS,
    PAPER_METHODS,
)
from sonarcarve.lab.instrument import ArcTable
from sonarcarve.maps import PointSource
from sonarcarve.plotting import new_figure, plot_sources
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.world import World

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "FIGURE_FILES",
    "FIGURE_TEXT",
    "ZOOM_SIZE",
    "map_limits",
    "plot_door_closeup",
    "plot_error_by_range",
    "plot_global_maps",
    "plot_map_zoom",
    "zoom_window",
]

#: Output files, in the order a reader should look at them.
FIGURE_FILES = {
    "global_maps": "fig1-global-maps.png",
    "map_zoom": "fig2-global-maps-zoom.png",
    "error_by_range": "fig3-error-vs-range.png",
    "door_closeup": "fig4-door-local-maps.png",
}
#: What each figure shows, in a few words (printed by the CLI, listed in ``summary.md``).
FIGURE_TEXT = {
    "global_maps": "each method's final map over the true walls",
    "map_zoom": "a close-up of those maps (dashed box of fig. 1)",
    "error_by_range": "map error against the range of the reading",
    "door_closeup": "the robot's local maps just before a door",
}
#: Size of the zoomed window of :func:`plot_map_zoom`, metres (at most the whole map).
ZOOM_SIZE = (16.0, 11.0)


def _walls(ax: Axes, world: World, **style: Any) -> None:
    from sonarcarve.plotting import plot_walls

    plot_walls(world.segments, ax, **({"colors": "0.55", "linewidths": 1.2} | style))


def _drawn_rows(result: DemoResult) -> tuple[MethodSummary, ...]:
    """The methods figures 1-3 show: the paper's four of the run (all if it ran none)."""
    rows = tuple(row for row in result.methods if row.method in PAPER_METHODS)
    return rows or result.methods


def map_limits(result: DemoResult, margin: float = 1.5) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` showing every drawn map point and the robot's path,
    metres."""
    traj = result.simulation.trajectory
    maps = [result.global_maps[row.method] for row in _drawn_rows(result)]
    xs = [traj.x] + [m.xy[:, 0] for m in maps]
    ys = [traj.y] + [m.xy[:, 1] for m in maps]
    x, y = np.concatenate(xs), np.concatenate(ys)
    wx0, wy0, wx1, wy1 = result.world.bounds
    # Clip to the walls' box: a stray multipath point far outside must not shrink the building.
    return (max(float(x.min()), wx0) - margin, min(float(x.max()), wx1) + margin,
            max(float(y.min()), wy0) - margin, min(float(y.max()), wy1) + margin)


def zoom_window(result: DemoResult) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)``: a :data:`ZOOM_SIZE` window over the stretch of the tour
    with the most map points (fig. 2's window; fig. 5's close-ups)."""
    x0, x1, y0, y1 = map_limits(result, margin=0.0)
    w, h = min(ZOOM_SIZE[0], x1 - x0), min(ZOOM_SIZE[1], y1 - y0)
    traj = result.simulation.trajectory
    step = max(1, len(traj) // 400)
    centres = np.column_stack((traj.x[::step], traj.y[::step]))
    centres[:, 0] = np.clip(centres[:, 0], x0 + w / 2, x1 - w / 2)
    centres[:, 1] = np.clip(centres[:, 1], y0 + h / 2, y1 - h / 2)
    xy = result.global_maps[_drawn_rows(result)[0].method].xy
    inside = ((np.abs(xy[None, :, 0] - centres[:, None, 0]) <= w / 2)
              & (np.abs(xy[None, :, 1] - centres[:, None, 1]) <= h / 2))
    cx, cy = centres[int(np.argmax(inside.sum(axis=1)))]
    return float(cx - w / 2), float(cx + w / 2), float(cy - h / 2), float(cy + h / 2)


def _map_panels(result: DemoResult, limits: tuple[float, float, float, float], size: float,
                title: str, box: tuple[float, float, float, float] | None = None) -> Figure:
    """Each method's global map over the true walls, 2x2 panels with the same limits."""
    from matplotlib.patches import Rectangle

    x0, x1, y0, y1 = limits
    drawn = _drawn_rows(result)
    cols = 2 if len(drawn) > 1 else 1
    rows = math.ceil(len(drawn) / cols)
    aspect = (y1 - y0) / max(x1 - x0, 1e-9)
    width = 13.0 if cols == 2 else 7.0
    fig, axes = new_figure(rows, cols, width=width,
                        height=min(14.0, 1.0 + rows * (width / cols) * aspect),
                        sharex=True, sharey=True)
    traj = result.simulation.trajectory
    for ax, row in zip(axes.flat, drawn, strict=False):
        gmap = result.global_maps[row.method]
        _walls(ax, result.world)
        ax.plot(traj.x, traj.y, color="0.25", lw=0.7, ls=":", zorder=2, label="robot path")
        plot_sources(gmap.xy, gmap.source, ax, size)
        if box is not None:
            ax.add_patch(Rectangle((box[0], box[2]), box[1] - box[0], box[3] - box[2],
                                   fill=False, ls="--", lw=1.2, color="k", zorder=4))
        ax.set_title(f"{row.label}: {row.map_points:,} points, median error "
                     f"{100.0 * row.median_error_m:.1f} cm", fontsize=11)
        ax.set_aspect("equal")
        # Legend dots about 6 pt across whatever the dot size on the map.
        ax.legend(loc="upper right", fontsize=8, markerscale=6.0 / math.sqrt(size),
                  framealpha=0.9)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
    for ax in axes.flat[len(drawn):]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("x (m)")
    for ax in axes[:, 0]:
        ax.set_ylabel("y (m)")
    fig.suptitle(title, fontsize=12)
    return fig


def plot_global_maps(result: DemoResult) -> Figure:
    """Fig. 1: each method's whole global map over the true walls (same limits everywhere)."""
    limits = map_limits(result)
    span = max(limits[1] - limits[0], limits[3] - limits[2])
    size = float(np.clip(60.0 / span, 0.8, 8.0))  # dots shrink as the map grows
    return _map_panels(
        result, limits, size, box=zoom_window(result),
        title=f"Final maps of the '{result.world.name}' tour: one dot per reading that survived, "
              "coloured by the model that placed it; grey: the true walls; dashed box: fig. 2")


def plot_map_zoom(result: DemoResult) -> Figure:
    """Fig. 2: the maps of fig. 1 inside its dashed box, where single points can be seen."""
    return _map_panels(
        result, zoom_window(result), 6.0,
        title="Close-up of the final maps (the dashed box of fig. 1): sharp maps hug the grey "
              "walls; smeared points and stray dots are errors")


def plot_error_by_range(result: DemoResult) -> Figure:
    """Fig. 3: distance of global map points to the true walls against the reading's range."""
    from matplotlib.lines import Line2D

    from sonarcarve.maps import chord_error

    fig, axes = new_figure(1, 1, width=10.5, height=5.5)
    ax = axes[0, 0]
    edges = np.asarray(RANGE_EDGES)
    handles = []
    for row in _drawn_rows(result):
        gmap = result.global_maps[row.method]
        stats = metrics.binned(result.map_errors[row.method], gmap.range, edges)
        enough = stats.counts >= 10  # the median of a handful of points is noise
        color = METHOD_COLORS.get(row.method, "k")
        ax.plot(stats.centers[enough], stats.median[enough], "-o", color=color, ms=4)
        ax.plot(stats.centers[enough], stats.p90[enough], "--", color=color, lw=1.2)
        handles.append(Line2D([], [], color=color, lw=2.5, label=row.label))
    handles += [Line2D([], [], color="0.4", marker="o", ms=4, label="median"),
                Line2D([], [], color="0.4", ls="--", label="90th percentile")]
    r = np.linspace(0.25, edges[-1], 100)
    handles += ax.plot(r, chord_error(r, np.full_like(r, result.config.beam_width)), ":",
                       color="0.3", lw=1.5,
                       label="centerline's worst case\nfor a true echo (eq. 5.3)")
    ax.set_yscale("log")
    ax.set_xlabel("range of the reading (m)")
    ax.set_ylabel("distance of the map point to the true walls (m, log scale)")
    ax.set_xlim(edges[0], edges[-1])
    ax.set_title("How far map points lie from the true walls, by the range of their reading "
                 "(lower is better)", fontsize=11)
    ax.grid(alpha=0.3, which="both")
    ax.legend(handles=handles, fontsize=9, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              borderaxespad=0.0)
    return fig


def plot_door_closeup(result: DemoResult) -> Figure:
    """Fig. 4: the local maps of centerline, carving and combined just before a door.

    Each panel shows one method's local map (one point per arc in its history, and the part of
    each arc where its echo may still have come from), the robot, the true walls and the door
    with its jambs, at the moment of :attr:`DemoResult.closeup` (mid-tour if no door).
    """
    door = result.closeup
    view = door.view if door is not None else result.fallback_view
    methods = [m for m in CLOSEUP_METHODS if view is not None and m in view.maps]
    cols = max(1, len(methods))
    fig, axes = new_figure(1, cols, width=4.8 * cols, height=5.9, sharex=True, sharey=True)
    if view is None or not methods:
        axes[0, 0].axis("off")
        return fig
    for ax, method in zip(axes[0], methods, strict=True):
        _closeup_panel(ax, result, view, door, method)
    axes[0, 0].set_ylabel("y (m)")
    fig.suptitle(_closeup_title(result, view, door), fontsize=12)
    fig.text(0.5, 0.01, "Dots: one point per reading in the history; faint arcs: where each "
             "reading's echo can still have come from (carving shrinks them); free = widest "
             f"stretch of the door with no point within {GAP_DEPTH:g} m of it",
             ha="center", va="bottom", fontsize=9, color="0.25")
    _leave_margin(fig, bottom=0.04)
    return fig


def _closeup_panel(ax: Axes, result: DemoResult, view: LocalView, door: DoorApproach | None,
                   method: str) -> None:
    """One panel of fig. 4: ``method``'s local map, the path ahead, the door and the robot."""
    sim = result.simulation
    traj = sim.trajectory
    # The next 2.5 approach distances of the drive: through the door and a little beyond.
    travelled = traj.distance_at(traj.t)
    now = float(traj.distance_at(view.t))
    ahead = (traj.t >= view.t) & (travelled <= now + 2.5 * APPROACH_DISTANCE)
    local = view.maps[method]
    _walls(ax, result.world, colors="0.45", linewidths=2.0)
    ax.plot(traj.x[ahead], traj.y[ahead], color="k", ls=":", lw=1.2, zorder=4,
            label="path ahead")
    _local_arcs(ax, sim, local)
    plot_sources(local.xy, local.source, ax, 20.0)
    if door is not None:
        ax.plot(door.jambs[:, 0], door.jambs[:, 1], color="orange", lw=3.0, ls="--",
                zorder=2, label="the door")
        ax.scatter(door.jambs[:, 0], door.jambs[:, 1], s=110, marker="s",
                   facecolors="none", edgecolors="darkorange", linewidths=2.2, zorder=5,
                   label="its jambs")
    _robot(ax, view.robot, float(sim.robot.robot_radius))
    # A square around the robot and the door's jambs, 1.6 m beyond the farther of them.
    rx, ry, _ = view.robot
    focus = np.array([[rx, ry]]) if door is None else np.vstack(([rx, ry], door.jambs))
    centre = 0.5 * (focus.min(axis=0) + focus.max(axis=0))
    half = 0.5 * float(np.max(focus.max(axis=0) - focus.min(axis=0))) + 1.6
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    label = METHOD_LABELS.get(method, method)
    if door is not None:
        gap = float(np.hypot(*(door.jambs[1] - door.jambs[0])))
        verdict = "passable" if door.passable[method] else "BLOCKED"
        ax.set_title(f"{label}: {door.free_width[method]:.2f} m of the {gap:.2f} m door "
                     f"free, {verdict}", fontsize=11)
    else:
        ax.set_title(f"{label}: local map", fontsize=11)
    ax.legend(loc="lower left", fontsize=7, framealpha=0.9)


def _closeup_title(result: DemoResult, view: LocalView, door: DoorApproach | None) -> str:
    """Fig. 4's title: where the robot is, and how much free width it needs."""
    if door is None:
        return f"Local maps at mid-tour (t = {view.t:.0f} s); the tour approaches no door"
    where = (f"{APPROACH_DISTANCE:g} m before driving through a door" if door.how == "through"
             else f"{door.distance:.1f} m from a door")
    need = passage_clearance(float(result.simulation.robot.robot_radius))
    return (f"'{result.world.name}': what the robot's local map shows {where} "
            f"(t = {view.t:.0f} s); the robot needs {need:.2f} m free to pass")


def _robot(ax: Axes, pose: tuple[float, float, float], radius: float) -> None:
    """The robot as a circle with an arrow along its heading."""
    from matplotlib.patches import Circle

    x, y, heading = pose
    ax.add_patch(Circle((x, y), radius, fill=False, color="k", lw=1.6, zorder=6))
    ax.annotate("", xy=(x + 2.2 * radius * math.cos(heading),
                        y + 2.2 * radius * math.sin(heading)),
                xytext=(x, y), zorder=6, arrowprops={"arrowstyle": "->", "color": "k", "lw": 1.6})
    ax.plot([], [], "o", mfc="none", mec="k", label="robot")


def _local_arcs(ax: Axes, sim: Simulation, local: ArcTable) -> None:
    """Faint arcs: each surviving arc's remaining interval, centred on its point (eq. 3.1)."""
    from matplotlib.collections import LineCollection

    from sonarcarve.plotting import SOURCE_COLORS

    # ATM points sit at the median of crossings, not at the centre of an interval: no arc.
    local = local.select(local.source != PointSource.ATM)
    if not len(local):
        return
    rid = local.reading_id
    ox, oy = sim.readings.x[rid], sim.readings.y[rid]
    r = local.range
    centre = np.arctan2(local.xy[:, 1] - oy, local.xy[:, 0] - ox)
    tau = centre[:, None] + local.width[:, None] * np.linspace(-0.5, 0.5, 24)[None, :]
    curves = np.stack((ox[:, None] + r[:, None] * np.cos(tau),
                       oy[:, None] + r[:, None] * np.sin(tau)), axis=-1)
    colors = [SOURCE_COLORS[PointSource(int(s))] for s in local.source]
    ax.add_collection(LineCollection(list(curves), colors=colors, linewidths=0.8, alpha=0.35,
                                     zorder=2))


def _leave_margin(fig: Figure, bottom: float) -> None:
    """Keep the bottom ``bottom`` share of the figure free of axes (for a footnote)."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    engine = fig.get_layout_engine()
    if isinstance(engine, ConstrainedLayoutEngine):
        engine.set(rect=(0.0, bottom, 1.0, 1.0 - bottom))
