"""Small matplotlib helpers shared by the experiments', the appendix's and the demo's figures.

matplotlib is imported inside each function (Agg backend), never at import time.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from sonarcarve.io.atomic import atomic_path
from sonarcarve.maps import PointSource

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = [
    "METHOD_COLORS",
    "new_figure",
    "save_pngs",
    "scatter_sources",
    "segments_collection",
]

#: One colour per method (by its results label), the same in every figure: centerline, carved
#: and ATM points as in :data:`~sonarcarve.plotting.SOURCE_COLORS`, combined in purple,
#: evidence in orange.
METHOD_COLORS = {"atm": "#2ca02c", "carving": "#1f77b4", "combined": "#9467bd",
                 "centerline": "#d62728", "evidence": "#ff7f0e"}


def new_figure(rows: int = 1, cols: int = 1, width: float = 7.0, height: float = 4.5,
               **options: Any) -> tuple[Figure, Any]:
    """A constrained-layout figure of ``rows`` x ``cols`` axes (a 2-D array, even for one),
    ``width`` x ``height`` inches; ``options`` go to ``plt.subplots`` (``sharex`` ...)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, cols, figsize=(width, height), layout="constrained",
                             squeeze=False, **options)
    return fig, axes


def segments_collection(ax: Axes, segments: npt.ArrayLike, color: str = "0.6",
                        linewidth: float = 0.8) -> None:
    """Draw wall segments ``(x1, y1, x2, y2)`` (shape (m, 4), metres) below everything else."""
    from matplotlib.collections import LineCollection

    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)
    ax.add_collection(LineCollection(list(seg), colors=color, linewidths=linewidth, zorder=1))


def scatter_sources(ax: Axes, xy: npt.ArrayLike, source: npt.ArrayLike, size: float) -> None:
    """Scatter map points ``xy`` (shape (n, 2)) coloured by the model that placed them
    (``source``: :class:`~sonarcarve.maps.PointSource` codes), one legend entry per source
    with its count."""
    from sonarcarve.plotting import SOURCE_COLORS

    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    codes = np.asarray(source)
    for code, color in SOURCE_COLORS.items():
        mask = codes == code
        if np.any(mask):
            ax.scatter(p[mask, 0], p[mask, 1], s=size, c=color, linewidths=0, zorder=3,
                       label=f"{PointSource(code).label} ({int(mask.sum()):,})")


def save_pngs(figures: dict[str, Figure | None], folder: str | Path,
              dpi: int = 110) -> list[Path]:
    """Save each figure as ``folder/<name>`` (atomically; the folder is created), close it,
    and return the paths written, in order; None entries (nothing to draw) are skipped."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in figures.items():
        if fig is None:
            continue
        with atomic_path(out / name, suffix=".png") as tmp:
            fig.savefig(tmp, dpi=dpi, format="png")
        plt.close(fig)
        written.append(out / name)
    return written
