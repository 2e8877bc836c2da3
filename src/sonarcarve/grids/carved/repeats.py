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

__all__ = ["Chains", "Echo", "EchoRows", "repeat_kernel"]


class Chains(NamedTuple):
    """The repeats' weight factors and their bookkeeping (updated in place)."""

    chain: FloatArray  # (storage,) by slot: each history arc's factor (1: repeated by none)
    batch_chain: FloatArray  # (echoes,): the batch's own arcs' factors, from its first arc
    seen_seq: npt.NDArray[np.int64]  # (storage,): stale_slots' record, -1 forces a recompute
    marked: SlotArray  # (capacity,): the slots whose factor this batch set, in order


class Echo(NamedTuple):
    """One arc as :func:`~sonarcarve.geometry.repeats.is_repeat` compares it (metres,
    radians)."""

    x: float
    y: float
    r: float
    theta: float
    half: float  # half the beam's width


class EchoRows(NamedTuple):
    """Arcs by row: a batch's readings (``half``: half widths), or the history's rows by slot
    (``half``: full widths, :attr:`~sonarcarve.history.SonarHistory.beam_width`), read only."""

    sensor: npt.NDArray[np.int64]
    x: FloatArray
    y: FloatArray
    r: FloatArray
    theta: FloatArray
    half: FloatArray


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

    The grid calls it once a batch, from Python, so its bundles come field by field (a
    NamedTuple costs numba's dispatcher microseconds a call, ``model.py``), in order:
    :class:`Chains` ``chain .. marked``; the batch, ``seqs, first, no_echo`` and
    :class:`EchoRows` ``sensor .. half``; the history's :class:`EchoRows` ``hsensor ..
    hwidth`` and ``capacity``; the rule, ``tol`` (ε) and ``factor``."""
    chains = Chains(chain, batch_chain, seen_seq, marked)
    batch = EchoRows(sensor, x, y, r, theta, half)
    past = EchoRows(hsensor, hx, hy, hr, htheta, hwidth)
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
            if (not _has_factor(chains, p, first, factor)
                    and _repeats(_earlier(p, first, rows, batch, past, size), echo, tol)):
                n_marked = _give_factor(chains, p, first, factor, n_marked)
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
def _has_factor(chains: Chains, p: int, first: int, factor: float) -> bool:
    """Whether arc ``p`` has the factor already (a batch arc's by number, a history arc's by
    slot): nothing to compare."""
    if p >= first:
        return bool(chains.batch_chain[p - first] == factor)
    return bool(chains.chain[p % chains.chain.shape[0]] == factor)


@compiled_inline
def _earlier(p: int, first: int, rows: npt.NDArray[np.int64], batch: EchoRows,
             past: EchoRows, size: int) -> Echo:
    """Arc ``p``: the batch's, by its row, if ``p >= first``, else the history's, in slot
    ``p % size`` (its row holds the full beam width)."""
    if p >= first:
        j = rows[p - first]
        return Echo(batch.x[j], batch.y[j], batch.r[j], batch.theta[j], batch.half[j])
    s = p % size
    return Echo(past.x[s], past.y[s], past.r[s], past.theta[s], 0.5 * past.half[s])


@compiled_inline
def _repeats(earlier: Echo, echo: Echo, tol: float) -> bool:
    """Whether ``echo`` repeats the ``earlier`` arc of its sensor
    (:func:`~sonarcarve.geometry.repeats.is_repeat`, ε = ``tol``)."""
    return is_repeat(earlier.x, earlier.y, earlier.r, earlier.theta, earlier.half, echo.x,
                     echo.y, echo.r, echo.theta, echo.half, tol)


@compiled_inline
def _give_factor(chains: Chains, p: int, first: int, factor: float, n_marked: int) -> int:
    """Arc ``p`` takes ``factor``; a history arc also forgets its seen state and is marked.
    Returns how many slots are marked now."""
    if p >= first:
        chains.batch_chain[p - first] = factor
        return n_marked
    s = p % chains.chain.shape[0]
    chains.chain[s] = factor
    chains.seen_seq[s] = -1
    chains.marked[n_marked] = s
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
