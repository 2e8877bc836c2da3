"""``sonarcarve warm``: compile every kernel once, into numba's on-disk cache."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Annotated

import typer
from rich.table import Table

from sonarcarve.cli.app import app, console, progress
from sonarcarve.warm import Lane, Step, cache_location, default_jobs, warm_lanes, warm_up

__all__ = ["warm"]


def _demo_metrics() -> None:
    """The lab's one kernel, which `sonarcarve demo` runs to score maps against the walls."""
    import numpy as np

    from sonarcarve.lab.metrics import segment_distance

    segment_distance(np.array([[0.5, 0.5], [1.0, 2.0]]), np.array([[0.0, 0.0, 2.0, 0.0]]))


def command_lanes() -> list[Lane]:
    """The product's lanes and the demo's kernel: what this command warms (module level, so
    that each process of a parallel warm-up can build them)."""
    return [*warm_lanes(), [("demo's truth metrics", _demo_metrics)]]


@app.command()
def warm(
    quiet: Annotated[bool, typer.Option(
        "--quiet", "-q", help="No progress bar and no table: one line when done.")] = False,
    jobs: Annotated[int, typer.Option(
        "--jobs", "-j", min=0, max=64,
        help="Processes compiling at once; 0: one per core this process may use (no more "
             "than a container's CPU quota allows). Numba compiles on one core, so 2 jobs take "
             "about half the time of 1.")] = 0,
) -> None:
    """Compile every method's kernels now, so that their first run needs no compiling.

    sonarcarve's methods, grids and CSV reader and writer run as machine code that numba
    compiles on first use and keeps on disk. Without this, the first run of each method in a
    fresh installation stops for several seconds (carving: about 9 s) while it
    compiles. `sonarcarve warm` runs every method, grid and CSV path once on a small built-in
    stream, so every later run loads the compiled code instead. `make demo` and `make test`
    run it right after installing.

    Run it again after upgrading sonarcarve, numba or Python, or after moving the cache: the
    cache is kept per version and source, and a run with nothing to compile takes a second or
    two. The cache is where numba keeps it: the folder named by `NUMBA_CACHE_DIR` if set,
    otherwise the `__pycache__` folders beside sonarcarve's modules. On an empty cache it
    takes a minute and a half on a 2-core machine with `--jobs 2` (the default there: one
    process per core), about three minutes with `--jobs 1` (docs/RESULTS.md, "cold start").

    Example: `sonarcarve warm` (once after `pip install sonarcarve[all]`)

    Example: `NUMBA_CACHE_DIR=~/.cache/sonarcarve sonarcarve warm --quiet`
    """
    tic = time.perf_counter()
    jobs = jobs or default_jobs()
    steps = [step for lane in command_lanes() for step in lane]
    if quiet:
        done = _warm(steps, jobs)
    else:
        with progress(elapsed=True) as bar:
            task = bar.add_task("compiling", total=len(steps) + (jobs > 1))

            def advance(what: str, seconds: float) -> None:
                bar.update(task, advance=1, description=f"done: {what}")

            done = _warm(steps, jobs, advance)
    total = time.perf_counter() - tic
    compiled = sum(count for _, _, count in done)
    if quiet:
        console.print(f"sonarcarve warm: {compiled} functions compiled in {total:.1f} s; "
                      f"cache: {cache_location()}")
        return
    table = Table(title="sonarcarve warm")
    table.add_column("what", style="bold")
    table.add_column("functions compiled", justify="right")
    table.add_column("seconds", justify="right")
    for what, seconds, count in done:
        table.add_row(what, f"{count:,}", f"{seconds:.1f}")
    processes = min(jobs, len(command_lanes()))  # never more processes than lanes
    label = "total" if jobs == 1 else f"total, {processes} processes at once (wall time)"
    table.add_row(label, f"{compiled:,}", f"{total:.1f}", style="bold")
    console.print(table)
    console.print(f"Compiled code cached in {cache_location()}.")
    if compiled == 0:
        console.print("Nothing needed compiling: the cache was already warm.")


def _warm(steps: list[Step], jobs: int,
          advance: Callable[[str, float], None] | None = None) -> list[tuple[str, float, int]]:
    """One process runs ``steps``; more run :func:`command_lanes` side by side."""
    if jobs == 1:
        return warm_up(advance, steps=steps)
    return warm_up(advance, lanes=command_lanes, jobs=jobs)
