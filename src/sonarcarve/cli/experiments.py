"""``sonarcarve experiments``: regenerate the paper's results (and more) from the simulator."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)

from sonarcarve.cli.app import app, console
from sonarcarve.evaluation.experiments import (
    EXPERIMENTS,
    ExperimentError,
    Settings,
    run_experiments,
)
from sonarcarve.evaluation.report import write_outputs

__all__ = ["experiments"]

_NAMES = ", ".join(f"`{name}` ({exp.title})" for name, exp in EXPERIMENTS.items())


@app.command(help=(
    "Regenerate the paper's experiments (section 5) on the simulator, plus what the paper "
    "could not measure without ground truth.\n\n"
    f"Experiments: {_NAMES}.\n\n"
    "Writes one PNG per figure and `results.json` into --out; with --results-md it also "
    "rewrites the experiments section of that Markdown file (between "
    "`<!-- experiments:begin -->` and `<!-- experiments:end -->`).\n\n"
    "Example: `sonarcarve experiments --quick --out /tmp/exp` (seconds); the full run "
    "(`make experiments`) takes minutes."
))
def experiments(
    out: Annotated[Path, typer.Option("--out", "-o", help="Folder for results.json and figures.")],
    quick: Annotated[bool, typer.Option(
        "--quick", help="Small runs (short tours, few openings, short sweeps): seconds.")] = False,
    only: Annotated[list[str] | None, typer.Option(
        "--only", help=f"Run only this experiment (repeatable): {', '.join(EXPERIMENTS)}.")]
        = None,
    seeds: Annotated[int | None, typer.Option(
        help="Simulation seeds per scenario (default 3, or 1 with --quick).")] = None,
    jobs: Annotated[int | None, typer.Option(
        help="Worker processes (default: all CPUs; 1 with --quick).")] = None,
    figures: Annotated[Path | None, typer.Option(
        help="Also copy the PNGs into this folder (e.g. docs/figures).")] = None,
    results_md: Annotated[Path | None, typer.Option(
        "--results-md", help="Markdown file whose experiments section to regenerate.")] = None,
) -> None:
    """Run the experiments and write their results and figures."""
    names = [n.strip() for item in (only or []) for n in item.split(",") if n.strip()]
    if names and results_md is not None:
        # A partial run would replace the whole generated section with a partial one.
        msg = "--results-md rewrites the whole results section: run it without --only"
        raise ExperimentError(msg)
    workers = jobs if jobs is not None else (1 if quick else max(1, os.cpu_count() or 1))
    settings = Settings.make(quick=quick, seeds=seeds, jobs=workers)
    command = _command(out, quick, names, seeds, jobs, figures, results_md)
    with _progress() as bar:
        tasks: dict[str, TaskID] = {}

        def on_progress(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
            bar.update(tasks[stage], completed=done, total=total)

        results = run_experiments(settings, names or None, on_progress)
    written = write_outputs(results, out, command=command, figures_dir=figures,
                            results_md=results_md)
    seconds = results.results["meta"]["seconds"]
    console.print(f"experiments done in {seconds:.0f} s: {len(written)} files in {out}")
    for key, label in (("table1", "Table I (unprocessed %)"), ("fully_carved", "fully carved"),
                       ("openings", "openings passable (%)")):
        if key in results.results:
            console.print(f"  {label}: {_short(results.results[key])}")


def _short(entry: dict[str, object]) -> str:
    parts = []
    for key, value in entry.items():
        if isinstance(value, float):
            parts.append(f"{key} {value:.1f}")
        elif isinstance(value, dict):
            parts.append(f"{key} " + "/".join(f"{v:.0f}" for v in value.values()
                                              if isinstance(v, float)))
    return ", ".join(parts[:6])


def _command(out: Path, quick: bool, names: list[str], seeds: int | None, jobs: int | None,
             figures: Path | None, results_md: Path | None) -> str:
    """The command line that reproduces this run."""
    parts = ["sonarcarve experiments"]
    if quick:
        parts.append("--quick")
    parts += [f"--only {n}" for n in names]
    if seeds is not None:
        parts.append(f"--seeds {seeds}")
    if jobs is not None:
        parts.append(f"--jobs {jobs}")
    parts.append(f"--out {out}")
    if figures is not None:
        parts.append(f"--figures {figures}")
    if results_md is not None:
        parts.append(f"--results-md {results_md}")
    return " ".join(parts)


def _progress() -> Progress:
    return Progress(TextColumn("{task.description:>10}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), console=console, transient=True)
