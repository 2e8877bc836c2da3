"""Repeated echoes count once: each echo of a batch gives the earlier arcs of its sensor that it
repeats (:func:`~sonarcarve.geometry.repeats.is_repeat`: ``| |P2 - P1| - |r1 - r2| | <= ε``) the
weight factor ``repeat_weight`` (:func:`repeat_kernel`). ``docs/carved-grid.md``, "Repeated echoes
count once".
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.repeats import is_repeat
from sonarcarve.typing import BoolArray, FloatArray, SlotArray

__all__ = ["Echo", "repeat_kernel"]


class Echo(NamedTuple):
    """One arc as :func:`~sonarcarve.geometry.repeats.is_repeat` compares it (metres,
    radians)."""

    x: float
    y: float
    r: float
    theta: float
    half: float  # half the beam's width


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
    Returns how many slots were marked.

    The arrays in groups: the factors and their bookkeeping ``chain .. marked``; the batch,
    ``seqs, first, no_echo`` and its readings ``sensor .. half`` (half widths); the history's
    rows ``hsensor .. hwidth`` (full widths) and ``capacity``; the rule, ``tol`` (ε) and
    ``factor``. Separate arrays, not bundles: the grid calls this once a batch from Python, and
    in this kernel, which counts references (it allocates), bundles of arrays handed to the
    steps cost an atomic increment and decrement per array at each call (2026-12-05, a
    5-reading batch of the office log: 4.0 µs a call with separate arrays, 5.5 with the
    factors and the two sets of rows as bundles); the arcs compared are bundles of numbers,
    :class:`Echo`, which cost nothing."""
    size = chain.shape[0]
    rows, count = _echo_rows(no_echo)
    start = max(0, first - capacity + 1)
    before = _same_sensor_before(hsensor, sensor, rows, count, start, first, capacity)
    n_marked = 0
    for k in range(x.shape[0]):
        if no_echo[k]:
            continue
        echo = Echo(x[k], y[k], r[k], theta[k], half[k])
        oldest = max(0, seqs[k] - capacity + 1)
        # The earlier arcs of sensor k within the window, newest first: the same arcs, so the
        # same results, as trying every arc of the window, most of which are other sensors'.
        p = before[seqs[k] - start]
        while p >= oldest:
            # An arc with the factor already needs no comparing.
            own = p >= first  # one of the batch's arcs (by number), else the history's (slot)
            if (batch_chain[p - first] if own else chain[p % size]) != factor:
                if own:
                    j = rows[p - first]
                    earlier = Echo(x[j], y[j], r[j], theta[j], half[j])
                else:
                    s = p % size
                    earlier = Echo(hx[s], hy[s], hr[s], htheta[s], 0.5 * hwidth[s])
                if _repeats(earlier, echo, tol):
                    n_marked = _give_factor(chain, batch_chain, seen_seq, marked, p, first,
                                            factor, n_marked)
            p = before[p - start]
    return n_marked


@compiled_inline
def _echo_rows(no_echo: BoolArray) -> tuple[npt.NDArray[np.int64], int]:
    """The batch's row of each of its arcs, ``first + i`` in row ``rows[i]`` (a no-echo
    reading has no arc), and how many arcs."""
    rows = np.empty(no_echo.shape[0], dtype=np.int64)
    count = 0
    for k in range(no_echo.shape[0]):
        if not no_echo[k]:
            rows[count] = k
            count += 1
    return rows, count


@compiled_inline
def _repeats(earlier: Echo, echo: Echo, tol: float) -> bool:
    """Whether ``echo`` repeats the ``earlier`` arc of its sensor
    (:func:`~sonarcarve.geometry.repeats.is_repeat`, ε = ``tol``)."""
    return is_repeat(earlier.x, earlier.y, earlier.r, earlier.theta, earlier.half, echo.x,
                     echo.y, echo.r, echo.theta, echo.half, tol)


@compiled_inline
def _give_factor(chain: FloatArray, batch_chain: FloatArray, seen_seq: npt.NDArray[np.int64],
                 marked: SlotArray, p: int, first: int, factor: float, n_marked: int) -> int:
    """Arc ``p`` takes ``factor``; a history arc also forgets its seen state and is marked.
    Returns how many slots are marked now."""
    if p >= first:
        batch_chain[p - first] = factor
        return n_marked
    s = p % chain.shape[0]
    chain[s] = factor
    seen_seq[s] = -1
    marked[n_marked] = s
    return n_marked + 1


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
