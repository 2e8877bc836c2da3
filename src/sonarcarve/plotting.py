"""Matplotlib figures of worlds, arcs and maps.

matplotlib is imported inside each function (never at import time), every function takes an
optional ``ax`` and returns the artists it drew, so callers own their figures.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from sonarcarve.maps import PointSource

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from sonarcarve.maps import GlobalMap, LocalMap
    from sonarcarve.sim.world import World

__all__ = ["SOURCE_COLORS", "new_axes", "plot_arc", "plot_freespace", "plot_map", "plot_world"]

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


def plot_world(world: World, ax: Axes | None = None, **style: Any) -> list[Any]:
    """Draw the walls as light grey lines (the paper's "obstacles drawn in for display")."""
    from matplotlib.collections import LineCollection

    ax = ax or new_axes()
    options: dict[str, Any] = {"colors": "0.6", "linewidths": 1.5, "zorder": 1} | style
    lines = LineCollection(list(world.segments.reshape(-1, 2, 2)), **options)
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
