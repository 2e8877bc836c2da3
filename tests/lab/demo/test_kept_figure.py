""":mod:`sonarcarve.lab.demo.kept_figure`: fig. 6 sorts each echo by what it truly was."""

from __future__ import annotations

import numpy as np

from sonarcarve.lab.demo import DemoResult
from sonarcarve.lab.demo.kept_figure import KEPT_METHODS, echo_fates, plot_kept_and_lost
from sonarcarve.sim.sonar import NO_ECHO, EchoKind


def test_echo_fates_sorts_points_and_the_direct_echoes_left_out() -> None:
    kind = np.array([EchoKind.DIRECT, EchoKind.CROSSTALK, NO_ECHO, EchoKind.DIRECT,
                     EchoKind.MULTIPATH, EchoKind.FLOOR, EchoKind.DIRECT])
    # The map kept readings 0, 1, 2 (a no-echo reading's point), 4 and 6.
    fates = echo_fates(kind, np.array([0, 1, 2, 4, 6]))
    assert fates.direct_point.tolist() == [True, False, False, False, True]
    assert fates.spurious_point.tolist() == [False, True, False, True, False]
    assert fates.lost_direct.tolist() == [False, False, False, True, False, False, False]


def test_fig6_draws_every_kept_point_and_every_deleted_direct_echo(doorway: DemoResult) -> None:
    import matplotlib.pyplot as plt

    fig = plot_kept_and_lost(doorway)
    try:
        panels = [ax for ax in fig.axes if ax.collections]
        assert len(panels) == len(KEPT_METHODS)  # the doorway is small: no close-up row
        kind = doorway.simulation.truth.kind
        for ax, method in zip(panels, KEPT_METHODS, strict=True):
            gmap = doorway.global_maps[method]
            lost, direct, spurious = (len(c.get_offsets()) for c in ax.collections[1:4])
            # Counted another way: direct readings whose id no map point carries.
            all_direct = np.flatnonzero(kind == EchoKind.DIRECT)
            assert lost == len(np.setdiff1d(all_direct, gmap.reading_id))
            assert direct + spurious == int(np.count_nonzero(kind[gmap.reading_id] != NO_ECHO))
            assert spurious == int(np.count_nonzero(kind[gmap.reading_id] > 0))
        assert "deleted" in " ".join(t.get_text() for t in fig.legends[0].get_texts())
    finally:
        plt.close(fig)
