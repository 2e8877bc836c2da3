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
    n_marked = 0
    for k in range(x.shape[0]):
        if no_echo[k]:
            continue
        for p in range(max(0, seqs[k] - capacity + 1), seqs[k]):
            if p >= first:
                j = rows[p - first]
                if sensor[j] != sensor[k] or batch_chain[p - first] == factor:
                    continue
                x1, y1, r1, t1, h1 = x[j], y[j], r[j], theta[j], half[j]
            else:
                s = p % size
                if hsensor[s] != sensor[k] or chain[s] == factor:
                    continue
                x1, y1, r1, t1, h1 = hx[s], hy[s], hr[s], htheta[s], 0.5 * hwidth[s]
            if not is_repeat(x1, y1, r1, t1, h1, x[k], y[k], r[k], theta[k], half[k], tol):
                continue
            if p >= first:
                batch_chain[p - first] = factor
            else:
                chain[p % size] = factor
                seen_seq[p % size] = -1
                marked[n_marked] = p % size
                n_marked += 1
    return n_marked
