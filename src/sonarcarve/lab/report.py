"""Write what the experiments produced: ``results.json``, figures, and the RESULTS.md section.

The Markdown section lives between ``<!-- experiments:begin -->`` and
``<!-- experiments:end -->`` of a file whose other parts belong to someone else: only that span
is rewritten (and the appendix's, between its own markers, when the appendix ran). A file that
does not exist yet is created with the sections; an existing one without the experiments
markers is refused (:class:`ReportError`), never appended to. The appendix section is appended
at the end of a file that has the experiments markers but none of its own yet.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from itertools import pairwise
from pathlib import Path

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import atomic_text
from sonarcarve.lab.appendix import APPENDIX_MARKERS, appendix_markdown
from sonarcarve.lab.experiments import ExperimentResults
from sonarcarve.lab.figures import SWEEP_LABELS, write_figures
from sonarcarve.lab.output import (
    Markers,
    check_marked_file,
    copy_into,
    json_ready,
    links_from,
    replace_marked_section,
    write_marked_file,
)
from sonarcarve.typing import JsonDict

__all__ = [
    "BEGIN_MARKER",
    "END_MARKER",
    "EXPERIMENTS_MARKERS",
    "PAPER",
    "ReportError",
    "check_results_md",
    "render_section",
    "replace_section",
    "write_outputs",
]


BEGIN_MARKER = "<!-- experiments:begin -->"
END_MARKER = "<!-- experiments:end -->"

#: The paper's numbers (section 5), where it gives one.
PAPER: JsonDict = {
    "table1": {"atm": 31.75, "carving": 55.59, "combined": 7.68, "centerline": 0.0},
    "fully_carved_share_min": 20.0,  # "over 20 percent of all arcs ... were fully carved"
    "combined_refined_min": 92.0,  # "more than 92 percent of all arcs ... some increase"
}


class ReportError(SonarcarveError):
    """A Markdown file whose experiments markers are missing or broken."""


#: The experiments section's markers in a Markdown file, and the error a broken file raises.
EXPERIMENTS_MARKERS = Markers(BEGIN_MARKER, END_MARKER, ReportError)


# ============================================================================ files


def write_outputs(
    results: ExperimentResults,
    out: str | Path,
    *,
    command: str,
    figures_dir: str | Path | None = None,
    results_md: str | Path | None = None,
) -> list[Path]:
    """Write ``results.json`` and the figures into ``out``; optionally copy the figures and
    regenerate the experiments section of ``results_md``. Returns the files written.

    Raises
    ------
    ReportError, AppendixError
        Before anything is written, when ``results_md`` exists but lacks the experiments
        markers, or either section's markers are broken (see :func:`check_results_md`).
    """
    data = {"command": command, **results.results}
    appendix = any(key.startswith("appendix_") for key in data)  # its own section
    if results_md is not None:
        check_results_md(results_md, appendix=appendix)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_text(folder / "results.json") as handle:
        json.dump(json_ready(data), handle, indent=1, allow_nan=False)
        handle.write("\n")
    written = [folder / "results.json"]
    figures = write_figures(results.results, results.artifacts, folder)
    written += figures
    shown = figures
    if figures_dir is not None:
        shown = [copy_into(path, figures_dir) for path in figures]
        written += shown
    if results_md is not None:
        rel = links_from(results_md, shown)
        sections = [(EXPERIMENTS_MARKERS, render_section(data, command, rel))]
        if appendix:
            sections.append((APPENDIX_MARKERS, appendix_markdown(data, command, rel)))
        written.append(write_marked_file(results_md, sections,
                                         appendable=[APPENDIX_MARKERS]))
    return written


def check_results_md(results_md: str | Path, *, appendix: bool = True) -> None:
    """Check that :func:`write_outputs` can regenerate the sections of ``results_md``.

    Fine when the file does not exist (or is blank): it will be created. Otherwise it must hold
    :data:`BEGIN_MARKER` and :data:`END_MARKER` once each, in order; with ``appendix`` (when the
    appendix experiments run) the appendix's markers must be intact too, or absent (the
    appendix section is then appended).

    Raises
    ------
    ReportError
        The experiments markers are missing or broken (one line naming the file and the line).
    AppendixError
        The appendix markers are broken.
    """
    check_marked_file(results_md, [EXPERIMENTS_MARKERS, *([APPENDIX_MARKERS] if appendix
                                                          else [])],
                      appendable=[APPENDIX_MARKERS])


def replace_section(text: str, section: str, where: str = "RESULTS.md", *,
                    append_missing: bool = False) -> str:
    """``text`` with the span between the markers (inclusive) replaced by ``section``.

    ``section`` must start with :data:`BEGIN_MARKER` and end with :data:`END_MARKER`. A blank
    ``text`` becomes the section; a ``text`` without markers gets it appended only with
    ``append_missing`` (see :func:`~sonarcarve.lab.output.replace_marked_section`).

    Raises
    ------
    ReportError
        When ``text`` has no markers (and not ``append_missing``), only one, or they are out of
        order or repeated; the message names ``where`` and the line.

    Examples
    --------
    >>> replace_section("a\\n<!-- experiments:begin -->\\nold\\n<!-- experiments:end -->\\nb\\n",
    ...                 "<!-- experiments:begin -->\\nnew\\n<!-- experiments:end -->")
    'a\\n<!-- experiments:begin -->\\nnew\\n<!-- experiments:end -->\\nb\\n'
    """
    return replace_marked_section(text, section, BEGIN_MARKER, END_MARKER, where,
                                  append_missing=append_missing, error=ReportError)


# ============================================================================ rendering


def _f(value: float | None, digits: int = 1, unit: str = "") -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "n/a"
    return f"{value:.{digits}f}{unit}"


def _range(spread: JsonDict | None, digits: int = 1) -> str:
    if not spread or spread.get("mean") is None:
        return "n/a"
    if len([v for v in spread["per_seed"] if v is not None]) <= 1:
        return _f(spread["mean"], digits)
    return f"{spread['mean']:.{digits}f} ({spread['min']:.{digits}f}-{spread['max']:.{digits}f})"


def render_section(results: JsonDict, command: str, figures: Sequence[str] = ()) -> str:
    """The Markdown experiments section for ``results`` (``results.json`` content).

    ``figures`` are paths of the PNGs relative to the Markdown file.
    """
    meta = results.get("meta", {})
    settings = meta.get("settings", {})
    config = settings.get("method_config", {})
    figs = {Path(f).name: f for f in figures}
    lines = [
        BEGIN_MARKER,
        "## Experiments: the paper's section 5 on the simulator",
        "",
        "<!-- Generated by sonarcarve.lab.report; edits here are overwritten. -->",
        "",
        f"Produced by `{command}` (`make experiments`). Wall time "
        f"{_f(meta.get('seconds', math.nan) / 60.0, 1)} min for {meta.get('simulations')} "
        f"simulations and {meta.get('jobs')} method runs in {settings.get('jobs')} worker "
        f"process(es), figures excluded; simulation seeds 0-{settings.get('seeds', 1) - 1}. "
        "Every number below is measured on the simulator (`sonarcarve.sim`): the `office` "
        "floor (90 m x 60 m, 5400 m²) driven along its built-in tour. Robot `scout2` (16 sonars, "
        f"φ = {_f(config.get('beam_width_deg'), 1)}°, one-inch range quantum) at "
        f"{_f(settings.get('speed'), 1)} m/s; history {config.get('history_size')} arcs, "
        f"ATM ψ = {_f(config.get('min_transversal_deg'), 0)}°, carving ε = "
        f"{_f(config.get('range_tolerance_m'), 3)} m (the library defaults). "
        "Ranges in brackets are min-max over seeds.",
        "",
    ]
    for part in (_table1, _fully_carved, _fig4, _openings, _fig10_12, _fig13, _true_error,
                 _latency, _sensitivity):
        lines += part(results, figs)
    lines.append(END_MARKER)
    return "\n".join(lines)


def _img(figs: dict[str, str], name: str, alt: str) -> list[str]:
    return [f"![{alt}]({figs[name]})", ""] if name in figs else []


def _table1(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "table1" not in r:
        return []
    paper = PAPER["table1"]
    spread = r["table1_spread"]
    alive = r.get("table1_alive_only", {})
    out = ["### Table I: mean percentage of the history unprocessed", "",
           "| method | paper | ours: all history rows | ours: live arcs only |",
           "|---|---:|---:|---:|"]
    names = {"atm": "ATM", "carving": "Arc carving", "combined": "Arc carving and ATM",
             "centerline": "Centerline"}
    for key, name in names.items():
        out.append(f"| {name} | {paper[key]:.2f} | {_range(spread[key], 2)} | "
                   f"{_f(alive.get(key), 2)} |")
    out += ["", "Sampled every 16 readings once the history is full. *All history rows* is the "
            "library's measure (`SonarMethod.measures().unprocessed_share`; also the one of "
            "Fig. 10 and the sensitivity tables below): an arc carving removed (fully carved, "
            "or split and dropped) stays in the history and counts as processed, since it was "
            "carved. The paper's history drops removed arcs, so its Table I can count only arcs "
            "still alive: *live arcs only* leaves removed arcs out, as the paper would."]
    out += ["", *_table1_sentences(r), ""]
    return out


def _share_below(entry: JsonDict, limit: float) -> float:
    edges, counts = entry["edges"], entry["count"]
    total = sum(counts)
    below = sum(c for lo, c in zip(edges[:-1], counts, strict=True) if lo < limit)
    return 100.0 * below / total if total else math.nan


def _table1_sentences(r: JsonDict) -> list[str]:
    t1, paper = r["table1"], PAPER["table1"]
    alive = r.get("table1_alive_only", {})
    short = _share_below(r["fig10"]["carving"], 1.0)
    carve_short = _mean_between(r["fig10"]["carving"], high=1.0)
    carve_far = _mean_between(r["fig10"]["carving"], 3.0)
    atm_far = _mean_between(r["fig10"]["atm"], 3.0)
    slow_short = carve_short is not None and carve_far is not None and carve_short > carve_far
    return [
        f"- ATM: {t1['atm']:.1f} % against the paper's {paper['atm']:.2f} %"
        + (", close. " if abs(t1["atm"] - paper["atm"]) < 5 else ". ")
        + "ATM's latency is set by how far the robot drives between readings of one obstacle "
        "(eq. 2.2), so it depends on speed, ψ and the tour, which the paper does not give.",
        f"- Arc carving: {t1['carving']:.1f} % of all history rows "
        f"({_f(alive.get('carving'), 1)} % of live arcs only) against {paper['carving']:.2f} %. "
        "The paper "
        "explains its high share by the many short arcs, which carving processes last (its "
        f"Fig. 10). {short:.0f} % of our history arcs are shorter than 1 m, and carving leaves "
        f"{_f(carve_short, 0)} % of them unprocessed against {_f(carve_far, 0)} % of arcs "
        "beyond 3 m: "
        + ("short arcs are the slow ones here too, " if slow_short else
           "here short arcs are not the slow ones, so the paper's explanation does not carry "
           "over to our simulated robot, ")
        + f"which is why our share is {'lower' if t1['carving'] < paper['carving'] else 'so'}. "
        f"Long arcs behave as in the paper: beyond 3 m carving leaves {_f(carve_far, 0)} % "
        f"unprocessed against ATM's {_f(atm_far, 0)} %.",
        f"- Both: {t1['combined']:.1f} % of all history rows "
        f"({_f(alive.get('combined'), 1)} % of live arcs only) against "
        f"{paper['combined']:.2f} %, so "
        + (f"{100 - alive['combined']:.1f} % of the live history arcs gain some azimuth "
           "resolution" if alive.get("combined") is not None else
           f"{100 - t1['combined']:.1f} % of history arcs are processed")
        + f" (paper: more than {PAPER['combined_refined_min']:.0f} %). Combined is never above "
        "the smaller of the two: one history, an arc is processed when either model processed "
        "it." + _combined_sentence(r),
        "- Centerline: 0 % in both, by definition.",
    ]


def _fully_carved(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "fully_carved" not in r:
        return []
    fc, sp = r["fully_carved"], r["fully_carved_spread"]
    return [
        "### Fully carved arcs (section 5-C)", "",
        "| measure | paper | ours |", "|---|---:|---:|",
        f"| arcs fully carved (% of all arcs) | over {PAPER['fully_carved_share_min']:.0f} | "
        f"{_range(sp['share'])} |",
        f"| arcs dropped as split (% of all arcs) | not reported | {_f(fc['split_share'])} |",
        f"| spurious readings removed (% of non-direct readings fully carved) | not measurable |"
        f" {_range(sp['spurious_removed'])} |",
        f"| true readings lost (% of direct readings fully carved) | not measurable | "
        f"{_range(sp['true_lost'])} |",
        f"| fully carved arcs that were spurious (%) | not measurable | "
        f"{_f(fc['spurious_of_removed'])} |",
        f"| spurious readings in the log (%) | not measurable | {_f(fc['spurious_readings'])} |",
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
        "",
    ]


def _lost_sentence(r: JsonDict) -> str:
    tb = r.get("truth_breakdown", {}).get("carving")
    if not tb:
        return ""
    return (f" The direct readings carving removes are mostly short (median range "
            f"{_f(tb['lost_direct_median_range'], 2)} m against "
            f"{_f(tb['kept_direct_median_range'], 2)} m for those it keeps) and were accurate "
            f"already (their centerline points' median true error "
            f"{_f(tb['lost_direct_centerline_error'], 3)} m against "
            f"{_f(tb['kept_direct_centerline_error'], 3)} m). Of the direct arcs that carving "
            f"kept and carved, {_f(tb['carved_contains_truth'], 0)} % still contain the bearing "
            "of their true reflection; the others were carved past it.")


def _fig4(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "t_junction" not in r:
        return []
    tj = r["t_junction"]
    out = ["### Fig. 4: T junction, when the facing wall appears", "",
           f"The robot drives up the stem of the T (2 m corridors) towards the facing wall; the "
           f"wall *shows* in a local map once at least {tj['points']} of its points lie within "
           f"{tj['radius_m']:g} m of that wall. Distance from the robot's centre to the wall at "
           f"that moment, metres (larger is earlier); the drive ends "
           f"{_f(tj.get('end_distance_m'), 2)} m from the wall.", "",
           "| method | any point of the map | refined points only (carved or ATM) |",
           "|---|---:|---:|"]
    for m in ("atm", "carving", "combined", "centerline"):
        refined = "n/a (no refined points)" if m == "centerline" else (
            _range(tj["refined"][m], 2) if tj["refined"][m]["mean"] is not None
            else "never during the drive")
        out.append(f"| {m} | {_range(tj['all'][m], 2)} | {refined} |")
    atm_never = tj["refined"]["atm"]["mean"] is None
    out += ["", "- Paper, Fig. 4: the ATM map has no point on the approaching wall while the "
            "centerline map does. "
            + ("Same here: ATM's medians never reach the facing wall during the drive, "
               if atm_never else "Here ATM's medians reach it late, ")
            + "while carving refines it "
            + (f"{tj['refined']['carving']['mean']:.1f} m before the wall."
               if tj["refined"]["carving"]["mean"] is not None else "not at all either.")
            + " Every map that keeps centerline points shows the wall as soon as it is in range "
            "(the same distance for all), which is why the paper combines them.", ""]
    out += _img(figs, "fig04_t_junction.png", "Fig. 4")
    return out


def _openings(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "openings" not in r:
        return []
    op, d = r["openings"], r["openings_definition"]
    dist = [f"{x:g}" for x in d["distances_m"]]
    out = ["### Fig. 2 and 9: narrow openings passable", "",
           f"{d['runs']} runs: doors of width {', '.join(f'{w:g}' for w in d['widths_m'])} m "
           f"approached at {', '.join(f'{h:g}' for h in d['door_headings_deg'])}° from the "
           f"wall normal aiming {', '.join(f'{o:g}' for o in d['door_offsets_m'])} m off the "
           f"door's centre; drives down a 2 m corridor past a side opening of the same widths "
           f"({', '.join(f'{o:g}' for o in d['corridor_offsets_m'])} m off the centre line); "
           "and the narrow hallway of Fig. 9 (widths above 0.9 m); all seeds. *Passable*: "
           f"along the gap there is a stretch at least {d['clearance_m']:.2f} m wide (Scout2 "
           f"diameter 0.41 m + 0.05 m) with no local-map point within {d['gap_depth_m']:g} m "
           "of the gap line; distances are measured along the drive (how far the robot still "
           "has to go to reach the door or come abreast of the opening).", "",
           "| method | " + " | ".join(f"{x} m before" for x in dist) + " |",
           "|---|" + "---:|" * len(dist)]
    for m in ("centerline", "atm", "carving", "combined"):
        out.append(f"| {m} | " + " | ".join(_f(op[m][x], 0, " %") for x in dist) + " |")
    by = r.get("openings_by_world", {})
    doors = {m: _avg([v for k, v in by.get(m, {}).get(dist[0], {}).items()
                      if k.startswith("doorway")]) for m in op}
    out += ["", "- The paper shows single examples (Fig. 2: centerline misses a doorway; Fig. "
            "9: ATM plus centerline closes a hallway that carving keeps open); here the share "
            f"of runs. At {dist[0]} m, doorways alone: centerline {_f(doors['centerline'], 0)} "
            f"%, ATM {_f(doors['atm'], 0)} %, carving {_f(doors['carving'], 0)} %, combined "
            f"{_f(doors['combined'], 0)} %. Side openings seen from a corridor and the "
            "narrow hallway are passable in almost every map: on specular walls few echoes "
            "come from the gap's edges at the angles that would put centerline points inside "
            "it.", ""]
    out += _img(figs, "fig02_09_openings.png", "Fig. 2 and 9")
    return out


def _removed(r: JsonDict) -> float | None:
    fc = r.get("fully_carved")
    return fc["share"] + fc["split_share"] if fc else None


def _ratio(a: float | None, b: float | None) -> float | None:
    return a / b if a is not None and b else None


def _avg(values: list[float]) -> float | None:
    return sum(values) / len(values) if values else None


def _fig10_12(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "fig10" not in r:
        return []
    f10, f11, f12 = r["fig10"], r["fig11"]["carved_only"], r["fig12"]
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
           f"ATM leaves {_f(atm_mid, 0)} % of arcs of 1-3 m unprocessed and "
           f"{_f(atm_far, 0)} % beyond 3 m, growing with range as eq. 2.2 predicts and as in "
           f"the paper. Carving: {_f(carve_mid, 0)} % and {_f(carve_far, 0)} %; "
           + ("it also grows with range, unlike the paper's nearly flat curve, but stays below "
              "ATM's for long arcs. A long arc is carved only by a newer reading whose freespace "
              "reaches it, that is a long reading beside it, and one must come within the "
              f"history window ({_span(r)}), while a short arc is reached by almost any newer "
              "reading that sweeps across it (the reason long carved arcs also stay wide, Fig. "
              "11 below)." if carve_far is not None and carve_mid is not None
              and carve_far > carve_mid + 5 else "nearly flat, as in the paper."),
           f"- Fig. 11: carved arcs end {_f(w_near, 1)}° wide on average at 1-3 m and "
           f"{_f(w_far, 1)}° beyond 4 m "
           + ("(narrower with range, as in the paper)." if shrink else
              "(wider with range, unlike the paper, where they narrow): a newer reading carves "
              "an old arc only as far as its own freespace reaches, so long arcs need newer long "
              f"readings beside them, and the history ({_span(r)}) gives them little time"
              + _history_effect(r) + ".")
           + " Widths are final: the arc's state when it leaves the history.",
           "- Fig. 12: carving's mean maximum error (eq. 5.3) is "
           + ("below centerline's at every range" if below_everywhere else
              "NOT below centerline's at every range")
           + f" ({_f(carve_far_err, 3)} m against {_f(center_far_err, 3)} m beyond 3 m), and "
           f"below ATM's theoretical bound ({f12['atm_bound']:.3f} m: eq. 5.4 in units of the "
           "one-inch range quantum, the same at every range) "
           + (f"up to {crossing:g} m." if crossing is not None else "at every range.")
           + " The paper prints these curves without numbers.", ""]
    for name, alt in (("fig10_unprocessed_by_range.png", "Fig. 10"),
                      ("fig11_carved_width_by_range.png", "Fig. 11"),
                      ("fig12_max_error_by_range.png", "Fig. 12")):
        out += _img(figs, name, alt)
    return out


def _span(r: JsonDict) -> str:
    """How long the history reaches back on the office tour, in words."""
    runs = r.get("office_runs", {})
    settings = r.get("meta", {}).get("settings", {})
    size = settings.get("method_config", {}).get("history_size", 250)
    readings, duration = runs.get("readings"), runs.get("duration_s")
    if not readings or not duration:
        return f"{size} readings"
    seconds = size * duration / readings
    return (f"{size} readings: {seconds:.0f} s and {seconds * settings.get('speed', 0.0):.1f} m "
            "of travel here")


def _history_effect(r: JsonDict) -> str:
    """How carving's error changes from the shortest history swept to the longest."""
    entry = r.get("sensitivity", {}).get("history")
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


def _seeds(r: JsonDict) -> str:
    """``seed 0`` or ``seeds 0-N`` of the run's settings."""
    n = int(r.get("meta", {}).get("settings", {}).get("seeds", 1))
    return "seed 0" if n == 1 else f"seeds 0-{n - 1}"


def _seed_stat(r: JsonDict) -> str:
    """``means over seeds 0-N``, or ``seed 0's numbers`` for a one-seed run."""
    seeds = _seeds(r)
    return "seed 0's numbers" if seeds == "seed 0" else f"means over {seeds}"


def _unprocessed_counts(entry: JsonDict) -> list[float]:
    """Unprocessed arcs per range bin of a Fig. 10 curve (share times arcs), 0 for empty bins."""
    return [0.0 if v is None else v * c / 100.0 for v, c in zip(entry["value"], entry["count"],
                                                                 strict=True)]


def _combined_sentence(r: JsonDict) -> str:
    """Why combined's unprocessed share is above the paper's: the two models' latencies are
    correlated through range here, anti-correlated in the paper (from Fig. 10's bins)."""
    f10, t1, paper = r.get("fig10", {}), r["table1"], PAPER["table1"]
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
            f"3 m, where ATM also leaves {_f(_mean_between(atm, 3.0), 0)} % unprocessed (Fig. "
            "10), so the two latencies are correlated through range: were they independent, "
            f"combined would leave {t1['carving']:.1f} % × {t1['atm']:.1f} % = "
            f"{t1['carving'] * t1['atm'] / 100.0:.1f} %, independent within each 0.5 m range "
            f"bin {100.0 * per_bin / total:.1f} %; it leaves {t1['combined']:.1f} %. In the "
            "paper carving's slow arcs were the short ones, which ATM processes quickly: its "
            f"{paper['combined']:.2f} % is far below its own {paper['carving']:.2f} % × "
            f"{paper['atm']:.2f} % = {paper['carving'] * paper['atm'] / 100.0:.1f} %.")


def _fig13(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "fig13" not in r:
        return []
    f = r["fig13"]
    out = ["### Fig. 13: final global maps", "",
           f"ATM's map keeps the medians of transversal intersections only; carving's keeps "
           f"points whose maximum error is at most {f['threshold_m']:.3f} m, ATM's own bound, so "
           "both maps promise the same accuracy.", "",
           f"The table gives {_seed_stat(r)} (point counts included); the figure shows the "
           "maps of seed 0, whose point counts are in its panel titles.", "",
           "| map | points in the global map | points shown | their true error, median / "
           "p90 (m) |", "|---|---:|---:|---:|"]
    for m in ("atm", "carving", "combined"):
        e = f[m]
        out.append(f"| {m} | {_f(e['points'], 0)} | {_f(e['kept'], 0)} | "
                   f"{_f(e['kept_error_median'], 3)} / {_f(e['kept_error_p90'], 3)} |")
    atm, carve = f["atm"], f["carving"]
    out += ["", f"- The paper finds the two maps \"quite similar\", the final accuracy of carving "
            f"\"equivalent to that of ATM\". Here the points shown have median true errors of "
            f"{_f(atm['kept_error_median'], 3)} m (ATM) and {_f(carve['kept_error_median'], 3)} "
            f"m (carving), but ATM's map is "
            f"{_f(_ratio(atm['kept'], carve['kept']), 1)} times as dense: ATM keeps every arc "
            f"and refines {_f(_ratio(100 * atm['kept'], atm['points']), 0)} % of them, while "
            f"carving removed {_f(_removed(r), 0)} % of its arcs (fully carved or split) and "
            f"only {_f(_ratio(100 * carve['kept'], carve['points']), 0)} % of the rest are "
            "carved narrow enough to pass the threshold.", ""]
    out += _img(figs, "fig13_global_maps.png", "Fig. 13")
    return out


def _true_error(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "true_error" not in r:
        return []
    te, sp, g = r["true_error"], r["true_error_spread"], r["true_error_global"]
    out = ["### Beyond the paper: true error of the maps", "",
           "Distance of every local-map point, at every snapshot (every 16 readings), to the "
           "nearest true wall; and of every global-map point.", "",
           "| method | local map: median (m) | local map: p90 (m) | global map: median | "
           "global map: p90 |", "|---|---:|---:|---:|---:|"]
    for m in ("centerline", "atm", "carving", "combined"):
        out.append(f"| {m} | {_range(sp[m]['median'], 3)} | {_range(sp[m]['p90'], 3)} | "
                   f"{_f(g[m]['median'], 3)} | {_f(g[m]['p90'], 3)} |")
    tb = r.get("truth_breakdown", {})
    if tb:
        out += ["", "Global map judged by truth: share of points from spurious readings, and the "
                "true error of the points from direct readings only (means over seeds):", "",
                "| method | spurious points (%) | direct points: median (m) | "
                "direct points: p90 (m) |", "|---|---:|---:|---:|"]
        for m in ("centerline", "atm", "carving", "combined"):
            e = tb[m]
            out.append(f"| {m} | {_f(e['spurious_share'])} | "
                       f"{_f(e['direct_error']['median'], 3)} | "
                       f"{_f(e['direct_error']['p90'], 3)} |")
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
            "long arcs carving leaves wide.", ""]
    out += _img(figs, "true_error_by_range.png", "true error by range")
    return out


def _latency(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "latency_accuracy" not in r:
        return []
    la = r["latency_accuracy"]
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
    for m in ("centerline", "atm", "carving", "combined"):
        cells = []
        for t in tols:
            e = la[m][t]
            cells += [_f(e["resolved_share"], 0), _f(e["median_s"], 1), _f(e["median_m"], 2)]
        out.append(f"| {m} | " + " | ".join(cells) + " |")
    grid = la["grid_s"]
    at5 = grid.index(5.0) if 5.0 in grid else None
    share5 = {m: la[m][tols[0]]["curve_s"][at5] if at5 is not None else None
              for m in ("centerline", "atm", "carving", "combined")}
    out += ["", f"- Within 5 s of coming into view, {_f(share5['carving'], 0)} % of patches are "
            f"right to {float(tols[0]) * 100:g} cm in carving's local map, "
            f"{_f(share5['atm'], 0)} % in ATM's, {_f(share5['centerline'], 0)} % in "
            f"centerline's and {_f(share5['combined'], 0)} % in the combined map: the "
            "latency-accuracy trade-off the paper argues for, measured. Most patches are right "
            "at once (walls seen head-on, where even the centerline point is on the wall); the "
            f"step in every curve is the history's span ({_span(r)}): a patch's first, least "
            "accurate arcs leave the local map then.", ""]
    out += _img(figs, "latency_accuracy.png", "latency against accuracy")
    return out


def _sensitivity(r: JsonDict, figs: dict[str, str]) -> list[str]:
    if "sensitivity" not in r:
        return []
    sens = r["sensitivity"]
    sc = sens["scenario"]
    out = [f"### Beyond the paper: sensitivity (seed {sc['seed']} only)", "",
           ("The whole office tour" if sc["length_m"] is None else
            f"The first {sc['length_m']:g} m of the office tour") + f", seed {sc['seed']} only "
           f"(one run per value, where the sections above average {_seeds(r)}); one "
           "parameter changed at a time from the defaults above; simulations shared by every "
           "parameter that does not change them (history, ε, ψ). Median true error of the "
           "local map (m) / unprocessed (% of all history rows, as in Table I) / fully carved "
           "(%):", ""]
    for param, entry in sens.items():
        if param == "scenario":
            continue
        methods = [m for m in ("carving", "atm", "combined", "centerline") if m in entry]
        out += [f"**{SWEEP_LABELS[param]}**" if param in SWEEP_LABELS else
                f"**{param}** ({entry['unit']})", "",
                "| value | " + " | ".join(methods) + " |", "|---|" + "---:|" * len(methods)]
        for i, v in enumerate(entry["values"]):
            cells = [f"{_f(entry[m]['error_median'][i], 3)} / "
                     f"{_f(entry[m]['unprocessed'][i], 0)} / "
                     f"{_f(entry[m]['fully_carved'][i], 0)}" for m in methods]
            out.append(f"| {v:g} | " + " | ".join(cells) + " |")
        out.append("")
    out += _sweep_sentences(sens)
    out += _img(figs, "sensitivity.png", "sensitivity")
    return out


def _sweep_sentences(sens: JsonDict) -> list[str]:
    """One line per sweep: the first and last value of each method's median true error."""

    def ends(param: str, method: str, key: str = "error_median") -> str:
        entry = sens.get(param)
        if not entry or method not in entry:
            return "n/a"
        v = entry["values"]
        e = entry[method][key]
        digits = 3 if key == "error_median" else 0
        unit = " m" if key == "error_median" else " %"
        return f"{_f(e[0], digits, unit)} at {v[0]:g} to {_f(e[-1], digits, unit)} at {v[-1]:g}"

    beam_center, beam_carve = ends("beam_width_deg", "centerline"), ends("beam_width_deg",
                                                                          "carving")
    psi_atm = ends("min_transversal_deg", "atm", "unprocessed")
    return [
        "- History (the paper: a longer history \"can result in an even further improvement "
        f"in resolution\"): carving's median true error goes from {ends('history', 'carving')} "
        f"arcs, its unprocessed share from {ends('history', 'carving', 'unprocessed')}; the "
        "cost is O(mn) time and a local map slower to forget.",
        "- Range tolerance ε (the paper has none, ε = 0): carving's error goes from "
        f"{ends('range_tolerance', 'carving')} m and its fully carved share from "
        f"{ends('range_tolerance', 'carving', 'fully_carved')} m: with noisy, quantised "
        "ranges, ε = 0 lets a newer reading of the same wall carve the true echo away.",
        f"- Beam width φ: centerline's error goes from {beam_center}°, carving's from "
        f"{beam_carve}°.",
        f"- ψ: ATM's unprocessed share goes from {psi_atm}° (eq. 2.2: larger ψ needs more "
        "travel)." + _psi_sentence(sens),
        f"- Speed: ATM's unprocessed share goes from {ends('speed', 'atm', 'unprocessed')} "
        f"m/s; carving's error from {ends('speed', 'carving')} m/s.",
        f"- Range noise: carving's error goes from {ends('range_noise', 'carving')} m, "
        f"ATM's from {ends('range_noise', 'atm')} m, centerline's from "
        f"{ends('range_noise', 'centerline')} m.", ""]


def _psi_sentence(sens: JsonDict) -> str:
    """Why ATM's median error need not be monotone in ψ: its points are a mixture of crossings
    and centerline fallbacks whose share and kind change with ψ."""
    entry = sens.get("min_transversal_deg")
    if not entry or "atm" not in entry or len(entry["values"]) < 2:
        return ""
    atm, values = entry["atm"], entry["values"]
    err = atm["error_median"]
    needed = ("refined_share", "error_median_refined", "error_median_fallback",
              "fallback_median_range")
    if any(v is None for v in err) or not all(k in atm for k in needed):
        return ""
    lo, hi = 0, len(values) - 1
    steps = [b - a for a, b in pairwise(err)]
    monotone = all(d >= 0 for d in steps) or all(d <= 0 for d in steps)
    peak = max(range(len(err)), key=lambda i: err[i])
    if monotone:
        shape = (f"{'rises' if err[hi] >= err[lo] else 'falls'} from {err[lo]:.3f} m at "
                 f"{values[lo]:g}° to {err[hi]:.3f} m at {values[hi]:g}°")
    else:
        shape = (f"is not monotone in ψ: {err[lo]:.3f} m at {values[lo]:g}°, largest "
                 f"({err[peak]:.3f} m) at {values[peak]:g}°, {err[hi]:.3f} m at "
                 f"{values[hi]:g}°")
    fallback = [None if v is None else 100.0 - v for v in atm["refined_share"]]
    f_range, f_err = atm["fallback_median_range"], atm["error_median_fallback"]

    def at(key: str, i: int, digits: int = 3) -> str:
        return _f(atm[key][i], digits)

    out = (f" ATM's median error {shape}. Its local map mixes crossings (median error "
           f"{at('error_median_refined', lo)} m at {values[lo]:g}°, "
           f"{at('error_median_refined', hi)} m at {values[hi]:g}°) with centerline "
           f"fallbacks, {_f(fallback[lo], 0)} % of its points at {values[lo]:g}° and "
           f"{_f(fallback[hi], 0)} % at {values[hi]:g}°: a larger ψ admits fewer crossings, "
           "each better conditioned (eq. 5.4), and leaves more arcs to centerline.")
    if None in (f_range[lo], f_range[hi], f_err[lo], f_err[hi]):
        return out
    if f_range[hi] < f_range[lo] and f_err[hi] < f_err[lo]:
        out += (f" At small ψ the fallbacks are the long arcs no pair crosses in time (median "
                f"range {f_range[lo]:.2f} m, error {f_err[lo]:.3f} m); at large ψ shorter arcs "
                f"fall back too (median range {f_range[hi]:.2f} m), which centerline already "
                f"places well (error {f_err[hi]:.3f} m), so the mixture's median follows the "
                "share and the kind of the fallbacks, not ψ alone.")
    return out
