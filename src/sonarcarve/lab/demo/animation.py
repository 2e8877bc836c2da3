"""The demo's animation: the robot approaching the close-up door, every close-up method side by
side (fig. 4 in motion).

The methods of fig. 4 (:data:`~sonarcarve.lab.demo.scenario.CLOSEUP_METHODS`) are fed the
tour's readings up to the close-up door's moment; the last :data:`FRAMES` steps are drawn: each
method's local map (its points coloured by the model that placed them, and the part of each
arc where the echo can still have come from) over the true walls, the door with its jambs, the
robot and its path. Each panel's title is *measured* in that frame, as fig. 4's is: the free
width the method's local map leaves in the door and whether the robot fits through, so the
last frame reads as fig. 4 and no title claims what the map does not show. Written as a GIF
(matplotlib's Agg canvas, one draw a frame, Pillow's GIF writer; no display).
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import GAP_DEPTH, passage_clearance
from sonarcarve.lab.demo.results import DemoResult
from sonarcarve.lab.demo.scenario import CLOSEUP_METHODS, METHOD_LABELS
from sonarcarve.maps import PointSource
from sonarcarve.methods import make_method
from sonarcarve.methods.base import SonarMethod
from sonarcarve.typing import FloatArray

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from PIL import Image

__all__ = ["ANIMATION_FILE", "ANIMATION_TEXT", "FRAMES", "DoorGauge", "animation_gif", "live_map"]

#: The animation's file name in the demo's output folder.
ANIMATION_FILE = "approach.gif"
#: What it shows, in a few words (printed by the CLI, listed in ``summary.md``).
ANIMATION_TEXT = "that approach, animated, measured in every frame"
#: Frames drawn (the readings before the door's moment are spread over them).
FRAMES = 40
_WINDOW = 2.4  # half-size of the drawn square, metres
_FPS = 6
_DPI = 72
_PANEL_INCHES = 3.9  # 3 panels at 72 dpi: an 840-pixel-wide GIF


class DoorGauge:
    """The close-up door: its jambs, the strip a map point closes it in, the width needed."""

    def __init__(self, result: DemoResult) -> None:
        door = result.closeup
        self.jambs: FloatArray | None = None
        self.region: Any = None
        self.gap = 0.0
        if door is not None:
            self.jambs = np.asarray(door.jambs, dtype=np.float64)
            self.region = metrics.gap_region(self.jambs[0], self.jambs[1], GAP_DEPTH)
            self.gap = float(np.hypot(*(self.jambs[1] - self.jambs[0])))
        self.need = passage_clearance(float(result.simulation.robot.robot_radius))

    def distance(self, x: float, y: float) -> str:
        """How far the robot at ``(x, y)`` is from the middle of the door, as words."""
        if self.jambs is None:
            return ""
        middle = self.jambs.mean(axis=0)
        return f", {math.hypot(x - middle[0], y - middle[1]):.1f} m from the door"

    def title(self, label: str, points: FloatArray) -> str:
        """``label`` and what its local map leaves free of the door (fig. 4's measure)."""
        if self.jambs is None:
            return f"{label}: local map"
        free = metrics.free_width(points, self.region)
        verdict = "passable" if free >= self.need else "BLOCKED"
        return f"{label}: {free:.2f} of {self.gap:.2f} m free, {verdict}"


def _moment(result: DemoResult) -> tuple[int, FloatArray]:
    """Readings fed by the end, and the centre of the drawn window: halfway between the door
    and where the robot is then, so both stay in view."""
    door = result.closeup
    readings = result.simulation.readings
    view = door.view if door is not None else result.fallback_view
    end = view.readings if view is not None else len(readings)
    k = max(end - 1, 0)
    robot = np.array([readings.x[k], readings.y[k]])
    if door is None:
        return end, robot
    return end, 0.5 * (robot + np.asarray(door.jambs, dtype=np.float64).mean(axis=0))


def live_map(method: SonarMethod) -> tuple[FloatArray, list[FloatArray], list[int]]:
    """The method's live points (shape (n, 2)), and the arc (shape (12, 2)) and source code of
    each. ATM points sit at a median of crossings, not at the middle of an interval, so their
    arcs are not drawn (as in fig. 4)."""
    h = method.history
    slots = h.slots()
    est = method.estimates(slots)
    alive = np.flatnonzero(est.alive)
    lines, sources = [], []
    for k in alive.tolist():
        source = int(est.source[k])
        sources.append(source)
        s = int(slots[k])
        ox, oy, r = float(h.x[s]), float(h.y[s]), float(h.r[s])
        if source == PointSource.ATM:
            lines.append(np.empty((0, 2)))
            continue
        mid = math.atan2(float(est.xy[k, 1]) - oy, float(est.xy[k, 0]) - ox)
        tau = np.linspace(mid - est.width[k] / 2, mid + est.width[k] / 2, 12)
        lines.append(np.column_stack((ox + r * np.cos(tau), oy + r * np.sin(tau))))
    return np.asarray(est.xy[alive], dtype=np.float64).reshape(-1, 2), lines, sources


def _panel(ax: Axes, result: DemoResult, door: DoorGauge, centre: FloatArray) -> None:
    """The still parts of a panel: walls, the door and its jambs, the window."""
    from sonarcarve.plotting import SOURCE_COLORS, plot_walls

    walls = np.asarray(result.world.segments, dtype=np.float64).reshape(-1, 2, 2)
    low, high = walls.min(axis=1), walls.max(axis=1)
    near = np.all((high >= centre - _WINDOW) & (low <= centre + _WINDOW), axis=1)
    plot_walls(walls[near].reshape(-1, 4), ax, colors="0.45", linewidths=1.6)  # only those in view
    if door.jambs is not None:
        ax.plot(door.jambs[:, 0], door.jambs[:, 1], color="orange", lw=2.5, ls="--", zorder=2,
                label="the door")
        ax.scatter(door.jambs[:, 0], door.jambs[:, 1], s=70, marker="s", facecolors="none",
                   edgecolors="darkorange", linewidths=1.8, zorder=5, label="its jambs")
    for code, color in SOURCE_COLORS.items():  # legend entries for the moving dots
        ax.scatter([], [], s=14, c=color, label=f"{PointSource(code).label} point")
    ax.set_xlim(centre[0] - _WINDOW, centre[0] + _WINDOW)
    ax.set_ylim(centre[1] - _WINDOW, centre[1] + _WINDOW)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def animation_gif(result: DemoResult, frames: int = FRAMES) -> bytes:
    """The approach animation of ``result`` as GIF bytes (3 panels, 840 x 330 pixels)."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.patches import Circle

    from sonarcarve.plotting import SOURCE_COLORS

    readings = result.simulation.readings
    rx, ry, _ = result.simulation.trajectory.pose_at(readings.t)  # robot centre per reading
    radius = float(result.simulation.robot.robot_radius)
    end, centre = _moment(result)
    start = max(0, end - 4 * frames)
    cuts = np.unique(np.linspace(start, end, frames + 1).round().astype(int))
    names = CLOSEUP_METHODS
    methods = {name: make_method(name, result.config) for name in names}
    for method in methods.values():
        if start:
            method.add_many(readings[:start], first_id=0)
    door = DoorGauge(result)
    fig, axes = plt.subplots(1, len(names), figsize=(_PANEL_INCHES * len(names), 4.6),
                             dpi=_DPI, layout="constrained")
    arcs, dots, titles, robots, paths = {}, {}, {}, [], []
    for ax, name in zip(axes, names, strict=True):
        _panel(ax, result, door, centre)
        arcs[name] = ax.add_collection(LineCollection([], linewidths=1.0, alpha=0.45, zorder=3))
        dots[name] = ax.scatter(np.empty(0), np.empty(0), s=12, zorder=4, linewidths=0)
        titles[name] = ax.set_title("", fontsize=9)
        paths.append(ax.plot([], [], color="0.3", linewidth=0.8, zorder=2)[0])
        robots.append(ax.add_patch(Circle((0.0, 0.0), radius, fill=False, color="k", lw=1.4,
                                          zorder=6)))
    axes[0].legend(loc="lower left", fontsize=6.5, framealpha=0.9)
    clock = fig.suptitle("", fontsize=10)
    fig.text(0.5, 0.005, f"The robot (circle) needs {door.need:.2f} m of the door free of map "
             f"points (within {GAP_DEPTH:g} m of it); faint arcs: where each echo can still "
             "have come from", ha="center", va="bottom", fontsize=7.5, color="0.25")

    def draw(frame: int) -> list[Any]:
        lo, hi = (int(cuts[frame - 1]) if frame else start), int(cuts[frame])
        for name, method in methods.items():
            if hi > lo:
                method.add_many(readings[lo:hi], first_id=lo)
            xy, lines, sources = live_map(method)
            colors = [SOURCE_COLORS[PointSource(s)] for s in sources]
            arcs[name].set_segments(lines)
            arcs[name].set_color(colors)
            dots[name].set_offsets(xy)
            dots[name].set_color(colors)
            titles[name].set_text(door.title(METHOD_LABELS.get(name, name), xy))
        k = max(hi - 1, 0)
        for robot, path in zip(robots, paths, strict=True):
            robot.set_center((float(rx[k]), float(ry[k])))
            path.set_data(rx[start:hi], ry[start:hi])
        clock.set_text(f"'{result.world.name}', t = {float(readings.t[k]):.1f} s: the robot's "
                       "local maps"
                       + door.distance(float(rx[k]), float(ry[k])))
        return [*arcs.values(), *dots.values(), *robots, *paths]

    moving = [*paths, *arcs.values(), *dots.values(), *robots, *titles.values(), clock]
    try:
        return _gif(_frames(fig, draw, len(cuts), moving))
    finally:
        plt.close(fig)


def _frames(fig: Figure, draw: Callable[[int], object], n: int,
            moving: list[Any]) -> list[Image.Image]:
    """The ``n`` frames as images. The still parts (walls, door, legend, footnote) are drawn
    and laid out once, with every moving artist's first state giving the layout its room;
    each frame then redraws only the moving artists over that background (matplotlib's
    blitting), a quarter of the time of drawing the whole figure each frame."""
    from PIL import Image

    draw(0)
    for artist in moving:
        artist.set_animated(True)  # left out of the full draw below
    fig.canvas.draw()
    fig.set_layout_engine("none")  # nothing moves the layout any more
    background = fig.canvas.copy_from_bbox(fig.bbox)  # type: ignore[attr-defined]
    images = []
    for k in range(n):
        if k:
            draw(k)
        fig.canvas.restore_region(background)  # type: ignore[attr-defined]
        for artist in moving:
            fig.draw_artist(artist)
        rgba = np.asarray(fig.canvas.buffer_rgba())  # type: ignore[attr-defined]
        images.append(Image.fromarray(rgba).convert("RGB"))
    return images


def _gif(frames: list[Image.Image]) -> bytes:
    """``frames`` as an animated GIF, :data:`_FPS` frames a second, looping
    forever (``loop=0``: a README shows it over and over)."""
    buffer = io.BytesIO()
    frames[0].save(buffer, format="GIF", save_all=True, append_images=frames[1:],
                   duration=round(1000 / _FPS), loop=0)
    return buffer.getvalue()
