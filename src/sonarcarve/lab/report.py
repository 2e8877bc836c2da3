"""Write what the experiments produced: ``results.json``, figures, and the RESULTS.md sections.

This is the edge of the lab: typed results become JSON here (:func:`results_json`), figures
become files and each experiment's Markdown parts are put together into two generated sections
of a Markdown file, the experiments section between ``<!-- experiments:begin -->`` and
``<!-- experiments:end -->`` and the appendix section between ``<!-- appendix:begin -->`` and
``<!-- appendix:end -->``. The rest of the file belongs to someone else: only those spans are
rewritten. A file that does not exist yet is created with the sections; an existing one without
the experiments markers is refused (:class:`ReportError`), never appended to. The appendix
section is appended at the end of a file that has the experiments markers but none of its own
yet.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, fields
from pathlib import Path
from typing import Any

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import atomic_text
from sonarcarve.lab.experiments import EXPERIMENTS, ExperimentResults
from sonarcarve.lab.experiments.appendix_base import AppendixError
from sonarcarve.lab.experiments.base import Page, Part
from sonarcarve.lab.formatting import fmt_num
from sonarcarve.lab.output import (
    Markers,
    check_marked_file,
    copy_into,
    json_ready,
    links_from,
    replace_marked_section,
    write_marked_file,
)
from sonarcarve.lab.plan import Settings
from sonarcarve.typing import JsonDict

__all__ = [
    "APPENDIX_BEGIN_MARKER",
    "APPENDIX_END_MARKER",
    "APPENDIX_MARKERS",
    "BEGIN_MARKER",
    "END_MARKER",
    "EXPERIMENTS_MARKERS",
    "ReportError",
    "check_results_md",
    "render_sections",
    "replace_section",
    "result_json",
    "results_json",
    "settings_json",
    "write_outputs",
]


BEGIN_MARKER = "<!-- experiments:begin -->"
END_MARKER = "<!-- experiments:end -->"
APPENDIX_BEGIN_MARKER = "<!-- appendix:begin -->"
APPENDIX_END_MARKER = "<!-- appendix:end -->"


class ReportError(SonarcarveError):
    """A Markdown file whose experiments markers are missing or broken."""


#: The experiments section's markers in a Markdown file, and the error a broken file raises.
EXPERIMENTS_MARKERS = Markers(BEGIN_MARKER, END_MARKER, ReportError)
#: The appendix section's markers, and the error a broken file raises.
APPENDIX_MARKERS = Markers(APPENDIX_BEGIN_MARKER, APPENDIX_END_MARKER, AppendixError)


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
    regenerate the sections of ``results_md``. Returns the files written.

    The appendix section is written when an appendix experiment ran.

    Raises
    ------
    ReportError, AppendixError
        Before anything is written, when ``results_md`` exists but lacks the experiments
        markers, or either section's markers are broken (see :func:`check_results_md`).
    """
    appendix = _ran_appendix(results)
    if results_md is not None:
        check_results_md(results_md, appendix=appendix)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_text(folder / "results.json") as handle:
        json.dump(results_json(results, command), handle, indent=1, allow_nan=False)
        handle.write("\n")
    written = [folder / "results.json"]
    figures = [path for name, result in results.results.items()
               for path in EXPERIMENTS[name].figure(result, results.artifacts.get(name, {}),
                                                   folder)]
    written += figures
    shown = figures
    if figures_dir is not None:
        shown = [copy_into(path, figures_dir) for path in figures]
        written += shown
    if results_md is not None:
        sections = render_sections(results, command, links_from(results_md, shown))
        written.append(write_marked_file(results_md, sections,
                                         appendable=[APPENDIX_MARKERS]))
    return written


def _ran_appendix(results: ExperimentResults) -> bool:
    return any(EXPERIMENTS[name].section == "appendix" for name in results.results)


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


# ============================================================================ JSON


def results_json(results: ExperimentResults, command: str) -> JsonDict:
    """The content of ``results.json``: the command, every result (:func:`result_json`, in
    run order) and ``meta`` (experiments, settings, wall time, counts); strict JSON."""
    data: JsonDict = {"command": command}
    for result in results.results.values():
        data.update(result_json(result))
    data["meta"] = {
        "experiments": list(results.results),
        "settings": settings_json(results.settings),
        "seconds": results.seconds,
        "simulations": results.simulations,
        "jobs": results.jobs,
        "readings_simulated": int(results.readings_simulated),
    }
    return dict(json_ready(data))


def result_json(result: Any) -> JsonDict:
    """One typed result (a dataclass) as ``results.json`` keys: each field a key, all of them
    under the class's ``JSON_KEY`` when it has one; not yet strict JSON (see
    :func:`~sonarcarve.lab.output.json_ready`)."""
    entries = {f.name: getattr(result, f.name) for f in fields(result)}
    key = getattr(result, "JSON_KEY", None)
    return {key: entries} if key else entries


def settings_json(s: Settings) -> JsonDict:
    """The settings as they appear in ``results.json``: every field, the sweeps as a dict, and
    the method configuration in degrees and metres."""
    out = asdict(s)
    out["sweeps"] = {k: list(v) for k, v in s.sweeps}
    config = s.method_config()
    out["method_config"] = {"history_size": config.history_size,
                            "beam_width_deg": math.degrees(config.beam_width),
                            "range_tolerance_m": config.range_tolerance,
                            "min_transversal_deg": math.degrees(config.min_transversal),
                            "range_resolution_m": config.range_resolution}
    return out


# ============================================================================ Markdown


def render_sections(results: ExperimentResults, command: str,
                    figures: Sequence[str] = ()) -> list[tuple[Markers, str]]:
    """The generated sections (markers included) for ``results``: the experiments section
    always, the appendix section when an appendix experiment ran.

    ``figures`` are the PNGs' paths relative to the Markdown file. Each section is its header
    and the parts (:class:`~sonarcarve.lab.experiments.base.Part`) of the experiments that
    belong to it, in their order.
    """
    page = Page({Path(f).name: f for f in figures}, results.settings, results.results)
    parts: dict[str, list[Part]] = {"experiments": [], "appendix": []}
    for name, result in results.results.items():
        experiment = EXPERIMENTS[name]
        parts[experiment.section] += experiment.markdown(result, page)
    sections = [("experiments", EXPERIMENTS_MARKERS, _experiments_header(results, command))]
    if _ran_appendix(results):
        sections.append(("appendix", APPENDIX_MARKERS, _appendix_header(command)))
    return [(markers, "\n".join([*header, *_body(parts[section]), markers.end]))
            for section, markers, header in sections]


def _body(parts: list[Part]) -> list[str]:
    return [line for part in sorted(parts, key=lambda p: p.order) for line in part.lines]


def _experiments_header(results: ExperimentResults, command: str) -> list[str]:
    settings = settings_json(results.settings)
    config: Mapping[str, Any] = settings["method_config"]
    return [
        BEGIN_MARKER,
        "## Experiments: the paper's section 5 on the simulator",
        "",
        "<!-- Generated by sonarcarve.lab.report; edits here are overwritten. -->",
        "",
        f"Produced by `{command}` (`make experiments`). Wall time "
        f"{fmt_num(results.seconds / 60.0, 1)} min for {results.simulations} "
        f"simulations and {results.jobs} method runs in {settings['jobs']} worker "
        f"process(es), figures excluded; simulation seeds 0-{settings['seeds'] - 1}. "
        "Every number below is measured on the simulator (`sonarcarve.sim`): the `office` "
        "floor (90 m x 60 m, 5400 m²) driven along its built-in tour. Robot `scout2` (16 sonars, "
        f"φ = {fmt_num(config['beam_width_deg'], 1)}°, one-inch range quantum) at "
        f"{fmt_num(settings['speed'], 1)} m/s; history {config['history_size']} arcs, "
        f"ATM ψ = {fmt_num(config['min_transversal_deg'], 0)}°, carving ε = "
        f"{fmt_num(config['range_tolerance_m'], 3)} m (the library defaults). "
        "Ranges in brackets are min-max over seeds.",
        "",
    ]


def _appendix_header(command: str) -> list[str]:
    return [
        APPENDIX_BEGIN_MARKER,
        "## Appendix A and B, Fig. 7 and 14: sonar polling, filters, a real log, maps from "
        "odometry",
        "",
        "<!-- Generated by sonarcarve.lab.report; edits here are overwritten. -->",
        "",
        f"Command: `{command}`.",
        "",
    ]
