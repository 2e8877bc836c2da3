"""The demo's animation: the robot approaching a door, centerline beside carving.

Both methods are fed the tour's readings up to the close-up door's moment; the last
:data:`FRAMES` steps are drawn: each method's live arcs (coloured by the model that placed
their point) over the true walls, the robot and its path. Newer readings carve the arcs
shorter, so carving opens the door while the centerline map closes it. Written as a GIF
(matplotlib ``FuncAnimation`` with ``PillowWriter``, Agg backend, no display).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from sonarcarve.lab.demo.results import DemoResult
from sonarcarve.methods import make_method
from sonarcarve.methods.base import SonarMethod

__all__ = ["ANIMATION_FILE", "FRAMES", "animation_gif"]

#: The animation's file name in the demo's output folder.
ANIMATION_FILE = "approach.gif"
#: Frames drawn (the readings before the door's moment are spread over them).
FRAMES = 40
_METHODS = ("centerline", "carve")
_TITLES = {"centerline": "centerline: the door closes", "carve": "arc carving: it opens"}
_WINDOW = 3.5  # half-size of the drawn square around the door, metres
_FPS = 8


def _moment(result: DemoResult) -> tuple[int, np.ndarray]:
    """Readings fed by the end, and the centre of the drawn window."""
    door = result.closeup
    readings = result.simulation.readings
    if door is not None:
        return door.view.readings, np.asarray(door.jambs, dtype=np.float64).mean(axis=0)
    view = result.fallback_view
    end = view.readings if view is not None else len(readings)
    k = max(end - 1, 0)
    return end, np.array([readings.x[k], readings.y[k]])


def _arcs(method: SonarMethod) -> tuple[list[np.ndarray], list[int]]:
    """Polylines (shape (m, 2)) and source codes of the method's live arcs."""
    h = method.history
    slots = h.slots()
    est = method.estimates(slots)
    lines, sources = [], []
    for k in np.flatnonzero(est.alive).tolist():
        s = int(slots[k])
        ox, oy, r = float(h.x[s]), float(h.y[s]), float(h.r[s])
        mid = math.atan2(float(est.xy[k, 1]) - oy, float(est.xy[k, 0]) - ox)
        tau = np.linspace(mid - est.width[k] / 2, mid + est.width[k] / 2, 12)
        lines.append(np.column_stack((ox + r * np.cos(tau), oy + r * np.sin(tau))))
        sources.append(int(est.source[k]))
    return lines, sources


def animation_gif(result: DemoResult, frames: int = FRAMES) -> bytes:
    """The approach animation of ``result`` as GIF bytes (small: 6 x 3.2 in at 70 dpi)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation, PillowWriter
    from matplotlib.collections import LineCollection

    from sonarcarve.plotting import SOURCE_COLORS, plot_walls

    readings = result.simulation.readings
    rx, ry, _ = result.simulation.trajectory.pose_at(readings.t)  # robot centre per reading
    end, centre = _moment(result)
    start = max(0, end - 4 * frames)
    cuts = np.unique(np.linspace(start, end, frames + 1).round().astype(int))
    methods = {name: make_method(name, result.config) for name in _METHODS}
    for method in methods.values():
        if start:
            method.add_many(readings[:start], first_id=0)
    fig, axes = plt.subplots(1, 2, figsize=(6.0, 3.2), layout="constrained")
    arcs: dict[str, Any] = {}
    robots, paths = [], []
    for ax, name in zip(axes, _METHODS, strict=True):
        plot_walls(result.world.segments, ax, colors="0.6", linewidths=1.0)
        ax.set_xlim(centre[0] - _WINDOW, centre[0] + _WINDOW)
        ax.set_ylim(centre[1] - _WINDOW, centre[1] + _WINDOW)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(_TITLES[name], fontsize=9)
        arcs[name] = ax.add_collection(LineCollection([], linewidths=1.2, zorder=3))
        paths.append(ax.plot([], [], color="0.3", linewidth=0.8, zorder=2)[0])
        robots.append(ax.plot([], [], "ko", markersize=5, zorder=4)[0])

    def draw(frame: int) -> list[Any]:
        lo, hi = (int(cuts[frame - 1]) if frame else start), int(cuts[frame])
        for name, method in methods.items():
            if hi > lo:
                method.add_many(readings[lo:hi], first_id=lo)
            lines, sources = _arcs(method)
            arcs[name].set_segments(lines)
            arcs[name].set_color([SOURCE_COLORS[s] for s in sources])  # type: ignore[index]
        k = max(hi - 1, 0)
        for robot, path in zip(robots, paths, strict=True):
            robot.set_data([rx[k]], [ry[k]])
            path.set_data(rx[start:hi], ry[start:hi])
        return [*arcs.values(), *robots, *paths]

    anim = FuncAnimation(fig, draw, frames=len(cuts), blit=False, repeat=False)
    try:
        with tempfile.TemporaryDirectory() as folder:
            gif = Path(folder) / ANIMATION_FILE
            anim.save(gif, writer=PillowWriter(fps=_FPS), dpi=70)
            return gif.read_bytes()
    finally:
        plt.close(fig)
