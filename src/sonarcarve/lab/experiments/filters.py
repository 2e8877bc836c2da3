"""Appendix B measured: reading filters and map filters on the office tour.

The paper (Appendix B) found that carving "can remove some of this noise by completely carving
arcs, [but] it is not always enough", and added two levels of filtering: per sensor (a jump
filter and a maximum range of 150 inches) and on the map (an outlier test). Here each filter of
:mod:`sonarcarve.filters`, and all of them together, runs on the simulated office tour for
centerline, carving and combined, and the simulator's truth says what they removed: spurious
readings (crosstalk, floor echoes, multipath) or true (direct) ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from sonarcarve.filters import (
    PAPER_MAX_RANGE,
    DropReason,
    MapFilter,
    ReadingFilter,
    filter_map,
    filter_readings,
)
from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import fig13_threshold
from sonarcarve.lab.experiments.appendix_base import (
    LABELS,
    AppendixSettings,
    mean_or_none,
    office_simulation,
    summary_dict,
)
from sonarcarve.lab.experiments.base import Artifacts, Experiment, Outputs, Page, Part, no_jobs
from sonarcarve.lab.formatting import fmt_cm, fmt_num, fmt_seeds
from sonarcarve.lab.plan import Settings
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.typing import BoolArray, FloatArray, JsonDict

__all__ = [
    "EXPERIMENT",
    "FILTER_METHODS",
    "JUMP_THRESHOLD",
    "OUTLIER_NEIGHBOURS",
    "OUTLIER_RADIUS",
    "FiltersResult",
    "filter_variants",
    "filters_experiment",
]

Variant = tuple[ReadingFilter | None, MapFilter | None]

#: Methods the filters are measured on (CLI names, table order). ATM is left out: it removes
#: nothing and its map is centerline's wherever it has no crossing.
FILTER_METHODS = ("centerline", "carve", "combined")
#: Jump filter threshold, metres: the paper gives none. Half a metre between two readings of one
#: sensor 0.64 s apart (one Scout2 ring cycle) is far more than driving at 0.4 m/s explains.
JUMP_THRESHOLD = 0.5
#: The outlier test: a map point needs at least this many other points within the radius.
OUTLIER_NEIGHBOURS = 2
OUTLIER_RADIUS = 0.3

#: How the text names each filter setting of :func:`filter_variants`.
_NOUNS = {"max_range": "the maximum range", "jump": "the jump filter",
          "outliers": "the outlier test", "max_error": "max-error thresholding",
          "all": "all four"}

_KEYS = ("readings_dropped", "points_before_map_filter", "points_dropped", "points",
         "spurious_removed_by_filters", "direct_removed_by_filters", "spurious_removed",
         "direct_removed", "spurious_points")


@dataclass(frozen=True)
class FiltersResult:
    """Appendix B measured (``results.json``: ``appendix_filters``).

    Attributes
    ----------
    scenario : dict
        The tour (``tour_m``, ``whole_tour``), seeds, mean readings and spurious share (%).
    filters : dict
        The filters' parameters (max range m, jump threshold m, outlier radius m and
        neighbours, max error m).
    variants : dict
        Filter setting name -> its label (see :func:`filter_variants`).
    methods : dict
        Per method label, per filter setting: means over seeds of the counts and shares of
        :func:`_judge` and the map's ``error`` (median, p90, mean m).
    """

    JSON_KEY: ClassVar[str] = "appendix_filters"

    scenario: JsonDict
    filters: JsonDict
    variants: dict[str, str]
    methods: dict[str, dict[str, JsonDict]]


def filter_variants(config: MethodConfig) -> dict[str, tuple[str, Variant]]:
    """The filter settings measured: name -> (label, (reading filter, map filter)).

    ``none``; the paper's maximum range (:data:`~sonarcarve.filters.PAPER_MAX_RANGE`); the jump
    filter (:data:`JUMP_THRESHOLD`); the outlier test (:data:`OUTLIER_NEIGHBOURS` within
    :data:`OUTLIER_RADIUS`); max-error thresholding at Fig. 13's threshold (ATM's bound, eq. 5.4
    times δ, for ``config``); and all four together.
    """
    threshold = fig13_threshold(config)
    max_range = ReadingFilter(max_range=PAPER_MAX_RANGE)
    jump = ReadingFilter(jump_threshold=JUMP_THRESHOLD)
    outliers = MapFilter(outlier_radius=OUTLIER_RADIUS, outlier_neighbours=OUTLIER_NEIGHBOURS)
    bounded = MapFilter(max_error=threshold)
    return {
        "none": ("none", (None, None)),
        "max_range": (f"max range {PAPER_MAX_RANGE:.2f} m", (max_range, None)),
        "jump": (f"jump > {JUMP_THRESHOLD:g} m", (jump, None)),
        "outliers": (f"outliers (< {OUTLIER_NEIGHBOURS} within {OUTLIER_RADIUS:g} m)",
                     (None, outliers)),
        "max_error": (f"max error > {fmt_cm(threshold)}", (None, bounded)),
        "all": ("all four", (ReadingFilter(max_range=PAPER_MAX_RANGE,
                                           jump_threshold=JUMP_THRESHOLD),
                             MapFilter(max_error=threshold, outlier_radius=OUTLIER_RADIUS,
                                       outlier_neighbours=OUTLIER_NEIGHBOURS))),
    }


def _judge(spurious: BoolArray, dropped: BoolArray, before: GlobalMap, after: GlobalMap,
           segments: FloatArray) -> JsonDict:
    """What one filter setting removed, judged by the truth (shares in percent).

    ``dropped`` marks the readings the reading filters dropped, ``before`` is the method's
    global map of the rest and ``after`` that map once the map filters ran. A reading is
    *removed* when it has no point in ``after`` (whatever removed it: a filter or carving);
    *removed by the filters* when a reading filter dropped it or a map filter dropped its point.
    """
    n = spurious.shape[0]
    present = np.zeros(n, dtype=bool)
    present[after.reading_id] = True
    mapped = np.zeros(n, dtype=bool)
    mapped[before.reading_id] = True
    by_filters = dropped | (mapped & ~present)
    direct = ~spurious
    err = metrics.segment_distance(after.xy, segments)[0]
    return {
        "readings_dropped": int(np.count_nonzero(dropped)),
        "points_before_map_filter": len(before),
        "points_dropped": len(before) - len(after),
        "points": len(after),
        "spurious_removed_by_filters": metrics.percent(by_filters[spurious]),
        "direct_removed_by_filters": metrics.percent(by_filters[direct]),
        "spurious_removed": metrics.percent(~present[spurious]),
        "direct_removed": metrics.percent(~present[direct]),
        "spurious_points": metrics.percent(spurious[after.reading_id]),
        "error": summary_dict(err),
    }


def _method_runs(batch: ReadingBatch, spurious: BoolArray, segments: FloatArray, method: str,
                 config: MethodConfig, variants: dict[str, tuple[str, Variant]]) -> JsonDict:
    """Every filter setting for one method on one log.

    The method runs once per distinct reading filter (``process_readings(...,
    reading_filter=...)``); the map filters then run on its global map with
    :func:`~sonarcarve.filters.filter_map`, as ``process_readings(..., map_filter=...)`` does,
    so that the points they drop are known.
    """
    runs: dict[ReadingFilter | None, tuple[GlobalMap, BoolArray]] = {}
    out: JsonDict = {}
    for name, (_, (reading_filter, map_filter)) in variants.items():
        if reading_filter not in runs:
            result = process_readings(batch, make_method(method, config),
                                      reading_filter=reading_filter)
            dropped = (np.zeros(len(batch), dtype=bool) if reading_filter is None else
                       filter_readings(batch, reading_filter).reasons != DropReason.KEPT)
            runs[reading_filter] = (result.global_map, dropped)
        before, dropped = runs[reading_filter]
        after = before if map_filter is None else filter_map(before, map_filter).points
        out[name] = _judge(spurious, dropped, before, after, segments)
    return out


def filters_experiment(settings: AppendixSettings) -> tuple[FiltersResult, Artifacts]:
    """Appendix B: each reading and map filter, and all together, on the office tour.

    Per seed (the office experiment's simulations: same scenario, same seeds), for centerline,
    carving and combined (library defaults) and each of :func:`filter_variants`: readings the
    reading filters dropped, map points the map filters dropped, the shares of spurious and of
    direct readings removed (by the filters, and in all: carving's removals included), the share
    of spurious points left in the global map, and the map's distance to the true walls. Means
    over seeds.

    Returns
    -------
    tuple
        The :class:`FiltersResult` and no artifacts (the section is a table).
    """
    config = settings.method_config()
    variants = filter_variants(config)
    runs: list[JsonDict] = []
    for seed in range(settings.seeds):
        sim, _ = office_simulation(settings, seed)
        spurious = sim.truth.kind != EchoKind.DIRECT
        runs.append({
            "tour_m": sim.trajectory.path_length,
            "readings": len(sim.readings),
            "spurious_percent": metrics.percent(spurious),
            "methods": {LABELS[m]: _method_runs(sim.readings, spurious, sim.world.segments, m,
                                                config, variants)
                        for m in FILTER_METHODS},
        })
    methods: JsonDict = {}
    for m in FILTER_METHODS:
        label = LABELS[m]
        methods[label] = {}
        for name in variants:
            per = [r["methods"][label][name] for r in runs]
            entry: JsonDict = {k: mean_or_none([p[k] for p in per]) for k in _KEYS}
            entry["error"] = {q: mean_or_none([p["error"][q] for p in per])
                              for q in ("median", "p90", "mean")}
            methods[label][name] = entry
    result = FiltersResult(
        scenario={"world": "office", "robot": "scout2", "seeds": settings.seeds,
                  "tour_m": runs[0]["tour_m"], "whole_tour": settings.tour_length is None,
                  "readings": mean_or_none([r["readings"] for r in runs]),
                  "spurious_percent": mean_or_none([r["spurious_percent"] for r in runs])},
        filters={"max_range_m": PAPER_MAX_RANGE, "jump_threshold_m": JUMP_THRESHOLD,
                 "outlier_radius_m": OUTLIER_RADIUS,
                 "outlier_neighbours": OUTLIER_NEIGHBOURS,
                 "max_error_m": fig13_threshold(config)},
        variants={name: label for name, (label, _) in variants.items()},
        methods=methods,
    )
    return result, {}


def summarise(settings: Settings, outputs: Outputs) -> tuple[FiltersResult, Artifacts]:
    """:func:`filters_experiment` at the appendix's size for ``settings`` (no job outputs)."""
    return filters_experiment(AppendixSettings.from_settings(settings))


def figure(result: FiltersResult, artifacts: Artifacts, folder: Path) -> list[Path]:
    """No figure: the section is a table."""
    return []


# ============================================================================ text


def markdown(res: FiltersResult, page: Page) -> list[Part]:
    """The Appendix B subsection of the appendix section."""
    sc, f = res.scenario, res.filters
    out = [
        "### Appendix B: reading filters and map filters", "",
        f"The office tour ({sc['tour_m']:.0f} m, {fmt_seeds(sc['seeds'])}"
        + (": the office experiment's simulations" if sc.get("whole_tour") else "")
        + f"; {fmt_num(sc['readings'], 0)} readings, "
        f"{fmt_num(sc['spurious_percent'], 1)} % of them spurious), library defaults. Reading "
        f"filters (`ReadingFilter`): the paper's maximum range of 150 inches "
        f"({f['max_range_m']:.2f} m); the jump filter, which drops a reading whose range differs "
        f"from its sensor's previous one by more than {f['jump_threshold_m']:g} m (the paper "
        "gives no threshold). Map filters (`MapFilter`, on the finished global map): the "
        f"outlier test, which keeps a point with at least {f['outlier_neighbours']} other "
        f"points within {f['outlier_radius_m']:g} m; max-error thresholding at "
        f"{fmt_cm(f['max_error_m'])} (ATM's bound, as Fig. 13b). *Removed*: the reading has no "
        "point in the final map, *by filters / in all* (in all counts carving's own removals "
        "too); judged by the simulator's truth (spurious: crosstalk, floor echo, multipath; "
        "true: direct). Error: distance of the map's points to the nearest true wall. Each "
        "filter's label says what it removes."
        + (" Means over seeds." if sc["seeds"] > 1 else ""), "",
        "| method | filter | readings dropped | points dropped | spurious removed (%): "
        "filters / in all | direct removed (%): filters / in all | map points | "
        "spurious points (%) | error median / p90 |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for label, entries in res.methods.items():
        for name, e in entries.items():
            out.append(
                f"| {label} | {res.variants[name]} | {fmt_num(e['readings_dropped'], 0)} | "
                f"{fmt_num(e['points_dropped'], 0)} | "
                f"{fmt_num(e['spurious_removed_by_filters'], 1)} / "
                f"{fmt_num(e['spurious_removed'], 1)} | "
                f"{fmt_num(e['direct_removed_by_filters'], 1)} / "
                f"{fmt_num(e['direct_removed'], 1)} | {fmt_num(e['points'], 0)} | "
                f"{fmt_num(e['spurious_points'], 1)} | {fmt_cm(e['error']['median'])} / "
                f"{fmt_cm(e['error']['p90'])} |")
    out += ["", *_filter_sentences(res), ""]
    return [Part(20, out)]


def _filter_sentences(res: FiltersResult) -> list[str]:
    """The comparison with the paper's claim, and what each filter costs."""
    carve = res.methods.get("carving")
    center = res.methods.get("centerline")
    if not carve or not center:
        return []
    none, every = carve["none"], carve["all"]
    helps = (every["spurious_points"] is not None and none["spurious_points"] is not None
             and every["spurious_points"] < none["spurious_points"]
             and every["error"]["p90"] is not None and none["error"]["p90"] is not None
             and every["error"]["p90"] < none["error"]["p90"])
    singles = [n for n in ("max_range", "jump", "outliers", "max_error") if n in carve]

    def by_filters(entry: JsonDict) -> str:
        return (f"{fmt_num(entry['spurious_removed_by_filters'], 0)} % / "
                f"{fmt_num(entry['direct_removed_by_filters'], 0)} %")

    def selectivity(name: str) -> float:
        e = center[name]
        spur, direct = e["spurious_removed_by_filters"], e["direct_removed_by_filters"]
        return (spur or 0.0) / max(direct or 0.0, 0.1)

    # Max-error thresholding removes almost every centerline point (each keeps the full beam's
    # bound), so it is no candidate for the filter that removes the most spurious readings.
    most = max((n for n in singles if n != "max_error"),
               key=lambda n: center[n]["spurious_removed_by_filters"] or 0.0)
    sharpest = max(singles, key=selectivity)
    return [
        "- Paper, Appendix B: carving \"can remove some of this noise by completely carving "
        "arcs, [but] it is not always enough\", so filtering was added beyond it. Measured: "
        f"carving alone removes {fmt_num(none['spurious_removed'], 0)} % of the spurious "
        f"readings (and {fmt_num(none['direct_removed'], 0)} % of the direct ones), leaving "
        f"{fmt_num(none['spurious_points'], 1)} % spurious points and a 90th-percentile error "
        f"of {fmt_cm(none['error']['p90'])}; with all four filters "
        f"{fmt_num(every['spurious_removed'], 0)} % of the spurious readings go (and "
        f"{fmt_num(every['direct_removed'], 0)} % of the direct ones), "
        f"{fmt_num(every['spurious_points'], 1)} % of the points are spurious and the 90th "
        f"percentile is {fmt_cm(every['error']['p90'])}: "
        + ("the filters remove noise carving leaves, as the paper found, at the price of true "
           "readings." if helps else "here the filters do not improve on carving, unlike the "
           "paper."),
        "- Centerline removes nothing itself, so its rows show each filter alone (spurious / "
        "direct readings removed): "
        + ", ".join(f"{_NOUNS[n]} {by_filters(center[n])}" for n in singles)
        + f". Of the reading filters and the outlier test, {_NOUNS[most]} removes the most "
        f"spurious readings; {_NOUNS[sharpest]} spares the direct ones best. Max-error "
        "thresholding keeps only points whose bound (eq. 5.3) is within ATM's: refined points, "
        "and of centerline's, whose every arc keeps the full beam's bound, only the shortest "
        f"({fmt_num(center['max_error']['points'], 0)} points).",
        "- The outlier test runs here on the whole tour's global map, denser than the paper's "
        "local map (the last 250 readings), so an isolated point finds neighbours more easily "
        "than it would there.",
    ]


EXPERIMENT = Experiment("filters", "Appendix B: reading and map filters, judged by the truth",
                        "appendix", no_jobs, summarise, figure, markdown)
