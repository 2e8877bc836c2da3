"""One runner for every parallel job: pure tasks on this process or on a Dask cluster, same
results.

The experiments (:func:`~sonarcarve.lab.experiments.run_experiments`), parameter sweeps
(:mod:`sonarcarve.lab.sweep`) and fleets of logs (:mod:`sonarcarve.fleet`) hand their work
to a :class:`Runner` as a list of :class:`Task` values: a module-level function and its
arguments, where an argument may be a :class:`Ref` to an earlier task's result (a simulation
shared by every method run on it). Every task is a pure function of its inputs, so the results
are the same whatever runs them, however many workers there are and in whatever order they
finish; callers key each result by its task, never by arrival order.

Two back ends, picked by :func:`open_runner` from a :class:`RunnerSpec`:

* :class:`SerialRunner`: in this process, in the given order (one worker and no scheduler);
  needs no Dask.
* :class:`DaskRunner`: a ``dask.distributed`` client, either to a ``LocalCluster`` of
  ``workers`` processes on this machine (started and closed by the runner) or to an existing
  scheduler by address (``tcp://HOST:PORT``: ``dask scheduler`` on one machine and
  ``dask worker tcp://HOST:PORT`` on the others, or any Dask deployment). A simulation is
  submitted once and its future passed to the tasks that need it; Dask recomputes a result lost
  with a worker, so a worker that dies loses and duplicates nothing.

Dask is imported here only when a :class:`DaskRunner` starts (``pip install
'sonarcarve[lab]'``); the product (``sonarcarve process LOGS... --out-dir``) runs on it without
the lab.
"""

from __future__ import annotations

import importlib
import logging
import math
import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from types import TracebackType
from typing import Any, NamedTuple, Protocol

from sonarcarve.errors import SonarcarveError
from sonarcarve.extras import require

__all__ = [
    "DEFAULT_CONNECT_TIMEOUT",
    "DaskRunner",
    "ProgressCallback",
    "Ref",
    "Runner",
    "RunnerError",
    "RunnerSpec",
    "SchedulerUnreachableError",
    "SerialRunner",
    "Task",
    "TaskFailure",
    "open_runner",
]

#: Seconds to wait for a scheduler to answer (and, on a cluster, for a first worker).
DEFAULT_CONNECT_TIMEOUT = 10.0

#: Dask's settings of the environment of a worker process, made before it starts.
_PRE_SPAWN = "distributed.nanny.pre-spawn-environ"

#: ``on_progress(stage, done, total)``, one stage per kind of task (``"simulating"`` ...).
ProgressCallback = Callable[[str, int, int], None]


class RunnerError(SonarcarveError):
    """The runner cannot start: a bad worker count, a malformed scheduler address."""


class SchedulerUnreachableError(RunnerError):
    """A Dask scheduler address that does not answer, or a cluster with no workers."""


class Ref(NamedTuple):
    """A task argument standing for the result of the earlier task at position ``task``."""

    task: int


@dataclass(frozen=True)
class Task:
    """One pure function call.

    Attributes
    ----------
    func : callable
        A module-level function (it is pickled by name to the workers).
    args : tuple
        Its positional arguments; a :class:`Ref` is replaced by that earlier task's result.
    stage : str
        What the progress bar calls this kind of task (``"simulating"``, ``"mapping"``).
    gather : bool
        Whether :meth:`Runner.run` yields the result; False for intermediate results that
        only feed other tasks (a simulation), which then never leave the workers.
    """

    func: Callable[..., Any]
    args: tuple[Any, ...] = ()
    stage: str = "running"
    gather: bool = True


class TaskFailure(NamedTuple):
    """What a task that raised (or whose worker kept dying) yields when failures are
    captured: the error on one line."""

    message: str


class Runner(Protocol):
    """Runs :class:`Task` lists; :class:`SerialRunner` and :class:`DaskRunner` implement it."""

    @property
    def workers(self) -> int:
        """Worker processes (1 for the serial runner)."""
        ...

    def run(self, tasks: Sequence[Task], *, on_progress: ProgressCallback | None = None,
            capture_errors: bool = False) -> Iterator[tuple[int, Any]]:
        """Run ``tasks`` (each after the tasks it refers to) and yield ``(index, result)`` for
        every task with ``gather``, in completion order.

        A task that raises stops the run with its exception, or, with ``capture_errors``,
        yields a :class:`TaskFailure` instead. Stopping the iteration early cancels the rest.
        """
        ...

    def close(self) -> None:
        """Release the workers (a local cluster stops; a remote one is left running)."""
        ...


@dataclass(frozen=True)
class RunnerSpec:
    """Where tasks run.

    Attributes
    ----------
    workers : int
        Worker processes of a local cluster; 1 (and no ``scheduler``) runs everything in this
        process without Dask.
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://HOST:PORT``); ``workers`` is then ignored.
    connect_timeout : float
        Seconds to wait for the scheduler to answer and for at least one worker.
    """

    workers: int = 1
    scheduler: str | None = None
    connect_timeout: float = DEFAULT_CONNECT_TIMEOUT

    def __post_init__(self) -> None:
        if self.workers < 1:
            msg = f"workers must be at least 1, got {self.workers}"
            raise RunnerError(msg)
        if self.scheduler is not None and not self.scheduler.strip():
            msg = "scheduler needs an address such as tcp://HOST:8786"
            raise RunnerError(msg)
        if not (math.isfinite(self.connect_timeout) and self.connect_timeout > 0):
            msg = f"connect_timeout must be > 0 seconds, got {self.connect_timeout}"
            raise RunnerError(msg)

    @classmethod
    def from_env(cls, workers: int | None = None, scheduler: str | None = None,
                 connect_timeout: float = DEFAULT_CONNECT_TIMEOUT) -> RunnerSpec:
        """The spec the commands use: ``scheduler``, else ``$DASK_SCHEDULER_ADDRESS``, else a
        local cluster of ``workers`` (default: every CPU of this machine)."""
        address = scheduler or os.environ.get("DASK_SCHEDULER_ADDRESS") or None
        count = workers if workers is not None else max(1, os.cpu_count() or 1)
        return cls(count, address, connect_timeout)

    @property
    def serial(self) -> bool:
        """True when tasks run in this process (one worker, no scheduler)."""
        return self.scheduler is None and self.workers == 1

    def describe(self) -> str:
        """One line for the command's output: where the tasks run."""
        if self.scheduler is not None:
            return f"Dask scheduler {self.scheduler}"
        if self.serial:
            return "this process"
        return f"local Dask cluster of {self.workers} workers"


def open_runner(spec: RunnerSpec) -> SerialRunner | DaskRunner:
    """The runner for ``spec``, ready to run (use it as a context manager to close it).

    Raises
    ------
    SchedulerUnreachableError
        ``spec.scheduler`` does not answer within ``spec.connect_timeout``, or has no worker.
    RunnerError
        A malformed address.
    MissingExtraError
        A cluster is asked for and Dask is not installed.
    """
    if spec.serial:
        return SerialRunner()
    return DaskRunner(spec)


class _Counter:
    """Per-stage progress: totals first, then one step per finished task."""

    def __init__(self, tasks: Sequence[Task], on_progress: ProgressCallback | None) -> None:
        self.report = on_progress or (lambda stage, done, total: None)
        self.totals: dict[str, int] = {}
        for task in tasks:
            self.totals[task.stage] = self.totals.get(task.stage, 0) + 1
        self.done = dict.fromkeys(self.totals, 0)
        for stage, total in self.totals.items():
            self.report(stage, 0, total)

    def step(self, stage: str) -> None:
        self.done[stage] += 1
        self.report(stage, self.done[stage], self.totals[stage])


def _check_refs(tasks: Sequence[Task]) -> list[list[int]]:
    """Each task's dependents; a Ref must point to an earlier task."""
    dependents: list[list[int]] = [[] for _ in tasks]
    for i, task in enumerate(tasks):
        for arg in task.args:
            if isinstance(arg, Ref):
                if not 0 <= arg.task < i:
                    msg = f"task {i} refers to task {arg.task}, which does not come before it"
                    raise ValueError(msg)  # a bug in the caller, not a user error
                dependents[arg.task].append(i)
    return dependents


def _one_line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


class _Closing:
    """Context-manager support shared by the runners."""

    def close(self) -> None:  # pragma: no cover - overridden
        ...

    def __enter__(self) -> Any:
        return self

    def __exit__(self, kind: type[BaseException] | None, err: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


@dataclass
class SerialRunner(_Closing):
    """Runs tasks one after the other in this process; a result is dropped as soon as the
    last task that refers to it has run."""

    @property
    def workers(self) -> int:
        return 1

    def run(self, tasks: Sequence[Task], *, on_progress: ProgressCallback | None = None,
            capture_errors: bool = False) -> Iterator[tuple[int, Any]]:
        """See :meth:`Runner.run`."""
        dependents = _check_refs(tasks)
        waiting = [len(d) for d in dependents]
        counter = _Counter(tasks, on_progress)
        kept: dict[int, Any] = {}
        for i, task in enumerate(tasks):
            refs = [a.task for a in task.args if isinstance(a, Ref)]
            failed = next((kept[r] for r in refs if isinstance(kept[r], TaskFailure)), None)
            if failed is not None:
                value: Any = failed
            else:
                args = [kept[a.task] if isinstance(a, Ref) else a for a in task.args]
                try:
                    value = task.func(*args)
                except Exception as err:
                    if not capture_errors:
                        raise
                    value = TaskFailure(_one_line(err))
            for r in refs:
                waiting[r] -= 1
                if waiting[r] == 0:
                    del kept[r]
            if waiting[i]:
                kept[i] = value
            counter.step(task.stage)
            if task.gather:
                yield i, value

    def close(self) -> None:
        """Nothing to release."""


@dataclass
class DaskRunner(_Closing):
    """Runs tasks on a ``dask.distributed`` client: a local cluster or a scheduler's."""

    spec: RunnerSpec
    _client: Any = field(init=False, repr=False)
    _cluster: Any = field(init=False, repr=False, default=None)

    def __post_init__(self) -> None:
        # Imported as modules (untyped attributes): Dask's API is only partly annotated.
        distributed = require("distributed", "lab", "Dask runs")
        Client, LocalCluster = distributed.Client, distributed.LocalCluster
        spec = self.spec
        if spec.scheduler is None:
            # One thread per worker: the methods hold the GIL; processes give the parallelism.
            # Dask's default MALLOC_TRIM_THRESHOLD_ (64 kB) makes glibc hand memory back after
            # every large free; the simulator allocates and frees large arrays all the time
            # and ran 2-4 times slower with it, so the local workers keep glibc's default.
            # Without a dashboard the scheduler still serves HTTP (health checks), on 8787 by
            # default, and warns when another cluster holds that port: any free port instead.
            config = importlib.import_module("dask").config
            with config.set({f"{_PRE_SPAWN}.MALLOC_TRIM_THRESHOLD_": None}):
                self._cluster = LocalCluster(
                    n_workers=spec.workers, threads_per_worker=1, processes=True,
                    host="127.0.0.1", dashboard_address=None, silence_logs=logging.CRITICAL,
                    scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
            self._client = Client(self._cluster, set_as_default=False)
            return
        try:
            self._client = Client(spec.scheduler, timeout=spec.connect_timeout,
                                  set_as_default=False)
        except (OSError, TimeoutError) as err:
            msg = (f"cannot reach Dask at {spec.scheduler} within {spec.connect_timeout:g} s "
                   f"({_one_line(err)}); start it with `dask scheduler`, or give no scheduler "
                   "to run on this machine")
            raise SchedulerUnreachableError(msg) from None
        except (ValueError, TypeError) as err:
            msg = f"scheduler {spec.scheduler}: not a Dask address ({_one_line(err)})"
            raise RunnerError(msg) from None
        try:
            self._client.wait_for_workers(1, timeout=spec.connect_timeout)
        except (OSError, TimeoutError):
            self._client.close()
            msg = (f"Dask at {spec.scheduler} has no worker processes after "
                   f"{spec.connect_timeout:g} s; start some with `dask worker {spec.scheduler}`")
            raise SchedulerUnreachableError(msg) from None

    @property
    def client(self) -> Any:
        """The ``distributed.Client`` (for tests and callers that need Dask itself)."""
        return self._client

    @property
    def workers(self) -> int:
        """Workers connected now."""
        return max(1, len(self._client.scheduler_info().get("workers", {})))

    def run(self, tasks: Sequence[Task], *, on_progress: ProgressCallback | None = None,
            capture_errors: bool = False) -> Iterator[tuple[int, Any]]:
        """See :meth:`Runner.run`. A simulation's data stays on the workers; only the results
        of ``gather`` tasks travel back."""
        tokenize = importlib.import_module("dask.base").tokenize
        as_completed = importlib.import_module("distributed").as_completed
        _check_refs(tasks)
        counter = _Counter(tasks, on_progress)
        keys: list[str] = []
        futures: dict[int, Any] = {}
        index_of: dict[str, int] = {}
        for i, task in enumerate(tasks):
            args = tuple(futures[a.task] if isinstance(a, Ref) else a for a in task.args)
            # Content keys: the same call gets the same key, on any client of the scheduler.
            token_args = tuple(keys[a.task] if isinstance(a, Ref) else a for a in task.args)
            key = f"{task.stage}-{task.func.__name__}-{tokenize(task.func, token_args)}"
            if key in index_of:  # the same pure call twice: a second key would be a copy
                key = f"{key}-{i}"
            keys.append(key)
            index_of[key] = i
            futures[i] = self._client.submit(task.func, *args, key=key, pure=False,
                                             retries=0)
        pending = as_completed(list(futures.values()), loop=self._client.loop)
        del futures  # dependencies stay on the workers only while a dependent still needs them
        try:
            for future in pending:
                i = index_of[future.key]
                task = tasks[i]
                counter.step(task.stage)
                if future.status == "error":
                    err = future.exception()
                    if not capture_errors:
                        raise err
                    value: Any = TaskFailure(_one_line(err))
                elif future.status == "cancelled":
                    if not capture_errors:
                        msg = f"task {future.key} was cancelled"
                        raise RunnerError(msg)
                    value = TaskFailure("cancelled")
                else:
                    if not task.gather:
                        future.release()
                        continue
                    value = future.result()
                future.release()
                if task.gather:
                    yield i, value
        finally:
            pending.clear()

    def close(self) -> None:
        """Close the client, and the local cluster if this runner started it."""
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()
