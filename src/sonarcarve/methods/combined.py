"""Arc carving and ATM on one history (paper, sections 4 and 5-A).

Storing the 6-tuple ``(x, y, r, θ, θ1, θ2)`` lets the two run "in parallel using the same data,
without interfering with each other" (section 5-A): here they are two models over one
:class:`~sonarcarve.history.SonarHistory`, each with its own per-row state, and the map keeps,
for every arc, "the most accurate data available from each technique" (section 4).
"""

from __future__ import annotations

import numpy as np

from sonarcarve.constants import DEFAULT_BEAM_WIDTH, POLAROID_RANGE_RESOLUTION
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.history import DEFAULT_HISTORY_SIZE
from sonarcarve.methods.atm import AtmModel
from sonarcarve.methods.base import Estimates, SonarMethod
from sonarcarve.methods.carving import CarvingModel
from sonarcarve.methods.config import (
    DEFAULT_MIN_TRANSVERSAL,
    DEFAULT_RANGE_TOLERANCE,
    MethodConfig,
)

__all__ = ["CombinedMethod", "combine_carving_atm"]


def combine_carving_atm(carving: Estimates, atm: Estimates) -> Estimates:
    """Per arc, the better of carving's and ATM's estimates (section 4).

    * ``alive``: carving's. An arc that carving removed (fully carved or split) is gone from the
      combined map even if ATM has crossings for it: the freespace of a newer reading says the
      echo did not come from anywhere on the arc (or from one connected piece of it), and that
      evidence is newer than any crossing, which may also be a spurious coincidence of two
      circles. Dropping it is what makes carving remove spurious returns (section 5-C).
    * the point, ``width``, ``max_error`` and ``source``: those of the estimate with the smaller
      ``max_error``, ATM's only where it has at least one kept crossing (its fallback is the
      centerline point, never better than carving's). Ties go to carving. ``source`` thus names
      the model that placed the point: ``carved``, ``atm`` or ``centerline`` (neither helped).
    * ``processed``: processed by either model, so the combined unprocessed share is at most the
      smaller of the two (Table I: 7.68 % against 31.75 % and 55.59 %).

    Parameters
    ----------
    carving, atm : Estimates
        The two models' estimates for the same rows.
    """
    use_atm = atm.processed & (atm.max_error < carving.max_error)
    return Estimates(
        alive=carving.alive,
        processed=carving.processed | atm.processed,
        xy=np.where(use_atm[:, None], atm.xy, carving.xy),
        width=np.where(use_atm, atm.width, carving.width),
        max_error=np.where(use_atm, atm.max_error, carving.max_error),
        source=np.where(use_atm, atm.source, carving.source).astype(np.int8),
        fate=carving.fate,
    )


class CombinedMethod(SonarMethod):
    """Carving and ATM on one shared history; each point from the model with the smaller bound.

    Parameters
    ----------
    history_size : int
        Arcs kept in the history (paper: 250).
    beam_width : float
        Default beam width φ, radians.
    range_tolerance : float
        Carving's ε ≥ 0, metres (see :class:`~sonarcarve.methods.carving.CarvingModel`).
    min_transversal : float
        ATM's ψ, radians (see :class:`~sonarcarve.methods.atm.AtmModel`).
    range_resolution : float
        ATM's δ, metres (see :func:`~sonarcarve.methods.atm.atm_error_bound`).
    max_incidence : float
        Carving's critical angle β, radians (see
        :class:`~sonarcarve.methods.carving.CarvingModel`; π/2, the default: the paper).

    Notes
    -----
    The rule is :func:`combine_carving_atm`. ``models`` is ``(CarvingModel, AtmModel)``; the
    counters of both are reported (``fully_carved``, ``split``, ``atm_crossings``).
    """

    name = "combined"

    def __init__(
        self,
        history_size: int = DEFAULT_HISTORY_SIZE,
        beam_width: float = DEFAULT_BEAM_WIDTH,
        range_tolerance: float = DEFAULT_RANGE_TOLERANCE,
        min_transversal: float = DEFAULT_MIN_TRANSVERSAL,
        range_resolution: float = POLAROID_RANGE_RESOLUTION,
        max_incidence: float = NO_INCIDENCE_LIMIT,
    ) -> None:
        self.config = MethodConfig(
            history_size=history_size, beam_width=beam_width, range_tolerance=range_tolerance,
            min_transversal=min_transversal, range_resolution=range_resolution,
            max_incidence=max_incidence,
        )
        self.range_tolerance = self.config.range_tolerance
        self.max_incidence = self.config.max_incidence
        self.min_transversal = self.config.min_transversal
        self.range_resolution = self.config.range_resolution
        super().__init__(history_size, beam_width)

    def _make_models(self) -> tuple[CarvingModel, AtmModel]:
        return (
            CarvingModel(self.history, self.range_tolerance, self.max_incidence),
            AtmModel(self.history, self.min_transversal, self.range_resolution),
        )

    def _combine(self, estimates: tuple[Estimates, ...]) -> Estimates:
        carving, atm = estimates
        return combine_carving_atm(carving, atm)
