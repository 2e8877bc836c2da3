"""``sonarcarve.warm``: warm_up fills numba's cache so that a later process compiles nothing.

The decisive checks run in subprocesses with their own empty ``NUMBA_CACHE_DIR``: one process
warms, a second, fresh one runs a normal workload and counts numba's compile events (which fire
only for a real compile, never for a cache load). Nothing here asserts on time.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path
from types import ModuleType
from typing import ClassVar

import numpy as np
import pytest

from sonarcarve.methods import METHODS
from sonarcarve.warm import (
    CHECK_STEP,
    cgroup_cpus,
    counting_compiles,
    default_jobs,
    warm_lanes,
    warm_steps,
    warm_stream,
    warm_up,
)


def _run(code: str, cache: Path) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env,
                          capture_output=True, text=True, check=False, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def _compiled_names(stdout: str) -> list[str]:
    line = next(line for line in stdout.splitlines() if line.startswith("COMPILED"))
    return line.split()[1:]


def test_the_stream_passes_the_history_and_has_no_echo_readings() -> None:
    batch = warm_stream()
    assert len(batch) >= 250 + 300  # past the default history: arcs leave it many times
    no_echo = np.isinf(batch.range)
    assert no_echo.any()
    assert (~no_echo).sum() > 500
    assert np.all(batch.max_range[no_echo] > 0)
    # Every echo is the distance to a wall of the room: its far point lies on a wall.
    x = batch.x + batch.range * np.cos(batch.theta)
    y = batch.y + batch.range * np.sin(batch.theta)
    wall = np.maximum(np.abs(x), np.abs(y))[~no_echo]
    assert np.all(np.abs(wall - 2.5) < 0.1)


def test_there_is_a_step_for_every_method_the_grids_and_the_csv_kernels() -> None:
    names = [name for name, _ in warm_steps()]
    for method in METHODS:
        assert f"method {method}" in names
    assert any("max_incidence" in name for name in names)
    assert any("grids" in name for name in names)
    assert any("CSV" in name for name in names)


def test_every_step_is_in_one_lane_and_kernel_sharing_steps_share_a_lane() -> None:
    lanes = [[name for name, _ in lane] for lane in warm_lanes()]
    names = [name for lane in lanes for name in lane]
    assert names == [name for name, _ in warm_steps()]
    assert len(set(names)) == len(names)

    def lane_of(name: str) -> int:
        return next(k for k, lane in enumerate(lanes) if name in lane)

    # Combined and specular-aware carving call carving's kernels; the carved grid calls
    # evidence carving's (measured: apart, each would compile them again).
    assert lane_of("method carve") == lane_of("method combined") == lane_of(
        "method carve, max_incidence 60 deg")
    assert lane_of("method evidence") == lane_of("grid carved")
    assert lane_of("method carve") != lane_of("method evidence")


def test_a_parallel_warm_up_compiles_in_other_processes_and_leaves_nothing_to_compile(
        tmp_path: Path) -> None:
    """Two lanes in two processes, then a fresh process finds everything in the cache."""
    (tmp_path / "cheap_lanes.py").write_text(textwrap.dedent("""
        import os
        from sonarcarve.warm import warm_lanes

        KEEP = ("method centerline", "CSV reader, map writer and occlusion filter")

        def lanes():
            def noted(step):
                def run():
                    with open(os.environ["PIDS"], "a") as out:
                        out.write(f"{os.getpid()}\\n")
                    step()
                return run
            return [[(name, noted(step)) for name, step in lane if name in KEEP]
                    for lane in warm_lanes() if any(name in KEEP for name, _ in lane)]
        """))
    code = f"""
    import os, sys
    sys.path.insert(0, {str(tmp_path)!r})
    os.environ["PIDS"] = {str(tmp_path / "pids.txt")!r}
    import cheap_lanes
    from sonarcarve.warm import warm_up
    if __name__ == "__main__":
        done = warm_up(lanes=cheap_lanes.lanes, jobs=2)
        print("PARENT", os.getpid())
        for what, _, count in done:
            print("ROW", count, what)
    """
    out = _run(code, tmp_path / "cache")
    rows = [line.split(maxsplit=2)[1:] for line in out.splitlines() if line.startswith("ROW")]
    assert [what for _, what in rows] == ["CSV reader, map writer and occlusion filter",
                                          "method centerline", "every step again in one process"]
    assert int(rows[0][0]) > 0
    assert int(rows[1][0]) > 0
    assert rows[2][0] == "0"  # so the last pass here found it all in the cache
    parent = next(line for line in out.splitlines() if line.startswith("PARENT")).split()[1]
    pids = (tmp_path / "pids.txt").read_text().split()
    assert len(pids) == 4  # two steps in the workers, then both again here
    assert parent not in pids[:2]
    assert pids[2:] == [parent, parent]
    run = _NORMAL_RUN.replace("sys.argv[1:]", "['centerline']")
    assert _compiled_names(_run(run, tmp_path / "cache")) == []


def test_without_processes_the_lanes_run_here_and_are_reported_alike(
        monkeypatch: pytest.MonkeyPatch) -> None:
    class NoProcesses:
        def __init__(self, *args: object, **kwargs: object) -> None:
            raise OSError(38, "Function not implemented")  # sem_open in some sandboxes

    monkeypatch.setattr("sonarcarve.warm.ProcessPoolExecutor", NoProcesses)
    calls: list[str] = []
    lanes = [[("a", lambda: calls.append("a")), ("b", lambda: calls.append("b"))],
             [("c", lambda: calls.append("c"))]]
    seen: list[str] = []
    done = warm_up(lambda what, _: seen.append(what), lanes=lambda: lanes, jobs=2)
    # Each lane here, then every step again in the last pass.
    assert calls == ["a", "b", "c", "a", "b", "c"]
    assert [what for what, _, _ in done] == seen == ["a", "b", "c", CHECK_STEP]


class _FakePool:
    """A process pool stand-in: lane 0's future holds ``error``, the others a result row."""

    made: ClassVar[list[_FakePool]] = []
    error: ClassVar[BaseException] = RuntimeError("a step failed")

    def __init__(self, *args: object, **kwargs: object) -> None:
        self.shutdowns: list[tuple[bool, bool]] = []
        _FakePool.made.append(self)

    def submit(self, run: object, lanes: object, k: int) -> Future[list[tuple[str, float, int]]]:
        future: Future[list[tuple[str, float, int]]] = Future()
        if k == 0:
            future.set_exception(_FakePool.error)
        else:
            future.set_result([(f"lane {k}", 0.0, 1)])
        return future

    def shutdown(self, wait: bool = True, cancel_futures: bool = False) -> None:
        self.shutdowns.append((wait, cancel_futures))


def test_a_failing_lane_stops_the_warm_up_without_waiting_for_the_others(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("sonarcarve.warm.ProcessPoolExecutor", _FakePool)
    monkeypatch.setattr(_FakePool, "made", [])
    calls: list[str] = []
    lanes = [[("a", lambda: calls.append("a"))], [("b", lambda: calls.append("b"))]]
    with pytest.raises(RuntimeError, match="a step failed"):
        warm_up(lanes=lambda: lanes, jobs=2)
    assert _FakePool.made[0].shutdowns == [(False, True)]  # queued lanes cancelled
    assert calls == []
    # A worker that died (BrokenProcessPool) is not an error: its lane runs here.
    monkeypatch.setattr(_FakePool, "error", BrokenProcessPool("killed"))
    done = warm_up(lanes=lambda: lanes, jobs=2)
    names = [what for what, _, _ in done]
    # Lane 1 is reported by the pool or, when the broken lane came out of as_completed first,
    # run here too; either way once, in lane order, then the last pass.
    assert names[0] == "a"
    assert names[1] in ("lane 1", "b")
    assert names[2:] == [CHECK_STEP]
    assert calls[:-2] in (["a"], ["a", "b"])
    assert calls[-2:] == ["a", "b"]
    with pytest.raises(ValueError, match="lanes"):
        warm_up(steps=lanes[0], jobs=2)


def test_warm_up_runs_every_step_and_reports_it(monkeypatch: pytest.MonkeyPatch) -> None:
    # The real steps compile for minutes; here each step is a stand-in that records
    # its call, so the reporting is checked, not the compiling (the subprocess tests do that).
    calls: list[str] = []
    steps = [(f"step {k}", lambda k=k: calls.append(f"step {k}")) for k in range(3)]
    monkeypatch.setattr("sonarcarve.warm.warm_steps", lambda: steps)
    seen: list[tuple[str, float]] = []
    done = warm_up(on_progress=lambda what, seconds: seen.append((what, seconds)))
    assert calls == ["step 0", "step 1", "step 2"]
    assert [what for what, _, _ in done] == calls == [what for what, _ in seen]
    assert all(seconds >= 0 and count == 0 for _, seconds, count in done)


def test_counting_compiles_counts_a_fresh_function_once() -> None:
    from numba import njit

    @njit(cache=False)
    def twice(v: float) -> float:
        return 2.0 * v

    with counting_compiles() as names:
        twice(1.0)
        twice(2.0)  # the same signature: no second compile
    assert names.count("test_counting_compiles_counts_a_fresh_function_once.<locals>.twice") == 1
    with counting_compiles() as names:
        twice(3)  # an int: a new signature
    assert len(names) == 1


# What a normal run does in a fresh process: every method's first add() and a process-like
# block, the readings CSV read and the map CSV written, as the CLI would.
_NORMAL_RUN = """
import math, sys, tempfile
from pathlib import Path
from sonarcarve.warm import counting_compiles, warm_stream
from sonarcarve import MethodConfig, Reading, make_method
from sonarcarve.io import read_readings_csv, write_map_csv, write_readings_csv
methods = sys.argv[1:]
with counting_compiles() as names:
    for name in methods:
        m = make_method(name, MethodConfig(history_size=250))
        m.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0))
        m.add(Reading(0.01, 1, 0.0, 0.1, 0.3, 1.5))
        m.local_map()
        m.finish()
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "log.csv"
        write_readings_csv(warm_stream(300), log)
        batch = read_readings_csv(log)
        m = make_method("centerline")
        m.add_many(batch)
        write_map_csv(m.finish(), Path(folder) / "map.csv")
print("COMPILED", *names)
"""


def test_a_cold_cache_compiles_so_the_check_below_can_fail(tmp_path: Path) -> None:
    """Without warming, the same normal run compiles the kernels (the oracle of the test)."""
    names = _compiled_names(_run(_NORMAL_RUN.replace("sys.argv[1:]", "['centerline']"),
                                 tmp_path))
    assert len(names) >= 5, names


@pytest.mark.slow
def test_after_warm_up_a_fresh_process_compiles_nothing(tmp_path: Path) -> None:
    """Every step warmed (minutes of compiling), then every method's first add()."""
    # In two processes, as `sonarcarve warm` runs on a 2-core machine.
    out = _run("import sonarcarve.warm as w\nif __name__ == '__main__':\n"
               "    w.warm_up(jobs=2)\n    print('WARM')\n", tmp_path)
    assert "WARM" in out
    run = _NORMAL_RUN.replace("sys.argv[1:]", repr(sorted(METHODS)))
    assert _compiled_names(_run(run, tmp_path)) == []
    # Specular-aware carving and the grids, as `sonarcarve grid` runs them.
    grids = """
    import math
    import pathlib
    import tempfile
    from sonarcarve.io.bag_out import write_map_bag
    from sonarcarve.warm import counting_compiles, warm_stream
    from sonarcarve import MethodConfig, make_method
    from sonarcarve.filters import MapFilter, filter_map, point_origins
    from sonarcarve.grids import CarvedGrid, OccupancyGrid, RangeSensorLayer
    batch = warm_stream(400)
    box = (-3.0, -3.0, 3.0, 3.0)
    with counting_compiles() as names:
        m = make_method('carve', MethodConfig(max_incidence=math.radians(30)))
        m.add_many(batch)
        points = m.finish()
        for grid in (CarvedGrid.around(box, 0.05), RangeSensorLayer(0.05, box),
                     OccupancyGrid.around(box, 0.05)):
            grid.add_many(batch)
            grid.probabilities()
        filter_map(points, MapFilter(occlusion_depth=0.5), point_origins(points, batch))
        # Bag output's arc markers, both formats (process --out X.bag | X.mcap).
        with tempfile.TemporaryDirectory() as folder:
            for name in ('arcs.bag', 'arcs.mcap'):
                write_map_bag(pathlib.Path(folder) / name, batch, make_method('centerline'))
    print('COMPILED', *names)
    """
    assert _compiled_names(_run(grids, tmp_path)) == []


def test_no_echo_reading_of_the_stream_is_valid_input() -> None:
    batch = warm_stream(40)
    k = int(np.flatnonzero(np.isinf(batch.range))[0])
    assert math.isinf(batch.range[k])
    assert batch.max_range[k] == pytest.approx(6.0)


def test_warm_up_runs_the_steps_it_is_given() -> None:
    calls: list[int] = []
    done = warm_up(steps=[("only", lambda: calls.append(1))])
    assert calls == [1]
    assert [what for what, _, _ in done] == ["only"]


def test_compile_time_benchmark_splits_the_compile_seconds_without_counting_twice(
    tmp_path: Path, benchmark_script: Callable[[str], ModuleType]
) -> None:
    """``benchmarks/compile_time.py``: each kernel's own seconds exclude its callees' (ATM's
    kernel compiles the spatial index's), so they add up to at most the steps' wall time
    (counting a callee in its caller too would not)."""
    script = benchmark_script("compile_time")
    child = script.start("WORKTREE", tmp_path, ["method centerline", "method atm"])
    result = script.finish("WORKTREE", child)
    assert [name for name, _ in result["steps"]] == ["method centerline", "method atm"]
    own = result["own"]
    assert "methods.atm._add_arcs" in own
    assert any(kernel.startswith("geometry.index.") for kernel in own), own
    assert all(value >= 0.0 for value in own.values())
    assert sum(own.values()) <= sum(seconds for _, seconds in result["steps"])


def _cgroups(tmp_path: Path, proc: str, files: dict[str, str]) -> tuple[Path, Path]:
    """A control-group tree under ``tmp_path`` with ``files`` (relative path: text) and a
    ``/proc/self/cgroup`` of text ``proc``."""
    root = tmp_path / "cgroup"
    for name, text in files.items():
        (root / name).parent.mkdir(parents=True, exist_ok=True)
        (root / name).write_text(text)
    proc_file = tmp_path / "proc-self-cgroup"
    proc_file.write_text(proc)
    return root, proc_file


@pytest.mark.parametrize(("proc", "files", "cores"), [
    # cgroup v2, a container's own namespace: "docker run --cpus 2" writes 200000 100000
    ("0::/\n", {"cpu.max": "200000 100000\n"}, 2),
    ("0::/\n", {"cpu.max": "150000 100000\n"}, 2),  # 1.5 CPUs: two processes, rounded up
    ("0::/\n", {"cpu.max": "max 100000\n"}, math.inf),  # no quota
    # v2 on the host: the process's own group, which is tighter than the root's
    ("0::/user.slice/ci.scope\n", {"cpu.max": "400000 100000",
                                   "user.slice/ci.scope/cpu.max": "100000 100000"}, 1),
    # a quota on a parent group (a systemd slice's CPUQuota=) bounds the groups below it
    ("0::/a/b\n", {"a/cpu.max": "100000 100000", "a/b/cpu.max": "max 100000"}, 1),
    ("1:cpu:/a/b\n", {"cpu/a/cpu.cfs_quota_us": "200000", "cpu/a/cpu.cfs_period_us": "100000"},
     2),
    # cgroup v1 (this machine's kind): cfs quota over period; -1 is no quota
    ("4:memory:/x\n1:cpu,cpuacct:/docker/abc\n0::/\n",
     {"cpu/docker/abc/cpu.cfs_quota_us": "300000", "cpu/docker/abc/cpu.cfs_period_us": "100000"},
     3),
    ("1:cpu:/\n0::/\n", {"cpu/cpu.cfs_quota_us": "-1", "cpu/cpu.cfs_period_us": "100000"},
     math.inf),
    ("", {}, math.inf),  # no control groups at all (not Linux, or not mounted)
    ("0::/\n", {"cpu.max": "garbage"}, math.inf),
])
def test_cgroup_cpus_reads_the_quota(tmp_path: Path, proc: str, files: dict[str, str],
                                     cores: float) -> None:
    root, proc_file = _cgroups(tmp_path, proc, files)
    assert cgroup_cpus(root, proc_file) == cores


def test_default_jobs_is_the_cores_capped_by_the_quota(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: set(range(64)), raising=False)
    root, proc_file = _cgroups(tmp_path, "0::/\n", {"cpu.max": "200000 100000"})
    assert default_jobs(root, proc_file) == 2  # 64 cores visible, 2 CPUs' time allowed
    root, proc_file = _cgroups(tmp_path / "none", "0::/\n", {"cpu.max": "max 100000"})
    assert default_jobs(root, proc_file) == 64
