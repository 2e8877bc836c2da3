"""Sweeps: the same table on a Dask cluster as in this process, even when a worker dies;
resumed sweeps run only what is missing."""

from __future__ import annotations

import faulthandler
import json
import os
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from sonarcarve.lab.sweep import (
    SweepError,
    SweepSpec,
    canonical_parameter,
    load_sweep_spec,
    plan_runs,
    read_finished,
    run_sweep,
)
from sonarcarve.runner import DaskRunner, RunnerSpec

TIME_LIMIT = 180

#: Small: 2 seeds (2 simulations of 4 m) x 2 history sizes x 2 methods = 8 runs.
SPEC = SweepSpec(grid=(("history", (50, 100)),), seeds=(0, 1), methods=("carve", "atm"),
                 length=4.0)


@pytest.fixture
def time_limit() -> Iterator[None]:
    faulthandler.dump_traceback_later(TIME_LIMIT, exit=True, file=sys.__stderr__)
    yield
    faulthandler.cancel_dump_traceback_later()


def _identity(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The rows without wall time, the one column that depends on the machine."""
    return [{k: v for k, v in row.items() if k != "seconds"} for row in rows]


@pytest.fixture(scope="module")
def serial_rows(tmp_path_factory: pytest.TempPathFactory) -> list[dict[str, Any]]:
    result = run_sweep(SPEC, tmp_path_factory.mktemp("serial"), figure=False)
    assert result.ran == 8
    return _identity(result.rows)


def _lines(folder: Path) -> list[str]:
    return (folder / "runs.jsonl").read_text().splitlines()


def test_the_plan_is_the_product_of_the_grid() -> None:
    runs = plan_runs(SPEC)
    assert len(runs) == 8
    assert len({run.run_id for run in runs}) == 8
    assert [run.run_id for run in plan_runs(SPEC)] == [run.run_id for run in runs]
    assert canonical_parameter("epsilon") == "range_tolerance"
    with pytest.raises(SweepError, match="unknown sweep parameter"):
        canonical_parameter("nope")
    with pytest.raises(SweepError, match="unknown method"):
        SweepSpec(methods=("nope",))


def test_a_yaml_spec_reads_with_aliases(tmp_path: Path) -> None:
    path = tmp_path / "sweep.yaml"
    path.write_text("grid:\n  psi: [20, 30]\n  epsilon: '0.0,0.05'\nseeds: [0, 2]\n"
                    "methods: [atm]\nlength: 5\n")
    spec = load_sweep_spec(path, worlds=("office",))
    assert spec.grid == (("min_transversal_deg", (20, 30)), ("range_tolerance", (0.0, 0.05)))
    assert spec.seeds == (0, 2)
    assert spec.methods == ("atm",)
    assert spec.length == 5
    path.write_text("grid:\n  warp: [1]\n")
    with pytest.raises(SweepError, match="warp"):
        load_sweep_spec(path)
    # UX review, finding 11: the YAML library's "while parsing a flow node ... <unicode
    # string>" leaked; now the form of every other YAML reader.
    path.write_text("grid: [1,\n")
    with pytest.raises(SweepError) as err:
        load_sweep_spec(path)
    assert str(err.value).startswith(f"{path}: line 2, column 1: invalid YAML (")
    assert "unicode string" not in str(err.value)
    with pytest.raises(SweepError, match=r"absent\.yaml"):
        load_sweep_spec(tmp_path / "absent.yaml")


def test_the_serial_table_is_tidy(tmp_path: Path, serial_rows: list[dict[str, Any]]) -> None:
    result = run_sweep(SPEC, tmp_path)
    assert _identity(result.rows) == serial_rows
    header = (tmp_path / "runs.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["run_id", "world", "seed", "method", "history"]
    assert {"error_median", "unprocessed", "fully_carved", "seconds"} <= set(header)
    assert (tmp_path / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_a_resumed_sweep_runs_only_what_is_missing(
    tmp_path: Path, serial_rows: list[dict[str, Any]]
) -> None:
    part = SweepSpec(grid=(("history", (50,)),), seeds=(0, 1), methods=("carve", "atm"),
                     length=4.0)
    first = run_sweep(part, tmp_path, figure=False)
    assert (first.ran, first.skipped) == (4, 0)
    again = run_sweep(part, tmp_path, figure=False)
    assert (again.ran, again.skipped, again.simulations) == (0, 4, 0)
    # A run cut short by a crash (a torn last line) is not taken as finished.
    with (tmp_path / "runs.jsonl").open("a") as handle:
        handle.write('{"run_id": "torn')
    full = run_sweep(SPEC, tmp_path, figure=False)
    assert (full.ran, full.skipped) == (4, 4)
    assert _identity(full.rows) == serial_rows
    assert len(read_finished(tmp_path)) == 8


def test_a_cluster_sweep_equals_the_serial_one_even_when_a_worker_dies(
    tmp_path: Path, serial_rows: list[dict[str, Any]], time_limit: None
) -> None:
    with DaskRunner(RunnerSpec(workers=2)) as runner:
        client = runner.client
        pids = client.run(os.getpid)
        killed: list[int] = []

        def kill_one(stage: str, done: int, total: int) -> None:
            if stage == "mapping" and done == 1 and not killed:
                pid = sorted(pids.values())[0]
                os.kill(pid, signal.SIGKILL)
                killed.append(pid)

        result = run_sweep(SPEC, tmp_path, runner=runner, on_progress=kill_one, figure=False)
    assert killed
    assert _identity(result.rows) == serial_rows
    lines = _lines(tmp_path)
    assert len(lines) == 8  # nothing lost, nothing twice
    assert len({json.loads(line)["run_id"] for line in lines}) == 8
