"""Exact arc and sector geometry (paper, sections 2-D and 3), one module per concept.

* :mod:`~sonarcarve.geometry.intervals`: carving an arc by a newer reading's freespace sector in
  closed form (eq. 3.2-3.5): :func:`carve_arc`, :func:`arc_remainder`, :func:`carve_arcs`.
* :mod:`~sonarcarve.geometry.specular`: the specular-aware incidence cut (beyond the paper).
* :mod:`~sonarcarve.geometry.circles`: circle-circle intersections for ATM.
* :mod:`~sonarcarve.geometry.bounds`: a circle around an arc, a cheap first test in carving.
* :mod:`~sonarcarve.geometry.fate`: :class:`ArcFate`, what carving did to an arc.
* :mod:`~sonarcarve.geometry.sector`, :mod:`~sonarcarve.geometry.circular` and
  :mod:`~sonarcarve.geometry._compiled`: the kernels' plumbing (a prepared sector, circular
  intervals and scratch arrays, the numba decorator and its cache key).
"""

from __future__ import annotations

from sonarcarve.geometry.bounds import arc_bounding_circle
from sonarcarve.geometry.circles import (
    CircleIntersections,
    circle_intersections,
    circle_pair,
    common_chord,
)
from sonarcarve.geometry.fate import ArcFate
from sonarcarve.geometry.intervals import MIN_PIECE, arc_remainder, carve_arc, carve_arcs
from sonarcarve.geometry.specular import NO_INCIDENCE_LIMIT

__all__ = [
    "MIN_PIECE",
    "NO_INCIDENCE_LIMIT",
    "ArcFate",
    "CircleIntersections",
    "arc_bounding_circle",
    "arc_remainder",
    "carve_arc",
    "carve_arcs",
    "circle_intersections",
    "circle_pair",
    "common_chord",
]
