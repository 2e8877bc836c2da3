""":mod:`sonarcarve.lab.demo.grid_figure`: fig. 5 lays out its texts without touching."""

from __future__ import annotations

from typing import TYPE_CHECKING

import pytest

from sonarcarve.lab.demo import DemoResult, run_demo
from sonarcarve.lab.demo.grid_figure import plot_occupancy_grids

if TYPE_CHECKING:
    from matplotlib.text import Text

#: Least clear space between two texts of different panels, points (a line of 10-point text
#: needs about 3 points of leading before a neighbour's ink stops touching it).
MIN_GAP_PT = 8.0


@pytest.fixture(scope="module")
def office_start() -> DemoResult:
    """The first 100 m of the office tour: a map large enough for fig. 5's close-up row."""
    return run_demo("office", seed=0, max_length=100.0, methods=("centerline",))


def _gap_pt(upper: Text, lower: Text, dpi: float) -> float:
    """Clear space from the bottom of ``upper`` to the top of ``lower``, points."""
    return (upper.get_window_extent().y0 - lower.get_window_extent().y1) * 72.0 / dpi


def test_rows_and_title_of_fig5_leave_space_between_their_texts(
        office_start: DemoResult) -> None:
    import matplotlib.pyplot as plt

    fig = plot_occupancy_grids(office_start)
    try:
        fig.canvas.draw()
        top, closeup = fig.axes[:2], fig.axes[2:]
        assert len(closeup) == 2, "the office's close-up row is drawn"
        suptitle = fig._suptitle  # matplotlib has no public getter of the title's Text
        assert suptitle is not None
        for upper, lower in zip(top, closeup, strict=True):
            assert _gap_pt(upper.xaxis.label, lower.title, fig.dpi) >= MIN_GAP_PT
            assert _gap_pt(suptitle, upper.title, fig.dpi) >= MIN_GAP_PT
    finally:
        plt.close(fig)
