"""One set of named parameters for every method, so the CLI and experiments can build any."""

from __future__ import annotations

import math
from dataclasses import dataclass

from sonarcarve.history import DEFAULT_HISTORY_SIZE
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
    min_transversal : float
        ψ, radians: ATM's minimum transversal angle (eq. 2.2, 5.4).
    range_resolution : float
        Range quantum of the sensors, metres (paper: one inch); scales ATM's error bound (5.4).
    """

    history_size: int = DEFAULT_HISTORY_SIZE
    beam_width: float = DEFAULT_BEAM_WIDTH
    range_tolerance: float = 0.0
    min_transversal: float = math.radians(30.0)
    range_resolution: float = 0.0254
