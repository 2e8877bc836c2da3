"""The centerline model (paper, section 2-A): the reflection is at the centre of the arc."""

from __future__ import annotations

import numpy as np

from sonarcarve.maps import PointSource, chord_error
from sonarcarve.methods.base import ArcModel, Estimates, SonarMethod, arc_point, source_codes
from sonarcarve.typing import SlotArray

__all__ = ["CenterlineMethod", "CenterlineModel"]


class CenterlineModel(ArcModel):
    """Every arc gives the point on its axis θ at range r, with ``E_m = φ/2`` (eq. 5.2, 5.3).

    No arc needs another to be placed, so every arc is processed the moment it arrives (Table I:
    0 %). The model keeps no state.
    """

    def on_add_many(self, first: int, count: int) -> None:
        """Nothing to do: the centerline point depends on the arc alone."""

    def estimates(self, slots: SlotArray) -> Estimates:
        h = self.history
        n = len(slots)
        width = h.beam_width[slots]
        return Estimates(
            alive=np.ones(n, dtype=bool),
            processed=np.ones(n, dtype=bool),
            xy=arc_point(h, slots, h.theta[slots]),
            width=width,
            max_error=chord_error(h.r[slots], width),
            source=source_codes(n, PointSource.CENTERLINE),
        )


class CenterlineMethod(SonarMethod):
    """The centerline model as a streaming method (section 2-A)."""

    name = "centerline"

    def _make_models(self) -> tuple[CenterlineModel]:
        return (CenterlineModel(self.history),)

    def _combine(self, estimates: tuple[Estimates, ...]) -> Estimates:
        return estimates[0]
