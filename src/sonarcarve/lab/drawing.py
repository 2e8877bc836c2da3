"""What the experiments', the appendix's and the demo's figures share beyond
:mod:`sonarcarve.plotting` (whose :func:`~sonarcarve.plotting.new_figure`,
:func:`~sonarcarve.plotting.plot_walls` and :func:`~sonarcarve.plotting.plot_sources` they draw
with): the methods' colours and saving a batch of PNGs.

matplotlib is imported inside each function, never at import time; the backend is the entry
point's choice (the command line's is Agg).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from sonarcarve.io.atomic import atomic_path

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["METHOD_COLORS", "save_pngs"]

#: One colour per method (by its results label), the same in every figure: centerline, carved
#: and ATM points as in :data:`~sonarcarve.plotting.SOURCE_COLORS`, combined in purple,
#: evidence in orange.
METHOD_COLORS = {"atm": "#2ca02c", "carving": "#1f77b4", "combined": "#9467bd",
                 "centerline": "#d62728", "evidence": "#ff7f0e"}


def save_pngs(figures: dict[str, Figure | None], folder: str | Path,
              dpi: int = 110) -> list[Path]:
    """Save each figure as ``folder/<name>`` (atomically; the folder is created), close it,
    and return the paths written, in order; None entries (nothing to draw) are skipped."""
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
