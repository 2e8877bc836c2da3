"""``sonarcarve sweep``: a grid of parameters × worlds × seeds × methods, one tidy table."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import TaskID

from sonarcarve.cli.app import app, console, progress, reworded, summary_table
from sonarcarve.cli.options import RUNNER_FLAGS
from sonarcarve.lab.sweep import (
    PARAMETERS,
    SweepError,
    SweepSpec,
    canonical_parameter,
    load_sweep_spec,
    parse_values,
    run_sweep,
)
from sonarcarve.runner import DEFAULT_CONNECT_TIMEOUT, RunnerError, RunnerSpec, open_runner

__all__ = ["sweep"]


@app.command(help=(
    "Sweep method and simulation parameters over worlds and seeds: one tidy table "
    "(runs.csv, one row per run, every parameter and measure) and a figure of each measure "
    "against each parameter.\n\n"
    f"Parameters: {', '.join(PARAMETERS)} (aliases epsilon, psi, beta, phi, noise), or any "
    "MethodConfig field by name. Resumable: rerunning into the same --out skips the runs "
    "already finished there (runs.jsonl).\n\n"
    "Example: `sonarcarve sweep --param history=100,250,500 --param psi=20,30 --seed 0 "
    "--seed 1 --out sweep-out`"
))
def sweep(
    spec_file: Annotated[Path | None, typer.Argument(
        metavar="[SWEEP.yaml]",
        help="Sweep file: grid (parameter: values), worlds, seeds, methods, length, "
             "sample_every; command-line options add to or replace it.",
        show_default=False)] = None,
    out: Annotated[str, typer.Option(
        "--out", "-o", metavar="FOLDER",
        help="Folder for runs.jsonl, runs.csv, runs.parquet (with pyarrow) and sweep.png; "
             "finished runs found there are not run again.")] = "sweep-output",
    param: Annotated[list[str] | None, typer.Option(
        "--param", "-p", metavar="NAME=V1,V2",
        help="A swept parameter and its values (repeatable).")] = None,
    world: Annotated[list[str] | None, typer.Option(
        metavar="WORLD", help="Simulator world (repeatable; default office).")] = None,
    seed: Annotated[list[int] | None, typer.Option(
        metavar="N", help="Simulation seed (repeatable; default 0).")] = None,
    method: Annotated[list[str] | None, typer.Option(
        "--method", "-m", metavar="NAME",
        help="Method (repeatable; default every method).")] = None,
    length: Annotated[float | None, typer.Option(
        metavar="METRES", help="Metres of each world's tour to drive (default 12).")] = None,
    workers: Annotated[int | None, typer.Option(
        "--workers", "-w", metavar="N",
        help="Dask worker processes of a local cluster (default: all CPUs); 1 runs in this "
             "process, without Dask.")] = None,
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", metavar="ADDRESS", envvar="DASK_SCHEDULER_ADDRESS",
        help="Run on an existing Dask cluster: its scheduler's address, e.g. tcp://HOST:8786 "
             "(default $DASK_SCHEDULER_ADDRESS).")] = None,
    connect_timeout: Annotated[float, typer.Option(
        "--connect-timeout", metavar="SECONDS",
        help="How long to wait for --scheduler to answer.")] = DEFAULT_CONNECT_TIMEOUT,
) -> None:
    """Sweep parameters over worlds and seeds into one tidy table."""
    if length is not None and not (math.isfinite(length) and length > 0.0):
        msg = f"--length must be > 0 metres, got {length:g}"
        raise SweepError(msg)
    grid: dict[str, tuple[float, ...]] = {}
    for item in param or []:
        name, sep, values = item.partition("=")
        if not sep or not values.strip():
            msg = f"--param {item}: expected NAME=V1,V2,... such as history=100,250"
            raise SweepError(msg)
        grid[canonical_parameter(name)] = parse_values(values)
    overrides: dict[str, Any] = {"worlds": tuple(world) if world else None,
                                 "seeds": tuple(seed) if seed else None,
                                 "methods": tuple(method) if method else None,
                                 "length": length}
    if spec_file is not None:
        spec = load_sweep_spec(spec_file, **overrides)
        if grid:
            spec = SweepSpec(**{**_fields(spec), "grid": (*_without(spec, grid), *grid.items())})
    else:
        spec = SweepSpec(grid=tuple(grid.items()),
                         **{k: v for k, v in overrides.items() if v is not None})
    with reworded(RunnerError, RUNNER_FLAGS):
        runner_spec = RunnerSpec.from_env(workers, scheduler, connect_timeout)
        runner = open_runner(runner_spec)
    with runner, progress(label_width=10, elapsed=True) as bar:
        tasks: dict[str, TaskID] = {}

        def on_progress(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
            bar.update(tasks[stage], completed=done, total=total)

        result = run_sweep(spec, out, runner=runner, on_progress=on_progress)
    console.print(summary_table("sonarcarve sweep", [
        ("runs in the table", f"{len(result.rows):,}"),
        ("run now", f"{result.ran:,}"),
        ("already finished (skipped)", f"{result.skipped:,}"),
        ("simulations", f"{result.simulations:,}"),
        ("ran on", runner_spec.describe()),
        ("written", ", ".join(p.name for p in result.files)),
        ("folder", out),
    ]))


def _fields(spec: SweepSpec) -> dict[str, Any]:
    return {"worlds": spec.worlds, "seeds": spec.seeds, "methods": spec.methods,
            "length": spec.length, "sample_every": spec.sample_every}


def _without(spec: SweepSpec, names: dict[str, Any]) -> tuple[tuple[str, tuple[float, ...]], ...]:
    return tuple((name, values) for name, values in spec.grid if name not in names)
