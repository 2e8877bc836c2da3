"""The carved grid: an occupancy grid whose occupied band follows arc carving over time.

The paper (section 4) proposes that "a new distribution can be used for each reading, computed from
the carved results": :class:`CarvedGrid` is that distribution, written into a log-odds grid. Each
reading's beam gets free space at once, ``l += γ(α) f(d) · logit(p_miss)``, and its arc, while it is
in the carving method's history, an occupied band over its *carved* interval,
``l_k = c · s · logit(p_hit)`` with ``s = min(1, L / (r (θ2' - θ1')))``, made final when the arc
leaves the history. The design, each rule added to that model with the measurements behind it, and
what was tried and not kept: ``docs/carved-grid.md``.

The modules from the bottom up, each importing only those before it (an import-linter contract
in ``pyproject.toml`` checks the layers): :mod:`.params` (the parameters and their measured
defaults), :mod:`.model` (them as the kernels take them), :mod:`~sonarcarve.grids.scan` (which
cells a sector covers; outside the package, the Elfes grid uses it too), :mod:`.heard` (where a
cell was heard from), :mod:`.band` (an arc's band), :mod:`.free_space` and :mod:`.mark` (a
reading's free space; the newest echo's mark), :mod:`.kernels`, :mod:`.repeats` and
:mod:`.intervals` (what the grid calls), :mod:`.grid` (:class:`CarvedGrid`) and :mod:`.classify`
(:func:`trinary`, for any grid).
"""

from __future__ import annotations

from sonarcarve.grids.carved.classify import trinary
from sonarcarve.grids.carved.grid import CarvedGrid
from sonarcarve.grids.carved.heard import HEARD_BINS, HEARD_NEAR
from sonarcarve.grids.carved.params import (
    DEFAULT_FREE_THRESHOLD,
    DEFAULT_FRESH_PERIODS,
    DEFAULT_MARK_LENGTH,
    DEFAULT_MAX_INCIDENCE,
    DEFAULT_METHOD,
    DEFAULT_SEE_THROUGH,
    DEFAULT_SIDE_LOBE_RANGE,
    DEFAULT_SIDE_LOBES,
    DEFAULT_SPREAD_LENGTH,
    MAX_SIDE_LOBES,
    CarvedGridParams,
)
from sonarcarve.grids.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "DEFAULT_FREE_THRESHOLD",
    "DEFAULT_FRESH_PERIODS",
    "DEFAULT_MARK_LENGTH",
    "DEFAULT_MAX_INCIDENCE",
    "DEFAULT_METHOD",
    "DEFAULT_SEE_THROUGH",
    "DEFAULT_SIDE_LOBES",
    "DEFAULT_SIDE_LOBE_RANGE",
    "DEFAULT_SPREAD_LENGTH",
    "FREE",
    "HEARD_BINS",
    "HEARD_NEAR",
    "MAX_SIDE_LOBES",
    "OCCUPIED",
    "UNKNOWN",
    "CarvedGrid",
    "CarvedGridParams",
    "OccupancyMap",
    "trinary",
]
