"""What carving did to an arc: one code for a single carving step and for an arc's state."""

from __future__ import annotations

from enum import IntEnum

__all__ = ["ALIVE", "FULLY_CARVED", "SHRUNK", "SPLIT", "UNCHANGED", "ArcFate"]


class ArcFate(IntEnum):
    """The fate of an arc under carving (paper, section 3).

    One carving step (:func:`~sonarcarve.geometry.carve_arc`) returns one of the four codes. An
    arc's state over its life (``CarvingModel.status``, ``Estimates.fate``) only ever holds
    ``ALIVE`` (the same code as ``UNCHANGED``: the arc still yields a point, whether or not it
    has shrunk), ``FULLY_CARVED`` or ``SPLIT``.

    Examples
    --------
    >>> ArcFate(0).name, ArcFate.ALIVE is ArcFate.UNCHANGED
    ('UNCHANGED', True)
    >>> [fate.name for fate in ArcFate]  # ALIVE is an alias, not a fifth member
    ['UNCHANGED', 'SHRUNK', 'FULLY_CARVED', 'SPLIT']
    """

    UNCHANGED = 0  #: the sector does not overlap the arc (beyond a sliver)
    SHRUNK = 1  #: the remainder is one shorter interval
    FULLY_CARVED = 2  #: the sector covers the whole arc: C'_i is empty; the arc is removed
    SPLIT = 3  #: the remainder is two or more pieces: the arc is removed (section 3)
    ALIVE = 0  # an alias on purpose: the state of an arc that carving left in the map


# The codes as plain ints for the compiled kernels (numba freezes int globals as constants).
UNCHANGED = int(ArcFate.UNCHANGED)
SHRUNK = int(ArcFate.SHRUNK)
FULLY_CARVED = int(ArcFate.FULLY_CARVED)
SPLIT = int(ArcFate.SPLIT)
ALIVE = int(ArcFate.ALIVE)
