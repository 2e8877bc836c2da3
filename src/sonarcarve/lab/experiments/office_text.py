"""The office experiment's parts of ``docs/RESULTS.md``: Table I, fully carved arcs, Fig. 10-12,
Fig. 13, true error, latency against accuracy; each set against the paper's numbers and claims.
"""

from __future__ import annotations

import math

from sonarcarve.lab.experiments.base import Page
from sonarcarve.lab.experiments.office_result import OfficeResult
from sonarcarve.lab.formatting import fmt_num, fmt_seeds, fmt_spread, md_image
from sonarcarve.lab.plan import Settings
from sonarcarve.typing import JsonDict

__all__ = ["METHODS", "PAPER", "fig13", "figs_10_12", "fully_carved", "latency", "table1",
           "true_error"]

#: Methods in the order the tables list them (result labels).
METHODS = ("centerline", "atm", "carving", "combined", "evidence")

#: The paper's numbers (section 5), where it gives one.
PAPER: JsonDict = {
    "table1": {"atm": 31.75, "carving": 55.59, "combined": 7.68, "centerline": 0.0},
    "fully_carved_share_min": 20.0,  # "over 20 percent of all arcs ... were fully carved"
    "combined_refined_min": 92.0,  # "more than 92 percent of all arcs ... some increase"
}


def table1(r: OfficeResult) -> list[str]:
    paper = PAPER["table1"]
    spread = r.table1_spread
    alive = r.table1_alive_only
    out = ["### Table I: mean percentage of the history unprocessed", "",
           "| method | paper | ours: all history rows | ours: live arcs only |",
           "|---|---:|---:|---:|"]
    names = {"atm": "ATM", "carving": "Arc carving", "combined": "Arc carving and ATM",
             "centerline": "Centerline", "evidence": "Evidence carving (beyond the paper)"}
    for key, name in names.items():
        if key not in spread:
            continue
        out.append(f"| {name} | {_paper_cell(paper.get(key))} | "
                   f"{fmt_spread(spread[key], 2)} | {fmt_num(alive.get(key), 2)} |")
    out += ["", "Sampled every 16 readings once the history is full. *All history rows* is the "
            "library's measure (`SonarMethod.measures().unprocessed_share`; also the one of "
            "Fig. 10 and the sensitivity tables below): an arc carving removed (fully carved, "
            "or split and dropped) stays in the history and counts as processed, since it was "
            "carved. The paper's history drops removed arcs, so its Table I can count only arcs "
            "still alive: *live arcs only* leaves removed arcs out, as the paper would."]
    out += ["", *_table1_sentences(r), ""]
    return out


def _paper_cell(value: float | None) -> str:
    return "not in the paper" if value is None else f"{value:.2f}"


def _share_below(entry: JsonDict, limit: float) -> float:
    edges, counts = entry["edges"], entry["count"]
    total = sum(counts)
    below = sum(c for lo, c in zip(edges[:-1], counts, strict=True) if lo < limit)
    return 100.0 * below / total if total else math.nan


def _table1_sentences(r: OfficeResult) -> list[str]:
    t1, paper = r.table1, PAPER["table1"]
    alive = r.table1_alive_only
    short = _share_below(r.fig10["carving"], 1.0)
    carve_short = _mean_between(r.fig10["carving"], high=1.0)
    carve_far = _mean_between(r.fig10["carving"], 3.0)
    atm_far = _mean_between(r.fig10["atm"], 3.0)
    slow_short = carve_short is not None and carve_far is not None and carve_short > carve_far
    return [
        f"- ATM: {t1['atm']:.1f} % against the paper's {paper['atm']:.2f} %"
        + (", close. " if abs(t1["atm"] - paper["atm"]) < 5 else ". ")
        + "ATM's latency is set by how far the robot drives between readings of one obstacle "
        "(eq. 2.2), so it depends on speed, ψ and the tour, which the paper does not give.",
        f"- Arc carving: {t1['carving']:.1f} % of all history rows "
        f"({fmt_num(alive.get('carving'), 1)} % of live arcs only) against "
        f"{paper['carving']:.2f} %. "
        "The paper "
        "explains its high share by the many short arcs, which carving processes last (its "
        f"Fig. 10). {short:.0f} % of our history arcs are shorter than 1 m, and carving leaves "
        f"{fmt_num(carve_short, 0)} % of them unprocessed against "
        f"{fmt_num(carve_far, 0)} % of arcs "
        "beyond 3 m: "
        + ("short arcs are the slow ones here too, " if slow_short else
           "here short arcs are not the slow ones, so the paper's explanation does not carry "
           "over to our simulated robot, ")
        + f"which is why our share is {'lower' if t1['carving'] < paper['carving'] else 'so'}. "
        f"Long arcs behave as in the paper: beyond 3 m carving leaves {fmt_num(carve_far, 0)} % "
        f"unprocessed against ATM's {fmt_num(atm_far, 0)} %.",
        f"- Both: {t1['combined']:.1f} % of all history rows "
        f"({fmt_num(alive.get('combined'), 1)} % of live arcs only) against "
        f"{paper['combined']:.2f} %, so "
        + (f"{100 - alive['combined']:.1f} % of the live history arcs gain some azimuth "
           "resolution" if alive.get("combined") is not None else
           f"{100 - t1['combined']:.1f} % of history arcs are processed")
        + f" (paper: more than {PAPER['combined_refined_min']:.0f} %). Combined is never above "
        "the smaller of the two: one history, an arc is processed when either model processed "
        "it." + _combined_sentence(r.fig10, r.table1),
        "- Centerline: 0 % in both, by definition.",
        *_evidence_table1(r),
    ]


def _evidence_table1(r: OfficeResult) -> list[str]:
    """Evidence carving's Table I share against carving's, and what it measures."""
    t1, alive = r.table1, r.table1_alive_only
    if t1.get("evidence") is None:
        return []
    return [
        f"- Evidence carving (`evidence`, beyond the paper): {t1['evidence']:.1f} % of all "
        f"history rows ({fmt_num(alive.get('evidence'), 1)} % of live arcs only) against "
        f"carving's {t1['carving']:.1f} %. Not the same test: an evidence arc counts as "
        "processed once any newer reading added evidence to it (free space, support or "
        "occlusion) or ATM found a crossing, a carving arc only once a newer sector actually "
        "cut it. So a processed evidence arc need not have moved its point yet: the "
        "latency-accuracy table below is the fair comparison of the two."]


def _combined_sentence(f10: JsonDict, t1: JsonDict) -> str:
    """Why combined's unprocessed share is above the paper's: the two models' latencies are
    correlated through range here, anti-correlated in the paper (from Fig. 10's bins, ``f10``,
    and Table I, ``t1``)."""
    paper = PAPER["table1"]
    if not {"carving", "atm", "combined"} <= set(f10):
        return ""
    carve, atm = f10["carving"], f10["atm"]
    total = sum(carve["count"])
    slow = _unprocessed_counts(carve)
    far = sum(u for lo, u in zip(carve["edges"][:-1], slow, strict=True) if lo >= 3.0)
    # Were the two independent within each range bin, an arc would stay unprocessed by both
    # with the product of the two shares of its bin.
    per_bin = sum(c * (pc or 0.0) * (pa or 0.0) / 1e4 for c, pc, pa in
                  zip(carve["count"], carve["value"], atm["value"], strict=True))
    if not total or not sum(slow):
        return ""
    return (f" Why more than the paper's {paper['combined']:.2f} %: here "
            f"{100.0 * far / sum(slow):.0f} % of the arcs carving leaves unprocessed lie beyond "
            f"3 m, where ATM also leaves {fmt_num(_mean_between(atm, 3.0), 0)} % unprocessed (Fig. "
            "10), so the two latencies are correlated through range: were they independent, "
            f"combined would leave {t1['carving']:.1f} % × {t1['atm']:.1f} % = "
            f"{t1['carving'] * t1['atm'] / 100.0:.1f} %, independent within each 0.5 m range "
            f"bin {100.0 * per_bin / total:.1f} %; it leaves {t1['combined']:.1f} %. In the "
            "paper carving's slow arcs were the short ones, which ATM processes quickly: its "
            f"{paper['combined']:.2f} % is far below its own {paper['carving']:.2f} % × "
            f"{paper['atm']:.2f} % = {paper['carving'] * paper['atm'] / 100.0:.1f} %.")


def _unprocessed_counts(entry: JsonDict) -> list[float]:
    """Unprocessed arcs per range bin of a Fig. 10 curve (share times arcs), 0 for empty bins."""
    return [0.0 if v is None else v * c / 100.0 for v, c in zip(entry["value"], entry["count"],
                                                                 strict=True)]


def fully_carved(r: OfficeResult) -> list[str]:
    fc, sp = r.fully_carved, r.fully_carved_spread
    return [
        "### Fully carved arcs (section 5-C)", "",
        "| measure | paper | ours |", "|---|---:|---:|",
        f"| arcs fully carved (% of all arcs) | over {PAPER['fully_carved_share_min']:.0f} | "
        f"{fmt_spread(sp['share'])} |",
        f"| arcs dropped as split (% of all arcs) | not reported | {fmt_num(fc['split_share'])} |",
        f"| spurious readings removed (% of non-direct readings fully carved) | not measurable |"
        f" {fmt_spread(sp['spurious_removed'])} |",
        f"| true readings lost (% of direct readings fully carved) | not measurable | "
        f"{fmt_spread(sp['true_lost'])} |",
        f"| fully carved arcs that were spurious (%) | not measurable | "
        f"{fmt_num(fc['spurious_of_removed'])} |",
        f"| spurious readings in the log (%) | not measurable | "
        f"{fmt_num(fc['spurious_readings'])} |",
        "",
        "Truth from the simulator: a *true* reading is a direct echo (kind `direct`), a "
        "*spurious* one is crosstalk, a floor echo or multipath.",
        f"- The fully carved share ({fc['share']:.1f} %) "
        + ("agrees with the paper's \"over 20 percent\"." if fc["share"] > 20.0 else
           "is below the paper's \"over 20 percent\".")
        + f" But carving is not only removing spurious returns: it removes "
        f"{fc['spurious_removed']:.0f} % of the spurious readings and also "
        f"{fc['true_lost']:.0f} % of the direct ones, so {fc['spurious_of_removed']:.0f} % of "
        "fully carved arcs were spurious. On smooth (specular) walls a reading's freespace "
        "sector is not truly free: walls seen at a glancing angle inside the beam send no echo, "
        "so newer readings carve away arcs that were right. The paper had no ground truth to "
        "see this."
        + _lost_sentence(r),
        *_evidence_removal(r),
        "",
    ]


def _evidence_removal(r: OfficeResult) -> list[str]:
    """Evidence carving's removal shares against carving's (fully carved or split)."""
    ev, fc = r.fully_carved_evidence, r.fully_carved
    tb = r.truth_breakdown
    if not ev or ev.get("share") is None:
        return []
    spurious = ""
    if "evidence" in tb and "carving" in tb:
        spurious = (f" Its confidence leaves more out of the map: spurious readings make "
                    f"{fmt_num(tb['evidence']['spurious_share'])} % of its global map's points "
                    f"against {fmt_num(tb['carving']['spurious_share'])} % of carving's (true "
                    "error section below).")
    return [
        f"- Evidence carving (`evidence`): fully carved here means no bin of the arc's "
        "profile survived (the fate the method reports); it never drops an arc as split, and "
        "arcs left out of its map for low confidence are not counted. It fully carves "
        f"{fmt_num(ev['share'])} % of all arcs: {fmt_num(ev['spurious_removed'])} % of the "
        f"spurious readings and {fmt_num(ev['true_lost'])} % of the direct ones "
        f"({fmt_num(ev['spurious_of_removed'])} % of them spurious); carving, counting split "
        f"arcs too, removes {fmt_num(fc['spurious_removed_or_split'])} % of the spurious "
        f"readings and {fmt_num(fc['true_lost_or_split'])} % of the direct ones." + spurious]


def _lost_sentence(r: OfficeResult) -> str:
    tb = r.truth_breakdown.get("carving")
    if not tb:
        return ""
    return (f" The direct readings carving removes are mostly short (median range "
            f"{fmt_num(tb['lost_direct_median_range'], 2)} m against "
            f"{fmt_num(tb['kept_direct_median_range'], 2)} m for those it keeps) and were accurate "
            f"already (their centerline points' median true error "
            f"{fmt_num(tb['lost_direct_centerline_error'], 3)} m against "
            f"{fmt_num(tb['kept_direct_centerline_error'], 3)} m). Of the direct arcs that carving "
            f"kept and carved, {fmt_num(tb['carved_contains_truth'], 0)} % still contain the "
            "bearing "
            "of their true reflection; the others were carved past it.")


def figs_10_12(r: OfficeResult, page: Page) -> list[str]:
    f10, f11, f12 = r.fig10, r.fig11["carved_only"], r.fig12
    atm_mid = _mean_between(f10["atm"], 1.0, 3.0)
    atm_far = _mean_between(f10["atm"], 3.0)
    carve_mid = _mean_between(f10["carving"], 1.0, 3.0)
    carve_far = _mean_between(f10["carving"], 3.0)
    w_near = _mean_between(f11["mean"], 1.0, 3.0)
    w_far = _mean_between(f11["mean"], 4.0)
    shrink = w_near is not None and w_far is not None and w_far < w_near
    carve_far_err = _mean_between(f12["carving"], 3.0)
    center_far_err = _mean_between(f12["centerline"], 3.0)
    below_everywhere = all(
        c is None or z is None or c <= z
        for c, z in zip(f12["carving"]["value"], f12["centerline"]["value"], strict=True))
    crossing = next((lo for lo, v in zip(f12["carving"]["edges"][:-1], f12["carving"]["value"],
                                         strict=True) if v is not None and v > f12["atm_bound"]),
                    None)
    out = ["### Fig. 10, 11, 12: latency, carved width and maximum error by range", "",
           f"- Fig. 10 (all history rows, removed arcs counting as processed, as in Table I): "
           f"ATM leaves {fmt_num(atm_mid, 0)} % of arcs of 1-3 m unprocessed and "
           f"{fmt_num(atm_far, 0)} % beyond 3 m, growing with range as eq. 2.2 predicts and as in "
           f"the paper. Carving: {fmt_num(carve_mid, 0)} % and {fmt_num(carve_far, 0)} %; "
           + ("it also grows with range, unlike the paper's nearly flat curve, but stays below "
              "ATM's for long arcs. A long arc is carved only by a newer reading whose freespace "
              "reaches it, that is a long reading beside it, and one must come within the "
              f"history window ({_span(r, page.settings)}), while a short arc is reached by "
              "almost any newer "
              "reading that sweeps across it (the reason long carved arcs also stay wide, Fig. "
              "11 below)." if carve_far is not None and carve_mid is not None
              and carve_far > carve_mid + 5 else "nearly flat, as in the paper."),
           f"- Fig. 11: carved arcs end {fmt_num(w_near, 1)}° wide on average at 1-3 m and "
           f"{fmt_num(w_far, 1)}° beyond 4 m "
           + ("(narrower with range, as in the paper)." if shrink else
              "(wider with range, unlike the paper, where they narrow): a newer reading carves "
              "an old arc only as far as its own freespace reaches, so long arcs need newer long "
              f"readings beside them, and the history ({_span(r, page.settings)}) gives them "
              "little time"
              + _history_effect(_sensitivity(page)) + ".")
           + " Widths are final: the arc's state when it leaves the history.",
           "- Fig. 12: carving's mean maximum error (eq. 5.3) is "
           + ("below centerline's at every range" if below_everywhere else
              "NOT below centerline's at every range")
           + f" ({fmt_num(carve_far_err, 3)} m against {fmt_num(center_far_err, 3)} m beyond "
           "3 m), and "
           f"below ATM's theoretical bound ({f12['atm_bound']:.3f} m: eq. 5.4 in units of the "
           "one-inch range quantum, the same at every range) "
           + (f"up to {crossing:g} m." if crossing is not None else "at every range.")
           + " The paper prints these curves without numbers.", ""]
    for name, alt in (("fig10_unprocessed_by_range.png", "Fig. 10"),
                      ("fig11_carved_width_by_range.png", "Fig. 11"),
                      ("fig12_max_error_by_range.png", "Fig. 12")):
        out += md_image(page.figures, name, alt)
    return out


def _evidence_latency(r: OfficeResult, share5: dict[str, float | None]) -> list[str]:
    """Evidence carving's latency to a right local map against carving's (issue 9's target:
    no worse than carving)."""
    la = r.latency_accuracy
    if "evidence" not in la:
        return []
    tols = [k for k in la["carving"] if k != "patches_seen"]
    parts, worse = [], False
    for t in tols:
        e, c = la["evidence"][t], la["carving"][t]
        parts.append(f"within {float(t) * 100:g} cm {fmt_num(e['resolved_share'], 0)} % of "
                     f"patches right, median {fmt_num(e['median_s'], 2)} s / "
                     f"{fmt_num(e['median_m'], 2)} m, against carving's "
                     f"{fmt_num(c['resolved_share'], 0)} %, {fmt_num(c['median_s'], 2)} s / "
                     f"{fmt_num(c['median_m'], 2)} m")
        worse = worse or _worse(e["resolved_share"], c["resolved_share"], higher=True) \
            or _worse(e["median_s"], c["median_s"], higher=False)
    return [f"- Evidence carving (`evidence`): {'; '.join(parts)}; "
            f"{fmt_num(share5.get('evidence'), 0)} % right within 5 s (carving "
            f"{fmt_num(share5.get('carving'), 0)} %). "
            + ("Its latency is NOT as good as carving's on this measure: it waits for "
               "evidence (several weak misses, or support) where one newer sector carves at "
               "once." if worse else "Its latency is no worse than carving's on this measure.")]


def _worse(value: float | None, reference: float | None, *, higher: bool) -> bool:
    """Whether ``value`` is worse than ``reference`` (``higher``: larger is better)."""
    if value is None or reference is None:
        return False
    return value < reference if higher else value > reference


def _span(r: OfficeResult, settings: Settings) -> str:
    """How long the history reaches back on the office tour, in words."""
    runs = r.office_runs
    size = settings.method_config().history_size
    readings, duration = runs.get("readings"), runs.get("duration_s")
    if not readings or not duration:
        return f"{size} readings"
    seconds = size * duration / readings
    return (f"{size} readings: {seconds:.0f} s and {seconds * settings.speed:.1f} m "
            "of travel here")


def _sensitivity(page: Page) -> JsonDict | None:
    """The sensitivity experiment's tables, when it ran.

    Read by field name rather than by importing its result type, so that no experiment module
    imports another (an import-linter contract).
    """
    tables = getattr(page.results.get("sensitivity"), "sensitivity", None)
    return tables if isinstance(tables, dict) else None


def _history_effect(sensitivity: JsonDict | None) -> str:
    """How carving's error changes from the shortest history swept to the longest."""
    entry = (sensitivity or {}).get("history")
    if not entry or "carving" not in entry or len(set(entry["values"])) < 2:
        return ""
    values, errors = entry["values"], entry["carving"]["error_median"]
    short = min(range(len(values)), key=lambda i: values[i])
    long = max(range(len(values)), key=lambda i: values[i])
    if errors[short] is None or errors[long] is None:
        return ""
    return (f" (the history sweep below: carving's median true error "
            f"{errors[short]:.3f} m with {values[short]:g} arcs, {errors[long]:.3f} m with "
            f"{values[long]:g})")


def _mean_between(entry: JsonDict, low: float = -math.inf,
                  high: float = math.inf) -> float | None:
    """Count-weighted mean of a binned curve over the bins lying within ``[low, high]``."""
    num = den = 0.0
    for lo, hi, v, c in zip(entry["edges"][:-1], entry["edges"][1:], entry["value"],
                            entry["count"], strict=True):
        if lo >= low and hi <= high and v is not None:
            num += v * c
            den += c
    return num / den if den else None


def fig13(r: OfficeResult, page: Page) -> list[str]:
    f = r.fig13
    out = ["### Fig. 13: final global maps", "",
           f"ATM's map keeps the medians of transversal intersections only; carving's keeps "
           f"points whose maximum error is at most {f['threshold_m']:.3f} m, ATM's own bound, so "
           "both maps promise the same accuracy.", "",
           f"The table gives {_seed_stat(page.settings.seeds)} (point counts included); the "
           "figure shows the "
           "maps of seed 0, whose point counts are in its panel titles.", "",
           "| map | points in the global map | points shown | their true error, median / "
           "p90 (m) |", "|---|---:|---:|---:|"]
    for m in [m for m in ("atm", "carving", "combined", "evidence") if m in f]:
        e = f[m]
        out.append(f"| {m} | {fmt_num(e['points'], 0)} | {fmt_num(e['kept'], 0)} | "
                   f"{fmt_num(e['kept_error_median'], 3)} / {fmt_num(e['kept_error_p90'], 3)} |")
    atm, carve = f["atm"], f["carving"]
    out += ["", f"- The paper finds the two maps \"quite similar\", the final accuracy of carving "
            f"\"equivalent to that of ATM\". Here the points shown have median true errors of "
            f"{fmt_num(atm['kept_error_median'], 3)} m (ATM) and "
            f"{fmt_num(carve['kept_error_median'], 3)} "
            f"m (carving), but ATM's map is "
            f"{fmt_num(_ratio(atm['kept'], carve['kept']), 1)} times as dense: ATM keeps every arc "
            f"and refines {fmt_num(_ratio(100 * atm['kept'], atm['points']), 0)} % of them, while "
            f"carving removed {fmt_num(_removed(r), 0)} % of its arcs (fully carved or split) and "
            f"only {fmt_num(_ratio(100 * carve['kept'], carve['points']), 0)} % of the rest are "
            "carved narrow enough to pass the threshold.", ""]
    out += md_image(page.figures, "fig13_global_maps.png", "Fig. 13")
    return out


def _removed(r: OfficeResult) -> float | None:
    fc = r.fully_carved
    share, split = fc.get("share"), fc.get("split_share")
    return share + split if share is not None and split is not None else None


def _ratio(a: float | None, b: float | None) -> float | None:
    return a / b if a is not None and b else None


def _seed_stat(n: int) -> str:
    """``means over seeds 0-N``, or ``seed 0's numbers`` for a one-seed run."""
    seeds = fmt_seeds(n)
    return "seed 0's numbers" if seeds == "seed 0" else f"means over {seeds}"


def true_error(r: OfficeResult, page: Page) -> list[str]:
    te, sp, g = r.true_error, r.true_error_spread, r.true_error_global
    out = ["### Beyond the paper: true error of the maps", "",
           "Distance of every local-map point, at every snapshot (every 16 readings), to the "
           "nearest true wall; and of every global-map point.", "",
           "| method | local map: median (m) | local map: p90 (m) | global map: median | "
           "global map: p90 |", "|---|---:|---:|---:|---:|"]
    for m in [m for m in METHODS if m in sp]:
        out.append(f"| {m} | {fmt_spread(sp[m]['median'], 3)} | {fmt_spread(sp[m]['p90'], 3)} | "
                   f"{fmt_num(g[m]['median'], 3)} | {fmt_num(g[m]['p90'], 3)} |")
    tb = r.truth_breakdown
    if tb:
        out += ["", "Global map judged by truth: share of points from spurious readings, and the "
                "true error of the points from direct readings only (means over seeds):", "",
                "| method | spurious points (%) | direct points: median (m) | "
                "direct points: p90 (m) |", "|---|---:|---:|---:|"]
        for m in [m for m in METHODS if m in tb]:
            e = tb[m]
            out.append(f"| {m} | {fmt_num(e['spurious_share'])} | "
                       f"{fmt_num(e['direct_error']['median'], 3)} | "
                       f"{fmt_num(e['direct_error']['p90'], 3)} |")
    carve, center, atm = te["carving"], te["centerline"], te["atm"]
    out += ["", "- " + (f"Carving's median true error ({carve['median']:.3f} m) is below "
                        f"centerline's ({center['median']:.3f} m), as its bounds (Fig. 12) "
                        "promise" if carve["median"] < center["median"] else
                        f"Carving's median true error ({carve['median']:.3f} m) is NOT below "
                        f"centerline's ({center['median']:.3f} m)")
            + f", and {'above' if carve['median'] > atm['median'] else 'below'} ATM's "
            f"({atm['median']:.3f} m). Its 90th percentile ({carve['p90']:.3f} m) is "
            + ("close to centerline's" if carve["p90"] > 0.8 * center["p90"] else
               "well below centerline's")
            + f" ({center['p90']:.3f} m). The truth shows why: the tail is spurious readings "
            "(carving keeps most of them, see the table above and the fully carved section) "
            "and long arcs carved little or not at all, while the readings carving removes "
            "are mostly short, accurate ones, so its map holds a larger share of long arcs. "
            "Carving plus ATM (combined) has the smallest error: ATM's crossings refine the "
            "long arcs carving leaves wide.", *_evidence_error(r), ""]
    out += md_image(page.figures, "true_error_by_range.png", "true error by range")
    return out


def _evidence_error(r: OfficeResult) -> list[str]:
    """Evidence carving's true error against carving's and centerline's."""
    te, g = r.true_error, r.true_error_global
    if "evidence" not in te or te["evidence"]["median"] is None:
        return []
    ev, carve, center = te["evidence"], te["carving"], te["centerline"]
    return [
        f"- Evidence carving (`evidence`): local-map median {ev['median']:.3f} m and p90 "
        f"{ev['p90']:.3f} m against carving's {carve['median']:.3f} m and {carve['p90']:.3f} m "
        f"(centerline {center['median']:.3f} m and {center['p90']:.3f} m); global map "
        f"{fmt_num(g['evidence']['median'], 3)} / {fmt_num(g['evidence']['p90'], 3)} m against "
        f"carving's {fmt_num(g['carving']['median'], 3)} / {fmt_num(g['carving']['p90'], 3)} m. "
        + ("Its tail is the shorter: it keeps fewer spurious points (table above)."
           if ev["p90"] < carve["p90"] else "Its tail is NOT shorter than carving's.")]


def latency(r: OfficeResult, page: Page) -> list[str]:
    la = r.latency_accuracy
    tols = [k for k in la["carving"] if k != "patches_seen"]
    out = ["### Beyond the paper: latency against accuracy", "",
           f"Every wall is cut into {la['patch_length_m']:g} m patches. A patch comes into view "
           "with the first direct reading that reflects off it; it is *right* at the first "
           "snapshot where at least half of the local-map points of readings that reflected "
           "off it lie within the tolerance of the true walls. Delay from view to right, in "
           "seconds and metres driven (median over the patches that got right).", "",
           "| method | " + " | ".join(f"within {float(t) * 100:g} cm: right (%) | median s | "
                                      "median m" for t in tols) + " |",
           "|---|" + "---:|" * (3 * len(tols))]
    for m in [m for m in METHODS if m in la]:
        cells = []
        for t in tols:
            e = la[m][t]
            cells += [fmt_num(e["resolved_share"], 0), fmt_num(e["median_s"], 1),
                      fmt_num(e["median_m"], 2)]
        out.append(f"| {m} | " + " | ".join(cells) + " |")
    grid = la["grid_s"]
    at5 = grid.index(5.0) if 5.0 in grid else None
    share5 = {m: la[m][tols[0]]["curve_s"][at5] if at5 is not None else None
              for m in METHODS if m in la}
    out += ["", f"- Within 5 s of coming into view, {fmt_num(share5['carving'], 0)} % of "
            "patches are "
            f"right to {float(tols[0]) * 100:g} cm in carving's local map, "
            f"{fmt_num(share5['atm'], 0)} % in ATM's, {fmt_num(share5['centerline'], 0)} % in "
            f"centerline's and {fmt_num(share5['combined'], 0)} % in the combined map: the "
            "latency-accuracy trade-off the paper argues for, measured. Most patches are right "
            "at once (walls seen head-on, where even the centerline point is on the wall); the "
            f"step in every curve is the history's span ({_span(r, page.settings)}): a patch's "
            "first, least "
            "accurate arcs leave the local map then.", *_evidence_latency(r, share5), ""]
    out += md_image(page.figures, "latency_accuracy.png", "latency against accuracy")
    return out
