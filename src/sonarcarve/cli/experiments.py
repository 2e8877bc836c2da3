"""``sonarcarve experiments``: regenerate the paper's results (and more) from the simulator."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.progress import TaskID

from sonarcarve.cli.app import app, console, progress, reworded
from sonarcarve.cli.drawing import draw_offscreen
from sonarcarve.cli.options import RUNNER_FLAGS
from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import check_output_dir, check_output_file
from sonarcarve.io.errors import InputError
from sonarcarve.lab.experiments import (
    EXPERIMENTS,
    ExperimentError,
    Settings,
    run_experiments,
)
from sonarcarve.lab.report import (
    BEGIN_MARKER,
    END_MARKER,
    replace_section,
    result_json,
    write_outputs,
)
from sonarcarve.runner import DEFAULT_CONNECT_TIMEOUT, RunnerError, RunnerSpec, open_runner

__all__ = ["experiments"]

_NAMES = ", ".join(f"`{name}` ({exp.title})" for name, exp in EXPERIMENTS.items())


@app.command(help=(
    "Regenerate the paper's experiments (section 5) on the simulator, plus what the paper "
    "could not measure without ground truth.\n\n"
    f"Experiments: {_NAMES}.\n\n"
    "Writes one PNG per figure and `results.json` into --out; with --results-md it also "
    "rewrites the experiments section of that Markdown file (between "
    f"`{BEGIN_MARKER}` and `{END_MARKER}`, which the file must hold; a file that does not "
    "exist yet is created). Every output path is checked before the run starts.\n\n"
    "Example: `sonarcarve experiments --quick --out /tmp/exp` (seconds); the full run "
    "(`make experiments`) takes minutes."
))
def experiments(
    out: Annotated[str, typer.Option(
        "--out", "-o", metavar="FOLDER",
        help="Folder for results.json and figures (created with its missing parents).")],
    quick: Annotated[bool, typer.Option(
        "--quick", help="Small runs (short tours, few openings, short sweeps): seconds.")] = False,
    only: Annotated[list[str] | None, typer.Option(
        "--only", metavar="NAME",
        help=f"Run only this experiment (repeatable): {', '.join(EXPERIMENTS)}.")] = None,
    seeds: Annotated[int | None, typer.Option(
        metavar="N", help="Simulation seeds per scenario (default 3, or 1 with --quick).")] = None,
    workers: Annotated[int | None, typer.Option(
        "--workers", "-w", metavar="N",
        help="Dask worker processes of a local cluster on this machine (default: all CPUs; 1 "
             "with --quick); 1 runs everything in this process, without Dask.")] = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", metavar="ADDRESS", envvar="DASK_SCHEDULER_ADDRESS",
        help="Run on an existing Dask cluster instead: its scheduler's address, e.g. "
             "tcp://HOST:8786 (`dask scheduler` there, `dask worker tcp://HOST:8786` on each "
             "machine; default $DASK_SCHEDULER_ADDRESS). The numbers do not change.")] = None,
    connect_timeout: Annotated[float, typer.Option(
        "--connect-timeout", metavar="SECONDS",
        help="How long to wait for --scheduler to answer.")] = DEFAULT_CONNECT_TIMEOUT,
    figures: Annotated[str | None, typer.Option(
        metavar="FOLDER", help="Also copy the PNGs into this folder (e.g. docs/figures).")] = None,
    results_md: Annotated[Path | None, typer.Option(
        "--results-md", metavar="FILE.md",
        help="Markdown file whose experiments section to regenerate (it must hold the markers "
             "below, or not exist yet).")] = None,
) -> None:
    """Run the experiments and write their results and figures."""
    names = [n.strip() for item in (only or []) for n in item.split(",") if n.strip()]
    if names and results_md is not None:
        # A partial run would replace the whole generated section with a partial one.
        msg = "--results-md rewrites the whole results section: run it without --only"
        raise ExperimentError(msg)
    with reworded(RunnerError, RUNNER_FLAGS):
        spec = RunnerSpec.from_env(1 if quick and workers is None else workers, scheduler,
                                   connect_timeout)
    Settings.make(quick=quick, seeds=seeds)  # refuse bad settings before starting workers
    # A run takes minutes: refuse an output it could not write before, not after.
    # Folders arrive as str, so that an empty --out is refused instead of meaning ".".
    folder = check_output_dir(out, label=f"--out {out}")
    figures_dir = None if figures is None else check_output_dir(figures,
                                                                 label=f"--figures {figures}")
    if results_md is not None:
        _check_results_md(results_md)
    command = _command(folder, quick, names, seeds, workers, scheduler, figures_dir,
                       results_md)
    draw_offscreen()
    with reworded(RunnerError, RUNNER_FLAGS):
        runner = open_runner(spec)
    with runner, progress(label_width=10, elapsed=True) as bar:
        settings = Settings.make(quick=quick, seeds=seeds, jobs=runner.workers)
        tasks: dict[str, TaskID] = {}

        def on_progress(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
            bar.update(tasks[stage], completed=done, total=total)

        results = run_experiments(settings, names or None, on_progress, runner)
    written = write_outputs(results, folder, command=command, figures_dir=figures_dir,
                            results_md=results_md)
    console.print(f"experiments done in {results.seconds:.0f} s on {spec.describe()}: "
                  f"{len(written)} files in {out}")
    keys = {k: v for result in results.results.values() for k, v in result_json(result).items()}
    for key, label in (("table1", "Table I (unprocessed %)"), ("fully_carved", "fully carved"),
                       ("openings", "openings passable (%)")):
        if key in keys:
            console.print(f"  {label}: {_short(keys[key])}")


def _short(entry: dict[str, object]) -> str:
    parts = []
    for key, value in entry.items():
        if isinstance(value, float):
            parts.append(f"{key} {value:.1f}")
        elif isinstance(value, dict):
            parts.append(f"{key} " + "/".join(f"{v:.0f}" for v in value.values()
                                              if isinstance(v, float)))
    return ", ".join(parts[:6])


def _command(out: Path, quick: bool, names: list[str], seeds: int | None, workers: int | None,
             scheduler: str | None, figures: Path | None, results_md: Path | None) -> str:
    """The command line that reproduces this run."""
    parts = ["sonarcarve experiments"]
    if quick:
        parts.append("--quick")
    parts += [f"--only {n}" for n in names]
    if seeds is not None:
        parts.append(f"--seeds {seeds}")
    if workers is not None:
        parts.append(f"--workers {workers}")
    if scheduler is not None:
        parts.append(f"--scheduler {scheduler}")
    parts.append(f"--out {out}")
    if figures is not None:
        parts.append(f"--figures {figures}")
    if results_md is not None:
        parts.append(f"--results-md {results_md}")
    return " ".join(parts)



class ResultsMarkdownError(SonarcarveError):
    """A ``--results-md`` file without the markers that say where the section goes."""


def _check_results_md(path: Path) -> None:
    """Refuse a --results-md the run could not update as asked.

    A new file is created; an existing one must hold exactly one pair of experiments markers,
    because without them the report would append the section (and the appendix) to a file the
    user may have named by mistake.
    """
    label = f"--results-md {path}"
    if not path.exists():
        check_output_file(path, label=label)
        return
    check_output_file(path, label=label)  # a directory, or a folder that refuses new files
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        msg = f"{label}: cannot read ({err})"
        raise InputError(msg) from None
    if BEGIN_MARKER not in text and END_MARKER not in text:
        msg = (f"{label}: has no {BEGIN_MARKER} / {END_MARKER} markers; add them where the "
               "experiments section belongs, or name a new file")
        raise ResultsMarkdownError(msg)
    replace_section(text, f"{BEGIN_MARKER}\n{END_MARKER}", label)  # raises on broken markers
