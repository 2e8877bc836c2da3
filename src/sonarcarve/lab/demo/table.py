"""The demo's tables and summaries: the methods table and its caption, the grid table and its
caption, ``summary.md``, ``summary.json``.

Pure text from a :class:`~sonarcarve.lab.demo.results.DemoResult`; the CLI prints the tables
(:func:`table_rows`, :func:`caption`, :func:`grid_table_rows`, :func:`grid_caption`) and
:func:`~sonarcarve.lab.demo.outputs.write_demo_outputs` writes the summaries.
"""

from __future__ import annotations

import json
import math
from typing import Any

from sonarcarve.lab.demo.animation import ANIMATION_FILE, ANIMATION_TEXT
from sonarcarve.lab.demo.doors import doors_tell_apart
from sonarcarve.lab.demo.figures import FIGURE_FILES, FIGURE_TEXT
from sonarcarve.lab.demo.grid_figure import (
    GRID_FIGURE_FILE,
    GRID_FIGURE_TEXT,
    free_verdict,
    grid_verdict,
)
from sonarcarve.lab.demo.kept_figure import KEPT_FIGURE_FILE, KEPT_FIGURE_TEXT, kept_rows
from sonarcarve.lab.demo.results import DemoResult, MethodSummary
from sonarcarve.lab.demo.scenario import (
    APPROACH_DISTANCE,
    CLOSEUP_METHODS,
    METHOD_LABELS,
    PAPER_METHODS,
)
from sonarcarve.lab.grid_measures import NEAR_PATH
from sonarcarve.lab.output import json_ready

__all__ = [
    "GRID_COLUMNS",
    "TABLE_COLUMNS",
    "caption",
    "door_note",
    "grid_caption",
    "grid_table_rows",
    "method_verdict",
    "summary_json",
    "summary_markdown",
    "table_rows",
]


def _pct(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.1f}"


def _rate(value: float) -> str:
    if not math.isfinite(value):
        return "–"
    return f"{value / 1000.0:,.0f}k" if value >= 10_000.0 else f"{value:,.0f}"


def _cm(value: float) -> str:
    return "–" if math.isnan(value) else f"{100.0 * value:.1f}"


#: Table columns: (key, header as printed with line breaks, unit-free description).
TABLE_COLUMNS = (
    ("method", "method", "sonar processing method"),
    ("readings", "readings", "sonar readings processed"),
    ("unprocessed_pct", "unpro-\ncessed\n%",
     "mean share of the history not yet processed (arcs carving removed count as processed; "
     "lower is better: less latency)"),
    ("median_error_m", "median\nerror\ncm",
     "median distance of map points to the true walls (lower is better)"),
    ("p90_error_m", "p90\nerror\ncm",
     "90th percentile of that distance (lower is better: fewer points far off)"),
    ("fully_carved_pct", "fully\ncarved\n%", "readings whose whole arc was carved away"),
    ("spurious_removed_pct", "spurious\nremoved\n%",
     "of the spurious readings, share left out of the map (higher is better)"),
    ("true_lost_pct", "true\nlost\n%",
     "of the true wall echoes, share left out of the map (lower is better)"),
    ("map_points", "map\npoints", "points in the final map"),
    ("readings_per_second", "readings\nper s", "processing speed"),
)


#: Grid table columns: (key, header as printed with line breaks, description).
GRID_COLUMNS = (
    ("grid", "grid", "occupancy grid, built from the same readings"),
    ("precision", "occupied\nprecision",
     "share of the occupied cells within one cell of a true wall (higher is better)"),
    ("recall", "recall",
     "share of the seen wall cells with an occupied cell within one cell (higher is better)"),
    ("phantoms", "phantom\n%", "share of the truly free cells marked occupied (lower is better)"),
    ("free_near_path", "free\nnear\npath %",
     f"share of the truly free floor within {NEAR_PATH:g} m of the robot's path marked free, "
     "what a planner may drive through (higher is better)"),
    ("cpu_us_per_reading", "CPU µs\nper\nreading",
     "processor time per reading: folding it in, and reading the map once at the end"),
)


def _share(value: float) -> str:
    return "–" if math.isnan(value) else f"{value:.2f}"


def grid_table_rows(result: DemoResult) -> tuple[list[str], list[list[str]]]:
    """Header (with line breaks) and cells of the grid table (empty rows without grids)."""
    header = [title for _, title, _ in GRID_COLUMNS]
    rows = [[g.label, _share(g.measures.precision), _share(g.measures.recall),
             _pct(100.0 * g.measures.phantoms), _pct(100.0 * g.measures.free_near_path),
             "–" if math.isnan(g.cpu_us_per_reading) else f"{g.cpu_us_per_reading:.0f}"]
            for g in result.grids]
    return header, rows


def grid_caption(result: DemoResult) -> str:
    """How to read the grid table, and which grid is better (one paragraph; empty without
    grids)."""
    if not result.grids:
        return ""
    text = (f"How to read: both grids mapped the same readings into "
            f"{result.grids[0].resolution:.2f} m cells, read as a planner reads them (occupied, "
            "free, unknown). Precision: share of the occupied cells that lie on a true wall "
            "(within one cell); recall: share of the walls the sonars saw that are marked; "
            "phantoms: free space marked occupied; free near path: the floor a planner may "
            "drive through, marked free.")
    verdict = grid_verdict(result)
    text = f"{text} Here {verdict}." if verdict else text
    free = free_verdict(result)
    return f"{text} {free[0].upper()}{free[1:]}." if free else text


def table_rows(result: DemoResult) -> tuple[list[str], list[list[str]]]:
    """Header (with line breaks) and cells of the demo table, as printed and in ``summary.md``."""
    header = [title for _, title, _ in TABLE_COLUMNS]
    rows = [[row.label, f"{row.readings:,}", _pct(row.unprocessed_pct), _cm(row.median_error_m),
             _cm(row.p90_error_m), _pct(row.fully_carved_pct), _pct(row.spurious_removed_pct),
             _pct(row.true_lost_pct), f"{row.map_points:,}", _rate(row.readings_per_second)]
            for row in result.methods]
    return header, rows


def caption(result: DemoResult) -> str:
    """How to read the table, in plain words, with this run's numbers (one paragraph)."""
    sim = result.simulation
    kinds = sim.kind_counts()
    spurious = sum(v for k, v in kinds.items() if k != "direct")
    parts = [
        f"How to read: every method mapped the same {len(sim.readings):,} readings "
        f"({spurious:,} of them spurious echoes) of a {sim.trajectory.path_length:.0f} m "
        f"simulated tour of '{result.world.name}'. Error is the distance from a map point to "
        "the true walls; unprocessed is the share of the history still waiting for a later "
        "reading to refine it (latency). Lower is better for both."
    ]
    names = {row.method for row in result.methods}
    if "centerline" in names:
        base = result.summary("centerline")
        for method, name in (("carve", "Carving"), ("atm", "ATM"), ("combined", "Combined"),
                             ("evidence", "Evidence carving (beyond the paper)")):
            if method in names:
                parts.append(_compare(name, result.summary(method), base))
    carve = result.summary("carve") if "carve" in names else None
    if carve is not None and math.isfinite(carve.spurious_removed_pct + carve.true_lost_pct):
        parts.append(f"Carving left out {carve.spurious_removed_pct:.0f}% of the spurious "
                     f"readings, but also {carve.true_lost_pct:.0f}% of the true ones.")
    evidence = result.summary("evidence") if "evidence" in names else None
    if evidence is not None and math.isfinite(evidence.spurious_removed_pct
                                              + evidence.true_lost_pct):
        parts.append(f"Evidence carving left out {evidence.spurious_removed_pct:.0f}% of the "
                     f"spurious readings and {evidence.true_lost_pct:.0f}% of the true ones.")
    hidden = result.occlusion
    if hidden is not None and math.isfinite(hidden.spurious_removed_pct + hidden.true_lost_pct):
        parts.append(f"With the occlusion filter on its final map (`sonarcarve process --method "
                     f"{hidden.method} --occlusion-depth {hidden.depth_m:g}`: points behind a "
                     "wall of the map, as multipath echoes are), it left out "
                     f"{hidden.spurious_removed_pct:.0f}% and {hidden.true_lost_pct:.0f}%.")
    return " ".join(parts)


def method_verdict(result: DemoResult) -> str:
    """Which method made the sharpest map, in one sentence with the numbers; empty with fewer
    than two methods that placed points. Printed on its own line between the table and its
    caption, and so written in ``summary.md`` (``verdict`` in ``summary.json``).

    Sharpest is the lowest 90th-percentile error, compared as the table shows it (to a tenth
    of a centimetre; a tie goes to the method listed first): the median alone hides the points
    that a smeared or spurious arc puts far from any wall, which are what close doorways. When
    that method is beyond the paper, the best of the paper's methods is named too, since
    figures 1-3 draw only those.

    Examples: "Sharpest map: evidence carving (beyond the paper), 90% of its points within
    12.5 cm of a true wall (centerline: 90.2 cm; the best of the paper's methods, combined:
    35.3 cm); figures 1-3 draw the paper's methods only, fig. 6 draws it beside carving."
    (fig. 6 is named only when carving ran too: it is what the figure sets it beside.)
    """
    rows = [row for row in result.methods if math.isfinite(row.p90_error_m)]
    if len(rows) < 2:
        return ""
    best = min(rows, key=lambda row: round(100.0 * row.p90_error_m, 1))
    others = []
    if best.method != "centerline" and "centerline" in {row.method for row in rows}:
        others.append(f"centerline: {_cm(result.summary('centerline').p90_error_m)} cm")
    paper = [row for row in rows if row.method in PAPER_METHODS]
    if best.method not in PAPER_METHODS and paper:
        runner_up = min(paper, key=lambda row: round(100.0 * row.p90_error_m, 1))
        others.append(f"the best of the paper's methods, {METHOD_LABELS[runner_up.method]}: "
                      f"{_cm(runner_up.p90_error_m)} cm")
    text = (f"Sharpest map: {best.label}, 90% of its points within {_cm(best.p90_error_m)} cm "
            "of a true wall")
    text += f" ({'; '.join(others)})" if others else ""
    if best.method not in PAPER_METHODS:
        text += "; figures 1-3 draw the paper's methods only"
        if "carve" in {row.method for row in result.methods}:
            text += ", fig. 6 draws it beside carving"
    return text + "."


def door_note(result: DemoResult) -> str:
    """A sentence when no door of the tour tells the methods apart, else empty.

    When every method fig. 4 draws leaves every approached door passable, fig. 4 and the
    animation would show three open doors; they show the doorway world's door instead
    (:attr:`DemoResult.door_scene`), and this says so, with what each method left free there.
    """
    doors = result.doors
    if doors_tell_apart(doors):
        return ""
    seen = (f"Doors: every door this tour approaches ({len(doors):,}) looks passable "
            f"{APPROACH_DISTANCE:g} m before it in each local map")
    scene = result.door_scene
    door = scene.closeup if scene is not None else None
    if scene is None or door is None:
        return f"{seen}, so fig. 4 and the animation show no method closing one."
    gap = math.dist(door.jambs[0], door.jambs[1])
    widths = "; ".join(
        f"{METHOD_LABELS.get(m, m)} {door.free_width[m]:.2f} m free"
        f"{'' if door.passable[m] else ', blocked'}"
        for m in CLOSEUP_METHODS if m in door.free_width)
    return (f"{seen}, so fig. 4 and approach.gif show the '{scene.world.name}' world's "
            f"{gap:.2f} m door instead (the paper's Fig. 2, a short drive simulated for them; "
            f"`sonarcarve demo --world {scene.world.name}` maps it alone): {widths}.")


def _door_figure(result: DemoResult) -> dict[str, Any]:
    """What fig. 4 and the animation show: the world, and that world's door with what each
    method left free (the tour's own, or the door scene's)."""
    source = result.door_source
    door = source.closeup
    return {"world": source.world.name, "door_scene": result.door_scene is not None,
            "opening": None if door is None else door.opening,
            "jambs": None if door is None else door.jambs.tolist(),
            "free_width_m": None if door is None else door.free_width,
            "passable": None if door is None else door.passable}


def _compare(name: str, row: MethodSummary, base: MethodSummary) -> str:
    """"Carving: points 2.0x closer to the walls than centerline (...), 22% unprocessed."."""
    ratio = base.median_error_m / row.median_error_m if row.median_error_m > 0.0 else math.nan
    if not math.isfinite(ratio):
        how = "no points to compare"
    elif ratio >= 1.05:
        how = f"points {ratio:.1f}x closer to the walls than centerline's"
    elif ratio <= 1.0 / 1.05:
        how = f"points {1.0 / ratio:.1f}x FARTHER from the walls than centerline's"
    else:
        how = "points as close to the walls as centerline's"
    return (f"{name}: {how} (median {_cm(row.median_error_m)} against "
            f"{_cm(base.median_error_m)} cm), {row.unprocessed_pct:.0f}% of the history "
            "unprocessed.")


def summary_markdown(result: DemoResult, *, animation: bool = False) -> str:
    """``summary.md``: the table, its caption, the figures (with ``animation``, the door
    approach's GIF after fig. 4, as it is written beside them) and how the run was made."""
    sim = result.simulation
    header, rows = table_rows(result)
    header = [_flat(title) for title in header]
    lines = [f"# sonarcarve demo: {result.world.name}, seed {result.seed}", ""]
    lines.append("| " + " | ".join(header) + " |")
    lines.append("|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|")
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    verdict = method_verdict(result)
    lines += ["", f"**{verdict}**"] if verdict else []
    lines += ["", caption(result), "", "Columns:", ""]
    lines += [f"- {_flat(title)}: {text}" for _, title, text in TABLE_COLUMNS[1:]]
    lines += _grid_markdown(result)
    lines += ["", "## Figures", ""]
    lines += [f"- [{name}]({name}): {text}" for name, text in _figures(result, animation)]
    note = door_note(result)
    lines += ["", note] if note else []
    lines += ["", "## Run", "",
              f"- world: {result.world.name}; seed {result.seed}; history "
              f"{result.config.history_size} arcs; tour {sim.trajectory.path_length:.0f} m in "
              f"{sim.trajectory.duration:.0f} s",
              f"- robot: {sim.robot.name}; readings per kind: "
              + ", ".join(f"{k} {v:,}" for k, v in sim.kind_counts().items()),
              "- seconds: " + ", ".join(f"{k} {v:.2f}" for k, v in result.seconds.items()), ""]
    return "\n".join(lines)


def _figures(result: DemoResult, animation: bool) -> list[tuple[str, str]]:
    """``(file name, what it shows)`` of every figure of the demo's output, in viewing order."""
    figures = [(name, FIGURE_TEXT[key]) for key, name in FIGURE_FILES.items()]
    if animation:
        figures.append((ANIMATION_FILE, ANIMATION_TEXT))
    if result.grids:
        figures.append((GRID_FIGURE_FILE, GRID_FIGURE_TEXT))
    if kept_rows(result):
        figures.append((KEPT_FIGURE_FILE, KEPT_FIGURE_TEXT))
    return figures


def _flat(title: str) -> str:
    """A printed header on one line ("unpro-\ncessed\n%" -> "unprocessed %")."""
    return title.replace("-\n", "").replace("\n", " ")


def _grid_markdown(result: DemoResult) -> list[str]:
    """The grid table of ``summary.md``, its caption and columns (no lines without grids)."""
    if not result.grids:
        return []
    header, rows = grid_table_rows(result)
    lines = ["", "## Occupancy grids", "", "| " + " | ".join(_flat(t) for t in header) + " |",
             "|" + "|".join(["---"] + ["---:"] * (len(header) - 1)) + "|"]
    lines += ["| " + " | ".join(cells) + " |" for cells in rows]
    lines += ["", grid_caption(result), "", "Columns:", ""]
    lines += [f"- {_flat(title)}: {text}" for _, title, text in GRID_COLUMNS[1:]]
    return lines


def summary_json(result: DemoResult, *, animation: bool = False) -> str:
    """``summary.json``: settings, one record per method, the doors, timings; its
    ``figures`` as :func:`summary_markdown` lists them."""
    sim = result.simulation
    data: dict[str, Any] = {
        "world": result.world.name,
        "seed": result.seed,
        "robot": sim.robot.name,
        "history_size": result.config.history_size,
        "tour_m": sim.trajectory.path_length,
        "tour_s": sim.trajectory.duration,
        "readings": len(sim.readings),
        "readings_by_kind": sim.kind_counts(),
        "methods": [row.as_dict() for row in result.methods],
        "occlusion_filter": None if result.occlusion is None else result.occlusion.as_dict(),
        "approach_distance_m": APPROACH_DISTANCE,
        "doors": [{"opening": d.opening, "how": d.how, "jambs": d.jambs.tolist(),
                   "readings": d.view.readings, "t": d.view.t,
                   "distance_m": d.distance,
                   "free_width_m": d.free_width, "passable": d.passable} for d in result.doors],
        "closeup_opening": None if result.closeup is None else result.closeup.opening,
        "door_figure": _door_figure(result),
        "door_note": door_note(result),
        "verdict": method_verdict(result),
        "caption": caption(result),
        "figures": [name for name, _ in _figures(result, animation)],
        "grids": [g.as_dict() for g in result.grids],
        "grid_caption": grid_caption(result),
        "seconds": result.seconds,
    }
    return json.dumps(json_ready(data), indent=2, allow_nan=False) + "\n"
