"""What the office experiment computes (:class:`OfficeResult`): its numbers summarised over
seeds, as :mod:`~sonarcarve.lab.experiments.office` makes them and
:mod:`~sonarcarve.lab.experiments.office_text` writes them up."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from sonarcarve.typing import JsonDict

__all__ = ["OfficeResult"]


@dataclass(frozen=True)
class OfficeResult:
    """The office tour summarised over seeds. Method tables are keyed by result label
    (:data:`~sonarcarve.lab.analyses.METHOD_LABELS`); a *spread* is
    :func:`~sonarcarve.lab.experiments.summary.spread` over seeds; a *binned curve* is
    :func:`~sonarcarve.lab.metrics.combine_binned` over the range bins
    (:data:`~sonarcarve.lab.analyses.RANGE_EDGES`). Means and shares are floats, None where
    no seed had a value.

    Attributes
    ----------
    table1 : dict
        Table I: mean percentage of history rows unprocessed, per method.
    table1_spread : dict
        The same as spreads over seeds.
    table1_alive_only : dict
        Table I over live arcs only (removed arcs left out, as the paper's history would).
    fig10 : dict
        Fig. 10: binned curve of the unprocessed share, per method.
    fig11 : dict
        Fig. 11: carving's final angular widths (degrees), ``all_surviving`` and
        ``carved_only`` arcs, each ``mean`` and ``median`` binned curves.
    fig12 : dict
        Fig. 12: binned mean maximum error (metres) of ``carving``, ``centerline``,
        ``atm_measured``, ``combined`` and ``evidence``, and ATM's bound ``atm_bound``
        (eq. 5.4 times δ).
    fully_carved : dict
        Carving's removal shares (:func:`~sonarcarve.lab.analyses.removal_summary`), means.
    fully_carved_spread : dict
        ``share``, ``spurious_removed`` and ``true_lost`` as spreads.
    fully_carved_combined : dict
        The same three means for the combined method.
    fully_carved_evidence : dict
        The same three means and ``spurious_of_removed`` for the evidence method, whose
        fully carved is: no bin of the arc's profile survived (arcs its confidence leaves out
        of the map are not counted).
    true_error : dict
        Per method, ``median``, ``p90`` and ``mean`` true error of local-map points, metres.
    true_error_spread : dict
        Per method, ``median`` and ``p90`` as spreads.
    true_error_by_range : dict
        Per method, ``median`` and ``p90`` binned curves of the true error.
    true_error_global : dict
        Per method, ``median`` and ``p90`` true error of the global map's points.
    fig13 : dict
        Fig. 13: ``threshold_m``, and per method the global map's ``points``, the points
        ``kept`` by the figure's rule and their ``kept_error_median`` / ``kept_error_p90``.
    latency_accuracy : dict
        The delay grids (``grid_s``, ``grid_m``), ``patch_length_m``, and per method and
        tolerance the resolved share, median delays and resolved-share curves.
    truth_breakdown : dict
        Per method, :func:`~sonarcarve.lab.analyses.truth_breakdown` means.
    office_runs : dict
        ``seeds``, mean ``readings`` and ``duration_s`` of a run, and per-method wall time.
    """

    table1: dict[str, Any]
    table1_spread: dict[str, JsonDict]
    table1_alive_only: dict[str, Any]
    fig10: dict[str, JsonDict]
    fig11: dict[str, JsonDict]
    fig12: JsonDict
    fully_carved: dict[str, Any]
    fully_carved_spread: dict[str, JsonDict]
    fully_carved_combined: dict[str, Any]
    fully_carved_evidence: dict[str, Any]
    true_error: dict[str, JsonDict]
    true_error_spread: dict[str, JsonDict]
    true_error_by_range: dict[str, JsonDict]
    true_error_global: dict[str, JsonDict]
    fig13: JsonDict
    latency_accuracy: JsonDict
    truth_breakdown: dict[str, JsonDict]
    office_runs: JsonDict
