"""The spatial index (geometry/index.py): queries return every arc that can meet the region."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from sonarcarve.geometry import NO_INCIDENCE_LIMIT, ArcFate, arc_bounding_circle, carve_arc
from sonarcarve.geometry.index import (
    MAX_CELLS,
    arc_box,
    index_insert,
    index_remove,
    make_index,
    query_box,
    query_sector,
    query_sector_circles,
)
from sonarcarve.geometry.sector import make_sector


@given(st.floats(-50, 50), st.floats(-50, 50), st.floats(0.01, 40), st.floats(-10, 10),
       st.floats(0.0, 3.0))
def test_arc_box_contains_the_arc(ox: float, oy: float, r: float, lo: float,
                                  width: float) -> None:
    xmin, xmax, ymin, ymax = arc_box(ox, oy, r, lo, lo + width)
    tau = np.linspace(lo, lo + width, 200)
    px, py = ox + r * np.cos(tau), oy + r * np.sin(tau)
    assert np.all((px >= xmin) & (px <= xmax) & (py >= ymin) & (py <= ymax))


def test_queries_after_inserts_and_removals_match_brute_force() -> None:
    rng = np.random.default_rng(3)
    storage = 200
    index = make_index(storage, cell_size=0.7)
    boxes = np.zeros((storage, 4))
    live = np.zeros(storage, dtype=bool)
    out = np.zeros(storage, dtype=np.int64)
    for step in range(3000):
        slot = int(rng.integers(storage))
        if live[slot]:
            index_remove(index, slot)
            live[slot] = False
        else:
            ox, oy = rng.uniform(-5, 5, 2)
            r = rng.choice([rng.uniform(0.1, 3.0), rng.uniform(20.0, 200.0)], p=[0.95, 0.05])
            lo = rng.uniform(-math.pi, math.pi)
            boxes[slot] = arc_box(ox, oy, r, lo, lo + rng.uniform(0, 1.0))
            index_insert(index, slot, *boxes[slot])
            live[slot] = True
        if step % 10 == 0:
            qx, qy = rng.uniform(-6, 6, 2)
            box = (qx, qx + rng.uniform(0, 3), qy, qy + rng.uniform(0, 3))
            found = query_box(index, *box, out)
            got = set(out[:found].tolist())
            assert len(got) == found  # each arc once
            meets = (live & (boxes[:, 0] <= box[1]) & (boxes[:, 1] >= box[0])
                     & (boxes[:, 2] <= box[3]) & (boxes[:, 3] >= box[2]))
            assert set(np.flatnonzero(meets).tolist()) <= got
            assert got <= set(np.flatnonzero(live).tolist())
    assert index.entries.max() <= MAX_CELLS
    assert query_box(index, -1e4, 1e4, -1e4, 1e4, out) == -1  # too many cells: scan instead


def test_sector_query_by_circles_keeps_every_arc_the_sector_carves() -> None:
    """query_sector_circles returns, once each, live arcs of query_sector's answer, and among
    them every arc the closed form (carve_arc, the all-pairs reference's step) changes."""
    rng = np.random.default_rng(4)
    storage = 300
    index = make_index(storage)
    arcs = np.zeros((storage, 5))  # ox, oy, r, lo, hi
    bounds = np.zeros((storage, 3))
    live = np.zeros(storage, dtype=bool)
    out = np.zeros(storage, dtype=np.int64)
    near = np.zeros(storage, dtype=np.int64)
    changed_total = kept_total = near_total = 0
    for step in range(4000):
        slot = int(rng.integers(storage))
        if live[slot]:
            index_remove(index, slot)
            live[slot] = False
        else:
            ox, oy = rng.uniform(-4, 4, 2)
            r = rng.choice([rng.uniform(0.1, 3.0), rng.uniform(20.0, 60.0)], p=[0.95, 0.05])
            lo = rng.uniform(-math.pi, math.pi)
            hi = lo + rng.uniform(0, 1.0)
            arcs[slot] = ox, oy, r, lo, hi
            bounds[slot] = arc_bounding_circle(ox, oy, r, lo, hi)
            index_insert(index, slot, *arc_box(ox, oy, r, lo, hi))
            live[slot] = True
        if step % 10 == 0:
            fx, fy = rng.uniform(-5, 5, 2)
            f_lo = rng.uniform(-4.0, 4.0)
            f_hi = f_lo + rng.uniform(0.0, 1.5)
            fr = rng.uniform(0.2, 4.0)
            sector = make_sector(fx, fy, fr, f_lo, f_hi, 0.0, math.pi / 2)
            found = query_sector_circles(index, sector, bounds, out)
            got = out[:found].tolist()
            assert len(set(got)) == found  # each arc once
            near_found = query_sector(index, sector, near)
            assert set(got) <= set(near[:near_found].tolist())
            assert set(got) <= set(np.flatnonzero(live).tolist())
            # Every argument given (ε = 0, β = π/2: the paper): numba's dispatcher resolves a
            # call that leaves a default out in Python, 0.1 ms each (4 of this test's 6 s).
            freespace = (fx, fy, fr, f_lo, f_hi, 0.0, NO_INCIDENCE_LIMIT)
            changed = {i for i in np.flatnonzero(live).tolist()
                       if carve_arc(*arcs[i], *freespace)[0] != ArcFate.UNCHANGED}
            assert changed <= set(got)
            changed_total += len(changed)
            kept_total += found
            near_total += near_found
    assert changed_total > 100
    assert kept_total < 0.5 * near_total  # the circles do reject most arcs near the sector
