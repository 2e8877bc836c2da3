"""Repeats: two echoes of one sensor that most likely come from the same point (beyond the paper).

A sonar that drives towards (or away from) the point it hears hears it again at a range that
changes by the distance it drove (exactly, for a point on its line of motion). Two echoes of
one sensor, origins ``P1``, ``P2`` and ranges ``r1``, ``r2``, are a *repeat* when

* their origins are more than ``2 ε`` apart (``ε`` the range tolerance): a sensor standing
  still or creeping along a wall (2-4.5 cm a ring cycle) hears the same range again within the
  range noise, and would otherwise "repeat" every echo of a side wall (the carved grid's review
  finding: a 16-sonar ring lost a whole side wall);
* their circles are internally tangent within ``ε``: ``| |P2 - P1| - |r1 - r2| | <= ε``;
* the tangent point lies inside both beams. It lies on the line through both origins, beyond
  the smaller circle's centre: ahead of ``P2`` in the direction ``P2 - P1`` when the range
  shrank (``r1 >= r2``, the sensor drove towards it), behind ``P2`` otherwise.

What a repeat says: both ranges fit one static reflector inside both beams while the sensor
moved more than ``2 ε`` roughly along its axis. It does not say the reflector is the tangent
point: for short travel every static point well inside the beam fits within ``ε`` (a point 3 m
away and 10° off the motion is a repeat after 0.1-1 m of travel, 0.52 m from the tangent point;
review rev9), which is why the test is used as evidence that the echo is real, not to place it.
Echoes off a wall approached at an angle, crosstalk (another sensor's ping, whose path length
changes differently with the motion) and floor echoes (a constant range) rarely line up so:
``benchmarks/repeat_echoes.py`` measured 0-4 % of spurious echoes with a repeat within 6 s,
against 19-33 % of the direct echoes evidence carving lost (8-19 % of those it kept).

The paper's section 6 proposes certainty values per point; this is one piece of evidence for
them (the ``repeated`` feature of :class:`~sonarcarve.methods.evidence.ConfidenceModel`). The
carved grid (``grids/carved/repeats.py``) calls :func:`is_repeat` for another purpose, to
stop counting a sensor's repeats as independent evidence.

What is exact: the tangency and beam tests on the readings' own numbers; nothing is binned.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.typing import FloatArray

__all__ = ["is_repeat", "mark_repeats"]


@compiled_inline
def _within_beam(bearing: float, theta: float, half: float) -> bool:
    """Whether ``bearing`` lies within ``half`` of the beam axis ``theta`` (both wrapped)."""
    off = bearing - theta
    off -= 2.0 * math.pi * math.floor((off + math.pi) / (2.0 * math.pi))
    return abs(off) <= half


@compiled_inline
def is_repeat(x1: float, y1: float, r1: float, theta1: float, half1: float,
              x2: float, y2: float, r2: float, theta2: float, half2: float,
              tolerance: float) -> bool:
    """Whether the echoes ``(x1, y1, r1)`` (beam ``theta1 ± half1``) and ``(x2, y2, r2)``
    (beam ``theta2 ± half2``) of one sensor are a repeat (module docstring): origins more than
    ``2 tolerance`` apart, circles internally tangent within ``tolerance``, the tangent point's
    bearing inside both beams. Symmetric in the two echoes; metres and radians."""
    dx = x2 - x1
    dy = y2 - y1
    d = math.sqrt(dx * dx + dy * dy)
    dr = r1 - r2
    if not d > 2.0 * tolerance or not abs(d - abs(dr)) <= tolerance:
        return False  # "not" so that NaN fails too
    # The tangent point is seen from both origins along the line of motion: in the direction
    # P1 -> P2 when the range shrank, in the direction P2 -> P1 when it grew.
    bearing = math.atan2(dy, dx) if dr >= 0.0 else math.atan2(-dy, -dx)
    return _within_beam(bearing, theta1, half1) and _within_beam(bearing, theta2, half2)


#: Relative slack of :func:`_may_repeat`'s squared test: far above its rounding errors (a few
#: units in the last place), far below any tolerance that matters; and an absolute one, for
#: reaches whose square would lose precision as a subnormal number (below 1e-154 m).
_SLACK = 1e-9
_FLOOR = 1e-290


@compiled_inline
def _may_repeat(x: FloatArray, y: FloatArray, r: FloatArray, sensor: npt.NDArray[np.int64],
                xj: float, yj: float, rj: float, sj: int, tolerance: float,
                flags: npt.NDArray[np.bool_]) -> None:
    """``flags[i]``: row ``i`` (of the arrays, slices of the history's rows) might repeat the
    echo ``(xj, yj, rj)`` of sensor ``sj``: the same sensor, and the squared distance ``d²``
    of the origins within :func:`is_repeat`'s bounds squared, ``(|Δr| - ε)² <= d² <= (|Δr|
    + ε)²`` and ``d² > (2 ε)²``, each widened by :data:`_SLACK` and :data:`_FLOOR`. Every pair
    that :func:`is_repeat` accepts is flagged (its tests, ``| d - |Δr| | <= ε`` and ``d > 2 ε``,
    imply these up to rounding errors far below the slack), and a NaN is never a repeat, so
    the flags drop only pairs it rejects. No branch and indices from 0: the compiler tests
    several rows at once."""
    least2 = 4.0 * tolerance * tolerance * (1.0 - _SLACK) - _FLOOR
    for i in range(flags.shape[0]):
        dx = xj - x[i]
        dy = yj - y[i]
        d2 = dx * dx + dy * dy
        change = abs(r[i] - rj)
        far = change + tolerance
        near = max(change - tolerance, 0.0)
        flags[i] = ((sensor[i] == sj) & (d2 <= far * far * (1.0 + _SLACK) + _FLOOR)
                    & (d2 >= near * near * (1.0 - _SLACK) - _FLOOR) & (d2 >= least2))


@compiled
def mark_repeats(first: int, count: int, capacity: int, x: FloatArray, y: FloatArray,
                 r: FloatArray, theta: FloatArray, beam_width: FloatArray,
                 sensor: npt.NDArray[np.int64], repeated: FloatArray, tolerance: float) -> int:
    """Mark the arcs of sequence numbers ``first .. first + count - 1`` of a history ring
    (``n`` rows, arc ``s`` in row ``s % n``), in order: each new arc's ``repeated`` is reset to
    0, then set to 1, with that of every older arc it repeats (:func:`is_repeat`), among the
    ``capacity - 1`` arcs before it (those still in the history) of the same sensor.

    Each pair is judged once, when its newer arc arrives, from the two readings alone, so the
    marks are the same whether the arcs come one at a time or in blocks (the block's rows and
    the up to ``capacity - 1`` stored before it must all be in the ring: ``count + min(first,
    capacity - 1) <= n``, which the history's first block of twice its capacity meets).
    Returns how many pairs were repeats.

    The older rows are first flagged by :func:`_may_repeat` (a loop the compiler runs on
    several rows at once), and :func:`is_repeat` judges the flagged ones, oldest first; eight
    flags are read as one word, so the rows of a word with none set cost one test. The same
    pairs in the same order as judging every row of the sensor (which this replaced: 0.78 µs
    an arc at history 1,000)."""
    storage = x.shape[0]
    pairs = 0
    # Flags of one run of rows, from index 0, whole words of 8 (bools are one byte each).
    flags = np.zeros((max(capacity, 1) + 7) // 8 * 8, dtype=np.bool_)
    words = flags.view(np.uint64)
    for sequence in range(first, first + count):
        j = sequence % storage
        repeated[j] = 0.0
        oldest = max(0, sequence - capacity + 1)
        start = oldest % storage
        end = start + sequence - oldest
        xj = x[j]
        yj = y[j]
        rj = r[j]
        # The older rows in two runs (the ring wraps), oldest first.
        for lo, hi in ((start, min(end, storage)), (0, max(end - storage, 0))):
            m = hi - lo
            _may_repeat(x[lo:hi], y[lo:hi], r[lo:hi], sensor[lo:hi], xj, yj, rj, sensor[j],
                        tolerance, flags[:m])
            for w in range((m + 7) // 8):
                if words[w] == 0:
                    continue
                for k in range(8 * w, min(8 * w + 8, m)):
                    i = lo + k
                    if flags[k] and is_repeat(
                            x[i], y[i], r[i], theta[i], 0.5 * beam_width[i], xj, yj, rj,
                            theta[j], 0.5 * beam_width[j], tolerance):
                        repeated[i] = 1.0
                        repeated[j] = 1.0
                        pairs += 1
    return pairs
