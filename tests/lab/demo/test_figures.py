""":mod:`sonarcarve.lab.demo.figures`: figures 1-3 show the paper's four methods only."""

from __future__ import annotations

import dataclasses
import io
from collections.abc import Callable
from typing import TYPE_CHECKING

import pytest

from sonarcarve.lab.demo import PAPER_METHODS, DemoResult
from sonarcarve.lab.demo.figures import plot_error_by_range, plot_global_maps

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _png(fig: Figure) -> bytes:
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=40)
    plt.close(fig)
    return buffer.getvalue()


@pytest.mark.parametrize("plot", [plot_global_maps, plot_error_by_range])
def test_evidence_carving_leaves_the_paper_figures_as_they_were(
        doorway: DemoResult, plot: Callable[[DemoResult], Figure]) -> None:
    assert "evidence" in doorway.global_maps
    paper_only = dataclasses.replace(doorway, methods=tuple(
        row for row in doorway.methods if row.method in PAPER_METHODS))
    assert len(paper_only.methods) == len(PAPER_METHODS)
    assert _png(plot(doorway)) == _png(plot(paper_only))
