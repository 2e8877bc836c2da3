"""Matplotlib figures of worlds, arcs and maps.

matplotlib is imported inside each function (never at import time), every function takes an
optional ``ax`` and returns the artists it drew, so callers own their figures.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import DEFAULT_BEAM_WIDTH
from sonarcarve.maps import PointSource

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from sonarcarve.maps import GlobalMap, LocalMap

__all__ = ["SOURCE_COLORS", "new_axes", "plot_arc", "plot_freespace", "plot_map", "plot_walls"]

#: One colour per point source, the same in every figure.
SOURCE_COLORS = {
    PointSource.CENTERLINE: "#d62728",
    PointSource.CARVED: "#1f77b4",
    PointSource.ATM: "#2ca02c",
}


def new_axes(width: float = 7.0, height: float = 6.0) -> Axes:
    """A fresh figure with one equal-aspect axes (Agg backend: works without a display)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(figsize=(width, height), layout="constrained")
    ax.set_aspect("equal")
    return ax


def plot_walls(segments: npt.ArrayLike, ax: Axes | None = None, **style: Any) -> list[Any]:
    """Draw wall ``segments`` (shape (n, 4): x1, y1, x2, y2, metres) as light grey lines (the
    paper's "obstacles drawn in for display")."""
    from matplotlib.collections import LineCollection

    ax = ax or new_axes()
    options: dict[str, Any] = {"colors": "0.6", "linewidths": 1.5, "zorder": 1} | style
    walls = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)
    lines = LineCollection(list(walls), **options)
    ax.add_collection(lines)
    ax.autoscale_view()
    return [lines]


def plot_map(
    points: LocalMap | GlobalMap, ax: Axes | None = None, size: float = 4.0, legend: bool = True
) -> list[Any]:
    """Scatter map points coloured by the model that placed them."""
    ax = ax or new_axes()
    artists = []
    for source, color in SOURCE_COLORS.items():
        mask = points.source == source
        if np.any(mask):
            artists.append(ax.scatter(points.xy[mask, 0], points.xy[mask, 1], s=size, c=color,
                                      label=f"{source.label} ({int(mask.sum())})", zorder=3,
                                      linewidths=0))
    if legend and artists:
        ax.legend(loc="best", fontsize="small", markerscale=3)
    return artists


def plot_arc(
    origin: npt.ArrayLike, r: float, lo: float, hi: float, ax: Axes | None = None, **style: Any
) -> list[Any]:
    """Draw the arc of radius ``r`` about ``origin`` over bearings [lo, hi] (eq. 3.1)."""
    ax = ax or new_axes()
    o = np.asarray(origin, dtype=np.float64)
    tau = np.linspace(lo, hi, 64)
    return list(ax.plot(o[0] + r * np.cos(tau), o[1] + r * np.sin(tau), **style))


def plot_freespace(
    origin: npt.ArrayLike, r: float, lo: float, hi: float, ax: Axes | None = None, **style: Any
) -> list[Any]:
    """Shade the freespace sector F of a reading (eq. 3.2)."""
    ax = ax or new_axes()
    o = np.asarray(origin, dtype=np.float64)
    tau = np.linspace(lo, hi, 64)
    xs = np.concatenate(([o[0]], o[0] + r * np.cos(tau), [o[0]]))
    ys = np.concatenate(([o[1]], o[1] + r * np.sin(tau), [o[1]]))
    return list(ax.fill(xs, ys, **({"alpha": 0.2, "lw": 0} | style)))


def plot_carving_explainer(ax: Axes | None = None) -> list[Any]:
    """The idea of arc carving in one picture (paper, Fig. 2, 5 and 6).

    A robot passes a 0.9 m doorway. Reading ``i`` hears the right-hand door jamb at the edge of
    its 22.5° beam; the centerline model puts the echo at the centre of the arc, inside the
    doorway, and the door looks closed (Fig. 2). A newer reading ``j`` looks straight through
    the door and hears the far wall, so its beam was empty up to that range: the part of arc
    ``i`` inside that sector is carved away (eq. 3.4-3.5) and the point moves to the centre of
    what remains (eq. 3.6), next to the jamb. The door opens up in the map.
    """
    import math

    from sonarcarve.geometry import ArcFate, carve_arc

    ax = ax or new_axes(7.0, 5.5)
    half = DEFAULT_BEAM_WIDTH / 2
    jamb_left, jamb_right, wall_y = 0.5, 1.4, 2.0
    oi = np.array([0.2, 0.0])
    theta_i = math.atan2(wall_y - oi[1], 0.5 * (jamb_left + jamb_right) - oi[0])
    ri = float(np.hypot(jamb_right - oi[0], wall_y - oi[1]))  # the jamb is the nearest echo
    oj, theta_j, rj = np.array([0.95, 0.2]), math.pi / 2, 4.8  # through the door to a far wall
    lo_i, hi_i = theta_i - half, theta_i + half
    status, new_lo, new_hi = carve_arc(oi[0], oi[1], ri, lo_i, hi_i, oj[0], oj[1], rj,
                                       theta_j - half, theta_j + half)
    if status != ArcFate.SHRUNK:  # the picture is built to show a shrink; keep it honest
        msg = f"explainer geometry no longer shrinks the arc (outcome {status})"
        raise RuntimeError(msg)
    artists: list[Any] = []
    for x0, x1 in ((-0.7, jamb_left), (jamb_right, 2.6)):
        artists += ax.plot([x0, x1], [wall_y, wall_y], color="0.45", lw=4,
                           label="walls" if x0 < 0 else None)
    artists += plot_freespace(oj, rj, theta_j - half, theta_j + half, ax, color="#2ca02c",
                              alpha=0.18, label="free space of newer reading j")
    artists += plot_arc(oi, ri, lo_i, hi_i, ax, color="#d62728", ls="--", lw=1.5,
                        label="arc of older reading i (22.5° wide)")
    artists += plot_arc(oi, ri, new_lo, new_hi, ax, color="#1f77b4", lw=4,
                        label="arc i after carving")
    centre = oi + ri * np.array([math.cos(theta_i), math.sin(theta_i)])
    mid = 0.5 * (new_lo + new_hi)
    carved = oi + ri * np.array([math.cos(mid), math.sin(mid)])
    artists.append(ax.scatter(centre[0], centre[1], s=90, marker="x", color="#d62728", zorder=5,
                              label="centerline point: blocks the door"))
    artists.append(ax.scatter(carved[0], carved[1], s=60, color="#1f77b4", zorder=5,
                              label="carved point: at the jamb"))
    for origin, name in ((oi, "sensor, reading i"), (oj, "sensor, reading j (later)")):
        artists.append(ax.scatter(origin[0], origin[1], s=40, color="k", zorder=5))
        artists.append(ax.annotate(name, (origin[0], origin[1]), textcoords="offset points",
                                   xytext=(6, -12), fontsize="small"))
    artists.append(ax.annotate("0.9 m door", (0.95, wall_y), textcoords="offset points",
                               xytext=(-25, -22), fontsize="small", color="0.3"))
    ax.set_xlim(-0.7, 2.6)
    ax.set_ylim(-0.4, 3.3)
    ax.set_title("Arc carving: newer free space cuts older arcs")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper left", fontsize="small", framealpha=0.95)
    return artists


def write_carving_explainer(path: str) -> None:
    """Write :func:`plot_carving_explainer` as a PNG (the README's figure)."""
    ax = new_axes(7.0, 5.5)
    plot_carving_explainer(ax)
    figure = ax.get_figure(root=True)
    if figure is not None:
        figure.savefig(path, dpi=110)
