"""Repeated echoes count once: each echo of a batch gives the earlier arcs of its sensor that it
repeats (:func:`~sonarcarve.geometry.repeats.is_repeat`: ``| |P2 - P1| - |r1 - r2| | <= ε``) the
weight factor ``repeat_weight`` (:func:`repeat_kernel`). ``docs/carved-grid.md``, "Repeated echoes
count once".
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled
from sonarcarve.geometry.repeats import is_repeat
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = ["repeat_kernel"]


@compiled
def repeat_kernel(chain: FloatArray, batch_chain: FloatArray,
                  seen_seq: npt.NDArray[np.int64], marked: SlotArray,
                  seqs: npt.NDArray[np.int64], first: int, no_echo: BoolArray,
                  sensor: npt.NDArray[np.int64], x: FloatArray, y: FloatArray, r: FloatArray,
                  theta: FloatArray, half: FloatArray, hsensor: npt.NDArray[np.int64],
                  hx: FloatArray, hy: FloatArray, hr: FloatArray, htheta: FloatArray,
                  hwidth: FloatArray, capacity: int, tol: float, factor: float) -> int:
    """For each echo ``k`` of a batch (arc ``seqs[k]``), give every earlier arc of the same
    sensor still in the history that the echo repeats
    (:func:`~sonarcarve.geometry.repeats.is_repeat`) the weight factor
    ``factor``: in ``batch_chain[p - first]`` if it is an arc of the batch (``first``: the
    batch's first arc), else in ``chain`` (by slot, rows ``hsensor..hwidth`` of the history),
    which then forgets it had seen that arc's state (``seen_seq`` -1) so that the next read
    recomputes its weight, and whose slot goes into ``marked`` (only arcs whose factor was 1, so
    that 1 undoes the marks; each at most once, so ``marked`` needs ``capacity`` places).
    Returns how many slots were marked."""
    size = chain.shape[0]
    rows = np.empty(x.shape[0], dtype=np.int64)  # the row of the batch's arc first + i
    count = 0
    for k in range(x.shape[0]):
        if not no_echo[k]:
            rows[count] = k
            count += 1
    start = max(0, first - capacity + 1)
    before = _same_sensor_before(hsensor, sensor, rows, count, start, first, capacity)
    n_marked = 0
    for k in range(x.shape[0]):
        if no_echo[k]:
            continue
        oldest = max(0, seqs[k] - capacity + 1)
        # The earlier arcs of sensor k within the window, newest first: the same arcs, so the
        # same results, as trying every arc of the window, most of which are other sensors'.
        p = before[seqs[k] - start]
        while p >= oldest:
            if p >= first:
                j = rows[p - first]
                if batch_chain[p - first] == factor:
                    p = before[p - start]
                    continue
                x1, y1, r1, t1, h1 = x[j], y[j], r[j], theta[j], half[j]
            else:
                s = p % size
                if chain[s] == factor:
                    p = before[p - start]
                    continue
                x1, y1, r1, t1, h1 = hx[s], hy[s], hr[s], htheta[s], 0.5 * hwidth[s]
            if is_repeat(x1, y1, r1, t1, h1, x[k], y[k], r[k], theta[k], half[k], tol):
                if p >= first:
                    batch_chain[p - first] = factor
                else:
                    chain[p % size] = factor
                    seen_seq[p % size] = -1
                    marked[n_marked] = p % size
                    n_marked += 1
            p = before[p - start]
    return n_marked


#: Sensor numbers from 0 to below this many times the window's length (plus 64) get their newest
#: arc looked up in an array; others by scanning back (the same answer, slower).
_SPAN_PER_ARC = 4


@compiled
def _same_sensor_before(hsensor: npt.NDArray[np.int64], sensor: npt.NDArray[np.int64],
                        rows: npt.NDArray[np.int64], count: int, start: int, first: int,
                        capacity: int) -> npt.NDArray[np.int64]:
    """For each arc ``p`` from ``start`` to the batch's last (``first + count - 1``; those before
    ``first`` in the history's slots ``p % size`` of ``hsensor``, the batch's ``count`` echoes in
    rows ``rows`` of ``sensor``), at ``p - start``: the newest earlier arc of the same sensor
    from ``start`` on and at most ``capacity - 1`` arcs earlier (older ones leave the history
    first), else -1."""
    size = hsensor.shape[0]
    n = first + count - start
    arc_sensor = np.empty(n, dtype=np.int64)
    for p in range(start, first):
        arc_sensor[p - start] = hsensor[p % size]
    for i in range(count):
        arc_sensor[first + i - start] = sensor[rows[i]]
    before = np.full(n, -1, dtype=np.int64)
    if n == 0:
        return before
    if arc_sensor.min() >= 0 and arc_sensor.max() < _SPAN_PER_ARC * n + 64:
        newest = np.full(arc_sensor.max() + 1, -1, dtype=np.int64)  # position, by sensor
        for i in range(n):
            q = newest[arc_sensor[i]]
            if q >= 0 and i - q < capacity:
                before[i] = start + q
            newest[arc_sensor[i]] = i
    else:
        for i in range(n):
            for q in range(i - 1, max(-1, i - capacity), -1):
                if arc_sensor[q] == arc_sensor[i]:
                    before[i] = start + q
                    break
    return before
