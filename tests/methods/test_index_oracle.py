"""The spatial index gives carving and ATM exactly the results of the all-pairs kernels.

The oracle replays the same readings through the all-pairs kernels: carving with
:func:`~sonarcarve.geometry.carve_arcs` over every live arc, ATM with its index switched off
(every live arc, oldest first). Streams are random and cover evictions and wrap-around of the
ring buffer (histories much shorter than the stream), arcs spanning many cells, huge ranges
(which overflow the index's cell limit and fall back to a scan), coincident origins and both
single ``add`` and block ``add_many`` feeding.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve import MethodConfig, Reading, ReadingBatch, make_method
from sonarcarve.geometry import ArcFate, arc_bounding_circle, carve_arcs
from sonarcarve.methods.atm import AtmModel
from sonarcarve.methods.base import SonarMethod
from sonarcarve.methods.carving import CarvingModel


def _stream(n: int, seed: int, *, spread: float, max_range: float,
            huge_share: float = 0.0) -> ReadingBatch:
    """Readings of a robot wandering over ``spread`` metres, random bearings and ranges."""
    rng = np.random.default_rng(seed)
    xy = np.mod(rng.normal(0.0, 0.05, (n, 2)).cumsum(axis=0), spread)
    for i in np.flatnonzero(rng.random(n) < 0.1):  # coincident origins: the previous one
        xy[i] = xy[max(i - 1, 0)]
    r = rng.uniform(0.05, max_range, n)
    huge = rng.random(n) < huge_share
    r[huge] = rng.uniform(50.0, 5e3, int(huge.sum()))
    r = np.round(r / 0.0254) * 0.0254 + 0.0254
    width = np.where(rng.random(n) < 0.3, rng.uniform(0.05, 2.5, n), np.nan)
    return ReadingBatch.from_arrays(
        t=np.arange(n) * 0.01, sensor=rng.integers(0, 16, n), x=xy[:, 0], y=xy[:, 1],
        theta=rng.uniform(-3.0 * math.pi, 3.0 * math.pi, n), range=r, beam_width=width,
    )


def _carving_oracle(batch: ReadingBatch, history: int, tolerance: float,
                    max_incidence: float) -> tuple[np.ndarray, ...]:
    """All-pairs carving state after the whole stream, by sequence number."""
    n = len(batch)
    phi = MethodConfig().beam_width
    width = np.where(np.isnan(batch.beam_width), phi, batch.beam_width)
    t1 = batch.theta - 0.5 * width
    t2 = batch.theta + 0.5 * width
    lo, hi = t1.copy(), t2.copy()
    bounds = np.zeros((n, 3))
    status = np.zeros(n, dtype=np.int8)
    carved = np.zeros(n, dtype=bool)
    for i in range(n):
        bounds[i] = arc_bounding_circle(batch.x[i], batch.y[i], batch.range[i], t1[i], t2[i])
        older = np.arange(max(0, i - history + 1), i, dtype=np.int64)
        carve_arcs(older, batch.x, batch.y, batch.range, lo, hi, bounds, status, carved,
                   batch.x[i], batch.y[i], batch.range[i], t1[i], t2[i], tolerance,
                   max_incidence)
    return lo, hi, bounds, status, carved


def _feed(name: str, batch: ReadingBatch, config: MethodConfig, single: bool) -> SonarMethod:
    """The method fed one reading at a time, or in blocks with single readings between."""
    method = make_method(name, config)
    if single:
        for i in range(len(batch)):
            method.add(batch[i])
    else:
        cut = len(batch) // 3
        method.add_many(batch[:cut])
        for i in range(cut, cut + 7):
            method.add(batch[i])
        method.add_many(batch[cut + 7:])
    return method


CASES = [
    # (seed, readings, history, spread m, max range m, huge share)
    (0, 600, 40, 3.0, 2.0, 0.0),
    (1, 700, 150, 8.0, 6.0, 0.0),
    (2, 500, 60, 1.0, 12.0, 0.02),  # arcs spanning many cells, some huge
    (3, 400, 400, 30.0, 3.0, 0.0),  # no eviction
    (4, 500, 1, 2.0, 2.0, 0.0),  # history of one arc
]


@pytest.mark.parametrize(("seed", "n", "history", "spread", "max_range", "huge"), CASES)
@pytest.mark.parametrize("max_incidence", [0.5 * math.pi, math.radians(17.5)])
def test_indexed_carving_equals_all_pairs(seed: int, n: int, history: int, spread: float,
                                          max_range: float, huge: float,
                                          max_incidence: float) -> None:
    batch = _stream(n, seed, spread=spread, max_range=max_range, huge_share=huge)
    config = MethodConfig(history_size=history, max_incidence=max_incidence)
    expected = _carving_oracle(batch, history, config.range_tolerance, max_incidence)
    for single in (False, True):
        method = _feed("carve", batch, config, single)
        model = method.models[0]
        assert isinstance(model, CarvingModel)
        live = method.history.slots()
        seq = np.arange(n - len(live), n)
        for got, want in zip((model.lo, model.hi, model.bounds, model.status, model.carved),
                             expected, strict=True):
            np.testing.assert_array_equal(got[live], want[seq])
        status = expected[3]
        assert model.counters() == {
            "fully_carved": int(np.sum(status == ArcFate.FULLY_CARVED)),
            "split": int(np.sum(status == ArcFate.SPLIT)),
        }


@pytest.mark.parametrize(("seed", "n", "history", "spread", "max_range", "huge"), CASES)
@pytest.mark.parametrize("name", ["atm", "combined"])
def test_indexed_atm_equals_all_pairs(seed: int, n: int, history: int, spread: float,
                                      max_range: float, huge: float, name: str) -> None:
    batch = _stream(n, seed, spread=spread, max_range=max_range, huge_share=huge)
    config = MethodConfig(history_size=history)
    indexed = _feed(name, batch, config, single=False)
    reference = make_method(name, config)
    model = next(m for m in reference.models if isinstance(m, AtmModel))
    model._use_index = False  # the all-pairs scan
    reference.add_many(batch)
    got = next(m for m in indexed.models if isinstance(m, AtmModel))
    np.testing.assert_array_equal(got.counts, model.counts)
    for slot in np.flatnonzero(model.counts):
        c = model.counts[slot]
        np.testing.assert_array_equal(np.sort(got.bearings[slot, :c]),
                                      np.sort(model.bearings[slot, :c]))
    assert got.counters() == model.counters()
    a, b = indexed.local_map(), reference.local_map()
    for field in ("reading_id", "xy", "source", "width", "max_error"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    ga, gb = indexed.finish(), reference.finish()
    np.testing.assert_array_equal(ga.xy, gb.xy)
    np.testing.assert_array_equal(ga.reading_id, gb.reading_id)


def test_local_map_is_reused_until_a_reading_arrives() -> None:
    method = make_method("carve", MethodConfig(history_size=10))
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0))
    first = method.local_map()
    assert method.local_map() is first
    assert not first.xy.flags.writeable
    method.add(Reading(0.1, 1, 0.0, 0.0, 1.0, 1.0))
    assert method.local_map() is not first
    assert len(method.local_map()) == 2
