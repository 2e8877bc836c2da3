"""The paper's appendix and Fig. 7 measured: sonar polling, filters, a real 8-sensor log,
odometry maps.

Four experiments, each a function of :class:`AppendixSettings` returning JSON-ready results
and the arrays its figure needs, each in its own module with its figure (if any) and its
Markdown:

* ``polling`` (:func:`polling_experiment`, Appendix A, Fig. 14,
  :mod:`~sonarcarve.lab.appendix_polling`): the simulated office tour read by a host
  that only *polls* sensor values (no firing times); readings stamped the naive way (the pose
  at the poll where a value changed) and by sonar polling (:mod:`sonarcarve.polling`);
  centerline global maps of both, their error to the true walls, and the polling error bound
  checked against the true stamping error.
* ``filters`` (:func:`filters_experiment`, Appendix B,
  :mod:`~sonarcarve.lab.appendix_filters`): the reading filters (maximum range, jump)
  and map filters (outlier test, max-error thresholding) of :mod:`sonarcarve.filters`, alone
  and together, on the office tour for centerline, carving and combined: what they remove,
  judged by the simulator's truth, and the map's error to the true walls.
* ``real-log`` (:func:`real_log_experiment`, :mod:`~sonarcarve.lab.appendix_real_log`):
  every method on the bundled roboND-sonar-8 log (no ground truth), with a map sharpness
  measure that needs none (:func:`line_spread`), the share of readings each method removed,
  and the same after max-error thresholding.
* ``odometry`` (:func:`odometry_experiment`, Fig. 7,
  :mod:`~sonarcarve.lab.appendix_odometry`): the office tour mapped from dead-reckoned
  poses against true poses: error to the true walls against distance travelled, raw and with
  each point moved back by its reading's pose error (what the local map itself got wrong).

This module runs them: :func:`run_appendix` writes the figures (``appendix-*.png``) and
returns the results; :func:`appendix_markdown` renders the ``docs/RESULTS.md`` section between
:data:`BEGIN_MARKER` and :data:`END_MARKER`. ``sonarcarve experiments`` runs the same
experiments through its registry and keeps their numbers in its ``results.json``, the one
results file (this module writes no JSON of its own, so none can go stale beside it).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from sonarcarve.errors import SonarcarveError
from sonarcarve.lab.appendix_base import AppendixError, AppendixSettings
from sonarcarve.lab.appendix_filters import filters_experiment, filters_markdown
from sonarcarve.lab.appendix_odometry import odometry_experiment, odometry_markdown
from sonarcarve.lab.appendix_polling import (
    latest_firing,
    polling_experiment,
    polling_markdown,
)
from sonarcarve.lab.appendix_real_log import (
    LineSpread,
    ReferencePicture,
    line_spread,
    real_log_experiment,
    real_log_markdown,
    reference_picture,
)
from sonarcarve.lab.figures import APPENDIX_FIGURES, write_figures
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
    "APPENDIX_EXPERIMENTS",
    "APPENDIX_FIGURES",
    "APPENDIX_MARKERS",
    "BEGIN_MARKER",
    "END_MARKER",
    "AppendixError",
    "AppendixSettings",
    "LineSpread",
    "ReferencePicture",
    "appendix_markdown",
    "experiment_summariser",
    "filters_experiment",
    "latest_firing",
    "line_spread",
    "odometry_experiment",
    "polling_experiment",
    "real_log_experiment",
    "reference_picture",
    "replace_appendix_section",
    "run_appendix",
    "write_appendix_figures",
    "write_appendix_section",
]


BEGIN_MARKER = "<!-- appendix:begin -->"
END_MARKER = "<!-- appendix:end -->"
#: The appendix section's markers in a Markdown file, and the error a broken file raises.
APPENDIX_MARKERS = Markers(BEGIN_MARKER, END_MARKER, AppendixError)


# ============================================================================ running


#: Experiment name -> (title, function of settings -> (results, artifacts)).
APPENDIX_EXPERIMENTS: dict[str, tuple[str, Callable[[AppendixSettings],
                                                    tuple[JsonDict, JsonDict]]]] = {
    "polling": ("Appendix A, Fig. 14: sonar polling against naive stamps",
                polling_experiment),
    "filters": ("Appendix B: reading and map filters, judged by the truth",
                filters_experiment),
    "real-log": ("the real roboND 8-sensor log, every method, map sharpness",
                 real_log_experiment),
    "odometry": ("Fig. 7: global maps from dead-reckoned poses", odometry_experiment),
}


def experiment_summariser(name: str) -> Callable[[Any, Any], tuple[JsonDict, JsonDict]]:
    """An appendix experiment as a ``summarise(settings, outputs)`` of
    :mod:`sonarcarve.lab.experiments` (it plans no jobs; ``settings`` needs ``quick``
    and ``seeds``)."""
    run = APPENDIX_EXPERIMENTS[name][1]

    def summarise(settings: Any, outputs: Any) -> tuple[JsonDict, JsonDict]:
        return run(AppendixSettings.make(quick=bool(settings.quick), seeds=int(settings.seeds)))

    return summarise


def write_appendix_figures(results: JsonDict, artifacts: JsonDict, out: str | Path,
                           dpi: int = 110) -> list[Path]:
    """Save each appendix figure whose results are present as ``out/<name>``; return paths.

    ``artifacts`` is keyed by experiment name (``polling``, ``real-log``, ``odometry``). The
    appendix's share of :func:`~sonarcarve.lab.figures.write_figures`.
    """
    return write_figures(results, artifacts, out, dpi, names=APPENDIX_FIGURES)


def run_appendix(out_dir: str | Path, quick: bool = False, seeds: int | None = None,
                 only: Sequence[str] | None = None) -> JsonDict:
    """Run the appendix experiments and write their figures (no JSON: see the module notes).

    Parameters
    ----------
    out_dir : path
        Folder for the PNGs (``appendix-*.png``).
    quick : bool
        Small runs (one seed, 40 m of the tour, 10 Hz polling): seconds.
    seeds : int, optional
        Seeds for the simulated experiments (default 3, or 1 when quick).
    only : sequence of str, optional
        Names of :data:`APPENDIX_EXPERIMENTS` to run (default all).

    Returns
    -------
    dict
        JSON-ready results: ``appendix_polling``, ``appendix_filters``, ``appendix_real_log``,
        ``appendix_odometry`` (those run) and ``appendix_meta`` (settings, seconds, figure
        files).
    """
    names = list(only) if only else list(APPENDIX_EXPERIMENTS)
    for name in names:
        if name not in APPENDIX_EXPERIMENTS:
            msg = f"unknown appendix experiment {name!r}; choose from " \
                  f"{', '.join(APPENDIX_EXPERIMENTS)}"
            raise AppendixError(msg)
    settings = AppendixSettings.make(quick=quick, seeds=seeds)
    tic = time.perf_counter()
    results: JsonDict = {}
    artifacts: JsonDict = {}
    for name in names:
        res, art = APPENDIX_EXPERIMENTS[name][1](settings)
        results.update(res)
        artifacts[name] = art
    folder = Path(out_dir)
    figures = write_appendix_figures(results, artifacts, folder)
    results["appendix_meta"] = {"experiments": names, "settings": asdict(settings),
                                "seconds": time.perf_counter() - tic,
                                "figures": [p.name for p in figures]}
    return dict(json_ready(results))


# ============================================================================ RESULTS.md


def replace_appendix_section(text: str, section: str, where: str = "RESULTS.md", *,
                             append_missing: bool = False) -> str:
    """``text`` with the span from :data:`BEGIN_MARKER` to :data:`END_MARKER` (inclusive)
    replaced by ``section`` (see :func:`~sonarcarve.lab.output.replace_marked_section`).

    A blank ``text`` becomes the section; a ``text`` without the markers gets it appended only
    with ``append_missing``.

    Raises
    ------
    AppendixError
        When ``text`` has no markers (and not ``append_missing``), only one, or they are
        repeated or out of order; the message names ``where`` and the line.

    Examples
    --------
    >>> replace_appendix_section("a\\n", "<!-- appendix:begin -->\\nx\\n<!-- appendix:end -->",
    ...                          append_missing=True)
    'a\\n\\n<!-- appendix:begin -->\\nx\\n<!-- appendix:end -->\\n'
    """
    return replace_marked_section(text, section, BEGIN_MARKER, END_MARKER, where,
                                  append_missing=append_missing, error=AppendixError)


def write_appendix_section(results_md: str | Path, results: JsonDict, command: str,
                           figures: Sequence[str | Path] = ()) -> Path:
    """Regenerate the appendix section of ``results_md`` (other text untouched).

    ``figures`` are the PNG paths; links are made relative to the Markdown file. A missing (or
    blank) file is created.

    Raises
    ------
    AppendixError
        When ``results_md`` exists but lacks the appendix markers, or they are broken.
    """
    rel = links_from(results_md, figures)
    return write_marked_file(results_md,
                             [(APPENDIX_MARKERS, appendix_markdown(results, command, rel))])


def appendix_markdown(results: JsonDict, command: str = "",
                      figures: Sequence[str] = ()) -> str:
    """The Markdown section (markers included) for the results of :func:`run_appendix`.

    ``figures`` are the PNGs' paths relative to the Markdown file (by file name otherwise
    ``figures/<name>``).
    """
    figs = {Path(f).name: f for f in figures}
    meta = results.get("appendix_meta", {})
    lines = [
        BEGIN_MARKER,
        "## Appendix A and B, Fig. 7 and 14: sonar polling, filters, a real log, maps from "
        "odometry",
        "",
        "<!-- Generated by sonarcarve.lab.appendix; edits here are overwritten. -->",
        "",
    ]
    if command:
        seconds = meta.get("seconds")
        took = f" ({seconds:.0f} s)" if isinstance(seconds, int | float) else ""
        lines += [f"Command: `{command}`{took}.", ""]
    for part in (polling_markdown, filters_markdown, real_log_markdown, odometry_markdown):
        lines += part(results, figs)
    lines.append(END_MARKER)
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m sonarcarve.lab.appendix``: run the appendix experiments alone, write
    the figures into ``--out`` and (with ``--results-md``) only the appendix section of that
    Markdown file. Their numbers go to ``results.json`` only through ``sonarcarve
    experiments``, which runs the same experiments (``--only polling`` and so on)."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m sonarcarve.lab.appendix",
                                     description=main.__doc__)
    parser.add_argument("--out", required=True, help="folder for appendix-*.png")
    parser.add_argument("--figures", help="also copy the PNGs into this folder (docs/figures)")
    parser.add_argument("--results-md", help="Markdown file whose appendix section to rewrite")
    parser.add_argument("--quick", action="store_true", help="small runs (seconds)")
    parser.add_argument("--seeds", type=int, help="simulation seeds (default 3, quick 1)")
    parser.add_argument("--only", action="append", help="experiment name (repeatable)")
    args = parser.parse_args(argv)
    try:
        if args.results_md:  # refuse a file without the markers before minutes of work
            check_marked_file(args.results_md, [APPENDIX_MARKERS])
        results = run_appendix(args.out, quick=args.quick, seeds=args.seeds, only=args.only)
        figures = [Path(args.out) / f for f in results["appendix_meta"]["figures"]]
        if args.figures:
            figures = [copy_into(f, args.figures) for f in figures]
        if args.results_md:
            parts = ["python -m sonarcarve.lab.appendix", f"--out {args.out}"]
            parts += ["--quick"] if args.quick else []
            parts += [f"--seeds {args.seeds}"] if args.seeds is not None else []
            parts += [f"--only {n}" for n in args.only or []]
            parts += [f"--figures {args.figures}"] if args.figures else []
            parts.append(f"--results-md {args.results_md}")
            write_appendix_section(args.results_md, results, " ".join(parts), figures)
    except SonarcarveError as err:
        print(f"error: {err}")
        return 2
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
