"""The weighing kernel's cull (``geometry/evidence/beam.py``): the circle of an arc's live bins,
and the verdicts that spare ATM's crossing search and pass 1 the arcs that would get nothing.
That the maps stay bit for bit the same is ``test_evidence_passes.py``'s (the one loop, which
has neither test); here each part on its own, against geometry worked out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from sonarcarve.geometry.evidence.arrays import ReadingRows
from sonarcarve.geometry.evidence.beam import (
    Beam,
    beam_of,
    clear_of_beam,
    draw_live_circle,
    meets_echo_circle,
)
from sonarcarve.geometry.evidence.model import EVIDENCE_ALIVE
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods.evidence import EvidenceMethod, EvidenceModel

BINS = 24
WIDTH = math.radians(22.5)
THRESHOLD = 1.6


@njit
def _draw(x: float, y: float, r: float, theta: float, free: np.ndarray) -> np.ndarray:
    one = np.ones(1)
    readings = ReadingRows(x * one, y * one, r * one, theta * one, WIDTH * one,
                           np.zeros(1, dtype=np.int64))
    live = np.zeros((4, 1))
    draw_live_circle(0, readings, free, THRESHOLD, live)
    return live[:, 0]


def _bin_centres(x: float, y: float, r: float, theta: float) -> np.ndarray:
    tau = theta - WIDTH / 2 + (np.arange(BINS) + 0.5) * WIDTH / BINS
    return np.stack([x + r * np.cos(tau), y + r * np.sin(tau)], axis=1)


@pytest.mark.parametrize(("first", "last"), [(0, 23), (5, 5), (3, 17), (20, 23)])
def test_the_live_circle_holds_the_live_bins_and_is_the_circle_of_their_span(
        first: int, last: int) -> None:
    """Live bins ``first .. last`` (and one carved bin between them): the circle holds each
    live centre, and its radius is the half-chord from the first centre to the last (the arc
    of one bin: just the pad), not the beam's."""
    x, y, r, theta = 1e3, -2e3, 3.0, 0.7
    free = np.full((1, BINS), 2.0 * THRESHOLD)
    free[0, first : last + 1] = 0.1
    if last - first >= 2:
        free[0, first + 1] = THRESHOLD  # carved: at T exactly
    cx, cy, rho, count = _draw(x, y, r, theta, free)
    assert count == np.count_nonzero(free[0] < THRESHOLD)
    centres = _bin_centres(x, y, r, theta)
    live = free[0] < THRESHOLD
    assert (np.hypot(centres[live, 0] - cx, centres[live, 1] - cy) <= rho).all()
    half_span = 0.5 * (last - first) * WIDTH / BINS
    assert rho == pytest.approx(r * math.sin(half_span), abs=1e-3)
    assert rho > 0.0


def test_an_arc_without_live_bins_has_an_infinite_circle() -> None:
    """No live bin: the cull must leave the arc to pass 1 (which carves it)."""
    free = np.full((1, BINS), THRESHOLD)
    cx, cy, rho, count = _draw(0.0, 0.0, 2.0, 0.0, free)
    assert (cx, cy, count) == (0.0, 0.0, 0.0)
    assert rho == math.inf


def test_a_nan_bin_counts_live_as_pass_1_weighs_it() -> None:
    free = np.full((1, BINS), THRESHOLD)
    free[0, 7] = math.nan
    *_, rho, count = _draw(0.0, 0.0, 2.0, 0.0, free)
    assert count == 1
    assert rho < 1e-3


class _Params:
    """The few model numbers :func:`beam_of` reads."""

    def __init__(self) -> None:
        self.edge_gain = 0.5
        self.range_scale = 10.0
        self.incidence_full = math.radians(10.0)
        self.incidence_zero = math.radians(30.0)
        self.viewpoint_spacing = 0.5


def _beam() -> Beam:
    """A beam from the origin along +x, range 2 m, 22.5° wide, reach 2.05 m."""
    half = 0.5 * WIDTH
    return beam_of.py_func(x=0.0, y=0.0, r=2.0, cos_axis=1.0, sin_axis=0.0, half=half,
                           cos_half=math.cos(half), step=WIDTH / BINS, free_r=1.95,
                           reach=2.05, params=_Params())


@pytest.mark.parametrize(("circle", "clear"), [
    ((2.0, 0.0, 0.3), False),  # across the echo circle, on the axis
    ((1.4, 0.0, 0.2), False),  # in the free sector
    ((2.0, 1.2, 0.1), True),  # above the upper edge
    ((2.0, -1.2, 0.1), True),  # below the lower edge
    ((2.3, 0.0, 0.2), True),  # beyond the reach
    ((50.0, 50.0, math.inf), False),  # no live bin: left to pass 1
])
def test_a_circle_is_clear_of_the_beam_beyond_its_reach_or_edges(
        circle: tuple[float, float, float], clear: bool) -> None:
    assert clear_of_beam.py_func(*circle, _beam()) == clear


@pytest.mark.parametrize(("circle", "meets"), [
    ((2.0, 0.0, 0.3), True),  # across it
    ((1.4, 0.0, 0.2), False),  # within 1.2 .. 1.6 m: inside it
    ((1.4, 0.0, 0.59), False),  # reaching 1.99 m
    ((1.4, 0.0, 0.61), True),  # reaching 2.01 m
    ((2.5, 0.0, 0.4), False),  # from 2.1 m on: beyond it
    ((0.0, 0.0, 3.0), True),  # around the origin, the echo circle inside it
])
def test_only_a_bounding_circle_meeting_the_echo_circle_can_hold_a_crossing(
        circle: tuple[float, float, float], meets: bool) -> None:
    assert meets_echo_circle.py_func(*circle, _beam()) == meets


def test_after_a_run_every_live_bin_lies_in_its_arcs_live_circle() -> None:
    """On a simulated office run the live circles hold every live bin's centre (the cull's
    premise), carving made some of them smaller than their arcs' bounding circles (the cull
    has something to cut), and the weighing redrew them as it carved."""
    readings = run_simulation(Scenario("office", 1, max_length=10.0)).readings
    method = EvidenceMethod(history_size=60)
    method.add_many(readings[:400])
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    rows = method.history.slots()
    alive = rows[model.status[rows] == EVIDENCE_ALIVE]
    live = model.free[alive] < model.threshold
    cx, cy, rho = model.live_circle[:3, alive]
    dist = np.hypot(model.bx[alive] - cx[:, None], model.by[alive] - cy[:, None])
    assert (dist[live] <= np.broadcast_to(rho[:, None], dist.shape)[live]).all()
    shrunk = rho < 0.999 * model.circle[2, alive]
    assert shrunk.any()
    # Drawn from the live bins of its time (bins are only carved), and redrawn when the
    # weighing carved some: stale only where the transmission carved one since.
    counts = live.sum(axis=1)
    assert (counts <= model.live_circle[3, alive]).all()
    assert np.mean(counts == model.live_circle[3, alive]) >= 0.9
    assert (counts < model.bins).sum() >= 10
