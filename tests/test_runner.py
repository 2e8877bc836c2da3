"""The runner: serial and Dask back ends give the same results; a dead scheduler is one line."""

from __future__ import annotations

import faulthandler
import operator
import socket
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from sonarcarve.cli import main
from sonarcarve.errors import SonarcarveError
from sonarcarve.runner import (
    DaskRunner,
    Ref,
    RunnerError,
    RunnerSpec,
    SchedulerUnreachableError,
    SerialRunner,
    Task,
    TaskFailure,
    open_runner,
)

#: Seconds any one cluster test may take before the process is stopped with a traceback.
TIME_LIMIT = 120


@pytest.fixture
def time_limit() -> Iterator[None]:
    faulthandler.dump_traceback_later(TIME_LIMIT, exit=True, file=sys.__stderr__)
    yield
    faulthandler.cancel_dump_traceback_later()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _tasks() -> list[Task]:
    return [Task(operator.add, (1, 2), "first", gather=False),
            Task(operator.mul, (Ref(0), 10), "second"),
            Task(operator.sub, (Ref(0), 1), "second"),
            Task(operator.truediv, (1, 0), "second")]


def test_serial_runner_passes_results_and_reports_progress() -> None:
    seen: list[tuple[str, int, int]] = []
    out = dict(SerialRunner().run(_tasks(), on_progress=lambda *a: seen.append(a),
                                  capture_errors=True))
    assert out[1] == 30
    assert out[2] == 2
    assert isinstance(out[3], TaskFailure)
    assert "ZeroDivisionError" in out[3].message
    assert 0 not in out  # not gathered
    assert seen[:2] == [("first", 0, 1), ("second", 0, 3)]
    assert seen[-1] == ("second", 3, 3)


def test_serial_runner_raises_without_capture() -> None:
    with pytest.raises(ZeroDivisionError):
        list(SerialRunner().run(_tasks()))


def test_a_ref_must_point_backwards() -> None:
    with pytest.raises(ValueError, match="does not come before"):
        list(SerialRunner().run([Task(abs, (Ref(0),))]))


def test_specs_are_checked() -> None:
    with pytest.raises(RunnerError, match="workers must be at least 1"):
        RunnerSpec(workers=0)
    assert RunnerSpec().serial
    assert isinstance(open_runner(RunnerSpec()), SerialRunner)
    assert RunnerSpec.from_env(3, "tcp://h:8786").describe() == "Dask scheduler tcp://h:8786"


def test_local_cluster_gives_the_serial_results(time_limit: None) -> None:
    with DaskRunner(RunnerSpec(workers=2)) as runner:
        assert runner.workers == 2
        out = dict(runner.run(_tasks(), capture_errors=True))
    assert out[1] == 30
    assert out[2] == 2
    assert isinstance(out[3], TaskFailure)


def test_an_unreachable_scheduler_is_a_one_line_error(time_limit: None) -> None:
    address = f"tcp://127.0.0.1:{_free_port()}"
    with pytest.raises(SchedulerUnreachableError, match="cannot reach") as caught:
        open_runner(RunnerSpec(scheduler=address, connect_timeout=1.0))
    assert isinstance(caught.value, SonarcarveError)
    assert len(str(caught.value).splitlines()) == 1


def test_the_cli_exits_2_on_an_unreachable_scheduler(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], time_limit: None
) -> None:
    address = f"tcp://127.0.0.1:{_free_port()}"
    code = main(["experiments", "--quick", "--only", "t-junction", "--scheduler", address,
                 "--connect-timeout", "1", "--out", str(tmp_path / "out")])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert address in err
    assert err.endswith("or give no --scheduler to run on this machine")  # the option
    assert not (tmp_path / "out" / "results.json").exists()


@pytest.mark.parametrize(("spec", "message"), [
    ({"workers": 0}, "workers must be at least 1, got 0"),
    ({"scheduler": "  "}, "scheduler needs an address such as tcp://HOST:8786"),
    ({"connect_timeout": 0.0}, "connect_timeout must be > 0 seconds, got 0.0"),
])
def test_a_bad_spec_names_the_parameter_not_a_flag(spec: dict[str, object],
                                                   message: str) -> None:
    """RunnerSpec is library: its errors name its fields; the commands reword them as their
    options (review finding 3; tests/cli/test_fleet_cli.py pins '--workers must be ...')."""
    with pytest.raises(RunnerError) as caught:
        RunnerSpec(**spec)  # type: ignore[arg-type]
    assert str(caught.value) == message


def _divide(a: float, b: float) -> float:
    return a / b


def _seen(value: object) -> object:
    _SEEN.append(value)
    return value


_SEEN: list[object] = []


def test_a_task_after_a_failed_one_fails_with_its_error_without_running() -> None:
    _SEEN.clear()
    tasks = [Task(_divide, (1.0, 0.0), gather=False), Task(_seen, (Ref(0),)),
             Task(_divide, (1.0, 4.0))]
    results = dict(SerialRunner().run(tasks, capture_errors=True))
    assert results == {1: TaskFailure("ZeroDivisionError: float division by zero"), 2: 0.25}
    assert _SEEN == []  # the dependent task never ran on the failure


class _Result:
    """A result that can be watched with a weak reference."""


def _make() -> _Result:
    return _Result()


def _ignore(value: object) -> int:
    return 1


def test_the_serial_runner_drops_a_result_once_its_last_dependent_ran() -> None:
    import gc
    import weakref

    refs: list[weakref.ref[_Result]] = []

    def keep(value: _Result) -> int:
        refs.append(weakref.ref(value))
        return 1

    tasks = [Task(_make, gather=False), Task(keep, (Ref(0),)), Task(_ignore, (0,)),
             Task(_ignore, (0,))]
    run = SerialRunner().run(tasks)
    assert next(run) == (1, 1)
    assert next(run) == (2, 1)  # the task after the last dependent has run
    gc.collect()
    assert refs[0]() is None
    assert list(run) == [(3, 1)]


def test_the_scheduler_comes_from_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("DASK_SCHEDULER_ADDRESS", "tcp://10.0.0.7:8786")
    assert RunnerSpec.from_env(workers=2).scheduler == "tcp://10.0.0.7:8786"
    assert RunnerSpec.from_env(2, "tcp://host:1").scheduler == "tcp://host:1"  # the flag wins
    monkeypatch.delenv("DASK_SCHEDULER_ADDRESS")
    assert RunnerSpec.from_env(workers=2).scheduler is None


def test_only_one_local_worker_is_serial() -> None:
    assert RunnerSpec(1).serial
    assert not RunnerSpec(2).serial
    assert RunnerSpec(2).describe() == "local Dask cluster of 2 workers"
    assert not RunnerSpec(1, "tcp://host:8786").serial
