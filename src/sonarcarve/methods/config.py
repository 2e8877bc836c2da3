"""One set of named parameters for every method, so the CLI and experiments can build any."""

from __future__ import annotations

import math
from dataclasses import dataclass

from sonarcarve.constants import POLAROID_RANGE_RESOLUTION
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.methods.carving import DEFAULT_RANGE_TOLERANCE
from sonarcarve.readings import DEFAULT_BEAM_WIDTH

__all__ = ["MethodConfig"]


@dataclass(frozen=True)
class MethodConfig:
    """Parameters shared by the sonar methods; each method reads the ones it needs.

    Attributes
    ----------
    history_size : int
        Arcs kept in the history (paper, section 5-C: 250).
    beam_width : float
        Default beam width φ, radians, for readings that carry none (paper: 22.5°).
    range_tolerance : float
        ε, metres: a newer reading's freespace ends at ``r - ε`` (0 is the paper exactly).
        Default 5 cm, measured with ``benchmarks/range_tolerance.py`` (1-inch quantised ranges,
        noise σ ≤ 2.5 cm): ε = 0 fully carved 15-39 % of true echoes, 5 cm at most 8.5 %, at a
        median point error within 2.5 mm of the best ε (see :mod:`sonarcarve.methods.carving`).
    min_transversal : float
        ψ, radians: ATM's minimum transversal angle (eq. 2.2, 5.4). Default 20°, measured with
        ``benchmarks/min_transversal.py``: against 30° it needs a third less travel per crossing
        (eq. 2.2) and, being below φ, lets two readings of one sensor cross; ATM's unprocessed
        share fell from 29 % to 22 % at equal point error (see :mod:`sonarcarve.methods.atm`).
    range_resolution : float
        Range quantum of the sensors, metres (paper: one inch); scales ATM's error bound (5.4).
    max_incidence : float
        β in ``[0, π/2]``, radians: specular-aware carving (beyond the paper), where a newer
        reading does not carve the points of an older arc whose implied surface it would see
        at an incidence above β (see :mod:`sonarcarve.geometry`). Default π/2
        (:data:`~sonarcarve.geometry.NO_INCIDENCE_LIMIT`): off, the paper.
    """

    history_size: int = DEFAULT_HISTORY_SIZE
    beam_width: float = DEFAULT_BEAM_WIDTH
    range_tolerance: float = DEFAULT_RANGE_TOLERANCE
    min_transversal: float = math.radians(20.0)
    range_resolution: float = POLAROID_RANGE_RESOLUTION
    max_incidence: float = NO_INCIDENCE_LIMIT
