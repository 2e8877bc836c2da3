"""The office tour: the paper's Table I, Fig. 10-13, fully carved share, and true error and
latency against accuracy (what the paper could not measure without ground truth).

Every method maps the simulated ``office`` tour for several seeds (sections 5-B and 5-C);
each run is analysed by :func:`~sonarcarve.lab.analyses.analyse_office` and the analyses are
summarised over seeds here. The text of its parts of ``docs/RESULTS.md`` is in
:mod:`~sonarcarve.lab.experiments.office_text`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from sonarcarve.lab import figures
from sonarcarve.lab.analyses import (
    LATENCY_GRID_M,
    LATENCY_GRID_S,
    METHOD_LABELS,
    PATCH_LENGTH,
    PATCH_TOLERANCES,
    fig13_threshold,
)
from sonarcarve.lab.drawing import save_pngs
from sonarcarve.lab.experiments import office_text
from sonarcarve.lab.experiments.base import Artifacts, Experiment, Outputs, Page, Part
from sonarcarve.lab.experiments.office_result import OfficeResult
from sonarcarve.lab.experiments.summary import binned_over_seeds, spread
from sonarcarve.lab.plan import ALL_METHODS, Job, Settings
from sonarcarve.lab.scenarios import Scenario
from sonarcarve.methods.atm import atm_error_bound
from sonarcarve.typing import JsonDict

__all__ = ["EXPERIMENT", "OfficeResult", "plan", "summarise"]

#: Per-method runs by CLI name (seed order).
Runs = dict[str, list[JsonDict]]


def plan(s: Settings) -> list[Job]:
    """Every method on the office tour, for each seed; seed 0 keeps its global maps."""
    return [Job(("office", seed, m), Scenario("office", seed, max_length=s.office_length,
                                              speed=s.speed),
                m, s.method_config(), "office", s.sample_every,
                (("detail", seed == 0),))
            for seed in range(s.seeds) for m in ALL_METHODS]


def _mean(values: Any) -> float | None:
    mean: float | None = spread(values)["mean"]
    return mean


def summarise(s: Settings, outs: Outputs) -> tuple[OfficeResult, Artifacts]:
    """:class:`OfficeResult` from the runs of :func:`plan`; artifacts: seed 0's global maps
    of ATM and carving (Fig. 13)."""
    by_method = {m: [outs[("office", seed, m)] for seed in range(s.seeds)] for m in ALL_METHODS}
    result = OfficeResult(
        **_table1(by_method), **_figs_10_12(s, by_method), **_fully_carved(by_method),
        **_true_error(by_method), fig13=_fig13(s, by_method),
        latency_accuracy=_latency_accuracy(by_method),
        truth_breakdown=_truth_breakdown(by_method), office_runs=_office_runs(s, by_method))
    first = {m: by_method[m][0] for m in ALL_METHODS}
    artifacts = {"fig13": {METHOD_LABELS[m]: first[m].get("global_map")
                           for m in ("atm", "carve")}}
    return result, artifacts


def _table1(by_method: Runs) -> dict[str, Any]:
    label = METHOD_LABELS
    return {
        "table1": {label[m]: _mean(o["unprocessed"] for o in by_method[m]) for m in ALL_METHODS},
        "table1_spread": {label[m]: spread(o["unprocessed"] for o in by_method[m])
                          for m in ALL_METHODS},
        "table1_alive_only": {label[m]: _mean(o["unprocessed_alive"] for o in by_method[m])
                              for m in ALL_METHODS},
    }


def _figs_10_12(s: Settings, by_method: Runs) -> dict[str, Any]:
    carve = by_method["carve"]
    config = s.method_config()
    return {
        "fig10": {METHOD_LABELS[m]: binned_over_seeds(by_method[m], "unprocessed_by_range")
                  for m in ALL_METHODS},
        "fig11": {
            "all_surviving": {"mean": binned_over_seeds(carve, "width_by_range", "mean"),
                              "median": binned_over_seeds(carve, "width_by_range", "median")},
            "carved_only": {
                "mean": binned_over_seeds(carve, "carved_width_by_range", "mean"),
                "median": binned_over_seeds(carve, "carved_width_by_range", "median")},
        },
        "fig12": {
            "carving": binned_over_seeds(carve, "max_error_by_range"),
            "centerline": binned_over_seeds(by_method["centerline"], "max_error_by_range"),
            "atm_measured": binned_over_seeds(by_method["atm"], "max_error_by_range"),
            "combined": binned_over_seeds(by_method["combined"], "max_error_by_range"),
            "evidence": binned_over_seeds(by_method["evidence"], "max_error_by_range"),
            "atm_bound": atm_error_bound(config.min_transversal, config.range_resolution),
        },
    }


def _fully_carved(by_method: Runs) -> dict[str, Any]:
    carve = by_method["carve"]
    main = ("share", "spurious_removed", "true_lost")
    return {
        "fully_carved": {k: _mean(o["removal"][k] for o in carve) for k in carve[0]["removal"]},
        "fully_carved_spread": {k: spread(o["removal"][k] for o in carve) for k in main},
        "fully_carved_combined": {k: _mean(o["removal"][k] for o in by_method["combined"])
                                  for k in main},
        "fully_carved_evidence": {k: _mean(o["removal"][k] for o in by_method["evidence"])
                                  for k in (*main, "spurious_of_removed")},
    }


def _true_error(by_method: Runs) -> dict[str, Any]:
    label = METHOD_LABELS
    return {
        "true_error": {label[m]: {q: _mean(o["true_error"][q] for o in by_method[m])
                                  for q in ("median", "p90", "mean")} for m in ALL_METHODS},
        "true_error_spread": {
            label[m]: {q: spread(o["true_error"][q] for o in by_method[m])
                       for q in ("median", "p90")} for m in ALL_METHODS},
        "true_error_by_range": {
            label[m]: {"median": binned_over_seeds(by_method[m], "true_error_by_range", "median"),
                       "p90": binned_over_seeds(by_method[m], "true_error_by_range", "p90")}
            for m in ALL_METHODS},
        "true_error_global": {
            label[m]: {q: _mean(o["global_error"][q] for o in by_method[m])
                       for q in ("median", "p90")} for m in ALL_METHODS},
    }


def _fig13(s: Settings, by_method: Runs) -> JsonDict:
    out: JsonDict = {"threshold_m": fig13_threshold(s.method_config())}
    for m in ALL_METHODS:
        runs = by_method[m]
        out[METHOD_LABELS[m]] = {
            "points": _mean(o["global_points"] for o in runs),
            "kept": _mean(o["thresholded_points"] for o in runs),
            "kept_error_median": _mean(o["thresholded_error"]["median"] for o in runs),
            "kept_error_p90": _mean(o["thresholded_error"]["p90"] for o in runs),
        }
    return out


def _latency_accuracy(by_method: Runs) -> JsonDict:
    out: JsonDict = {"grid_s": list(LATENCY_GRID_S), "grid_m": list(LATENCY_GRID_M),
                     "patch_length_m": PATCH_LENGTH}
    for m in ALL_METHODS:
        entry: JsonDict = {}
        for tol in PATCH_TOLERANCES:
            key = f"{tol:g}"
            per = [o["latency_accuracy"][key] for o in by_method[m]]
            entry[key] = {
                "resolved_share": _mean(p["resolved_share"] for p in per),
                "median_s": _mean(p["median_s"] for p in per),
                "median_m": _mean(p["median_m"] for p in per),
                "curve_s": np.mean([p["curve_s"] for p in per], axis=0).tolist(),
                "curve_m": np.mean([p["curve_m"] for p in per], axis=0).tolist(),
            }
        entry["patches_seen"] = _mean(o["latency_accuracy"]["patches_seen"]
                                      for o in by_method[m])
        out[METHOD_LABELS[m]] = entry
    return out


def _truth_breakdown(by_method: Runs) -> dict[str, JsonDict]:
    out: dict[str, JsonDict] = {}
    for m in ALL_METHODS:
        per = [o["truth_breakdown"] for o in by_method[m]]
        entry: JsonDict = {k: _mean(p[k] for p in per) for k in per[0] if k != "direct_error"}
        entry["direct_error"] = {q: _mean(p["direct_error"][q] for p in per)
                                 for q in ("median", "p90")}
        out[METHOD_LABELS[m]] = entry
    return out


def _office_runs(s: Settings, by_method: Runs) -> JsonDict:
    carve = by_method["carve"]
    return {"seeds": s.seeds, "readings": _mean(o["readings"] for o in carve),
            "duration_s": _mean(o["duration"] for o in carve),
            "method_seconds": {METHOD_LABELS[m]: _mean(o["seconds"] for o in by_method[m])
                               for m in ALL_METHODS}}


def figure(result: OfficeResult, artifacts: Artifacts, folder: Path) -> list[Path]:
    """Fig. 10, 11, 12 and 13, true error by range, latency against accuracy."""
    return save_pngs({
        "fig10_unprocessed_by_range.png": figures.plot_fig10(result.fig10),
        "fig11_carved_width_by_range.png": figures.plot_fig11(result.fig11),
        "fig12_max_error_by_range.png": figures.plot_fig12(result.fig12),
        "fig13_global_maps.png": figures.plot_fig13(result.fig13["threshold_m"],
                                                    artifacts),
        "true_error_by_range.png": figures.plot_true_error(result.true_error_by_range),
        "latency_accuracy.png": figures.plot_latency_accuracy(result.latency_accuracy),
    }, folder)


def markdown(result: OfficeResult, page: Page) -> list[Part]:
    """Table I, fully carved, Fig. 10-12, Fig. 13, true error, latency (in the paper's order,
    between which the T junction and openings parts go)."""
    return [Part(10, office_text.table1(result)), Part(20, office_text.fully_carved(result)),
            Part(50, office_text.figs_10_12(result, page)),
            Part(60, office_text.fig13(result, page)),
            Part(70, office_text.true_error(result, page)),
            Part(80, office_text.latency(result, page))]


EXPERIMENT = Experiment("office", "Table I, Fig. 10-13, fully carved, true error, latency",
                        "experiments", plan, summarise, figure, markdown)
