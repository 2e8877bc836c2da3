"""Fill numba's on-disk cache once, so that a user's first ``add()`` loads machine code.

Every kernel of the product is compiled by numba on first use and cached on disk
(``cache=True``; :mod:`sonarcarve.geometry._compiled` keys the cache on the kernel sources).
Compiling is slow: carving's first ``add()`` compiles about 21 functions, about 9 s of CPU
(``benchmarks/speed.py --sections cold``; docs/RESULTS.md, "cold start"), and compiling less was
measured not to get near a second; ``benchmarks/compile_time.py`` says which kernels take it.
So the honest remedy is to compile once, right after installing: :func:`warm_up` runs every
method, grid and compiled I/O path on a small built-in stream, and every later process
(the same Python, numba and CPU, the same sources) loads the cached machine code instead.

Where the cache lives is numba's choice: ``NUMBA_CACHE_DIR`` if set, otherwise the
``__pycache__`` folders next to the kernel modules (or a user cache folder when those are not
writable). :func:`cache_location` says which.

A step list rather than one run: numba compiles one version per argument type, and the types
depend on the path (one reading or a block, an echo or none, a fresh or a re-used map), so
each path a normal run takes is taken here once. ``tests/test_warm.py`` checks, in a fresh
process with the warmed cache, that a normal run of every method compiles nothing.

Steps come in *lanes*: steps that share kernels (carving, its specular-aware variant and
combined, which calls carving; evidence carving and the carved grid) stay in one lane, and lanes
share little (15 small helpers are compiled in two lanes: 128 functions against 113), so
:func:`warm_up` with ``jobs > 1`` runs lanes in separate processes at once. Numba compiles on
one core, so two processes about halve the wall time on a 2-core machine (docs/RESULTS.md,
"The warm-up on two cores"). Saves to numba's cache take turns under a file lock
(:func:`sonarcarve.geometry._compiled._cache_lock`), and the parallel warm-up ends with every
step once more in this process: loads only, a second or two, and it compiles anything a worker
did not leave in the cache (the plain-``njit`` CSV and demo kernels save without that lock, each
in one lane only).
"""

from __future__ import annotations

import importlib.util
import math
import multiprocessing
import os
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import suppress
from pathlib import Path

import numpy as np

from sonarcarve.compiles import watching_compiles
from sonarcarve.filters import occlusion_mask, point_origins
from sonarcarve.grids import CarvedGrid, OccupancyGrid, RangeSensorLayer, trinary
from sonarcarve.io import read_readings_csv, write_map_csv, write_readings_csv
from sonarcarve.io.map_csv import map_csv_sink
from sonarcarve.io.readings_csv import iter_readings_csv
from sonarcarve.methods import METHODS, MethodConfig, make_method
from sonarcarve.pipeline import process_chunks
from sonarcarve.readings import Reading, ReadingBatch

__all__ = [
    "CHECK_STEP",
    "WARM_READINGS",
    "cache_location",
    "counting_compiles",
    "default_jobs",
    "warm_lanes",
    "warm_steps",
    "warm_stream",
    "warm_up",
]

#: Readings of the built-in stream: a default history (250) and 350 more, so that arcs leave
#: the history (eviction, commit to the global map) many times.
WARM_READINGS = 600

#: Half the side of the square room of the built-in stream, metres.
_ROOM = 2.5
#: Sensors around the robot, evenly spread (8, like the roboND ring).
_SENSORS = 8
#: The square room's extent, (xmin, ymin, xmax, ymax) in metres, for the grids.
_EXTENT = (-_ROOM, -_ROOM, _ROOM, _ROOM)
#: Every this many readings is a no-echo one (range inf, heard up to ``_MAX_RANGE``).
_NO_ECHO_EVERY = 37
_MAX_RANGE = 6.0
#: Single ``add()`` calls before the rest goes in blocks through ``add_many()``.
_SINGLE_ADDS = 40

#: What a step reports: its name; what ``on_progress`` receives after each step.
Progress = Callable[[str, float], None]
#: A step: its name and what it runs. A lane: steps that share kernels, run in order.
Step = tuple[str, Callable[[], None]]
Lane = list[Step]
#: Name of the last, in-process pass of a parallel warm-up (see the module docstring).
CHECK_STEP = "every step again in one process"


def warm_stream(n: int = WARM_READINGS) -> ReadingBatch:
    """A robot circling in a square room with a ring of sonars: ``n`` readings, deterministic.

    Ranges are the distance to the room's walls along each sensor's axis plus a little noise
    (seeded), and every ``_NO_ECHO_EVERY``-th reading hears nothing up to ``_MAX_RANGE``.
    """
    i = np.arange(n)
    heading = 2.0 * math.pi * i / 400.0
    x, y = 1.2 * np.cos(heading), 1.2 * np.sin(heading)
    sensor = i % _SENSORS
    theta = heading + math.pi / 2.0 + 2.0 * math.pi * sensor / _SENSORS
    c, s = np.cos(theta), np.sin(theta)
    with np.errstate(divide="ignore"):  # an axis parallel to a wall never meets it
        to_x = np.where(c > 0, (_ROOM - x) / c, np.where(c < 0, (-_ROOM - x) / c, np.inf))
        to_y = np.where(s > 0, (_ROOM - y) / s, np.where(s < 0, (-_ROOM - y) / s, np.inf))
    rng = np.random.default_rng(0)
    r = np.minimum(to_x, to_y) + rng.normal(0.0, 0.01, n)
    max_range = np.full(n, np.nan)
    no_echo = i % _NO_ECHO_EVERY == _NO_ECHO_EVERY - 1
    r[no_echo], max_range[no_echo] = np.inf, _MAX_RANGE
    return ReadingBatch.from_arrays(t=0.05 * i, sensor=sensor, x=x, y=y, theta=theta, range=r,
                                    beam_width=np.full(n, math.radians(22.5)),
                                    max_range=max_range, source="warm-up stream")


def _readings(batch: ReadingBatch, rows: range) -> Iterator[Reading]:
    for k in rows:
        yield Reading(float(batch.t[k]), int(batch.sensor[k]), float(batch.x[k]),
                      float(batch.y[k]), float(batch.theta[k]), float(batch.range[k]),
                      float(batch.beam_width[k]), float(batch.max_range[k]))


def _run_method(name: str, config: MethodConfig) -> None:
    """Every path of a method a run takes: single adds, blocks, no echo, maps, measures."""
    batch = warm_stream()
    method = make_method(name, config)
    for reading in _readings(batch, range(_SINGLE_ADDS)):
        method.add(reading)
        method.local_map()
    last = float(batch.t[_SINGLE_ADDS - 1])
    method.add(Reading(last + 0.01, 0, 0.0, 0.0, 0.0, math.inf, max_range=_MAX_RANGE))
    method.add_many(batch[_SINGLE_ADDS:])
    method.local_map()
    method.local_map()  # asked again with nothing new: the cached map
    method.global_map()
    method.measures()
    method.finish()
    # A second method of the same kind re-uses the compiled code; a process-like run feeds
    # it one whole block, as ``sonarcarve process`` does.
    again = make_method(name, config)
    again.add_many(batch)
    again.finish()


def _run_grids(*make: Callable[[], CarvedGrid | RangeSensorLayer | OccupancyGrid]) -> None:
    """Occupancy grids, each made fresh: one reading, a block, the grid read out."""
    batch = warm_stream()
    for grid in (new() for new in make):
        grid.add(next(_readings(batch, range(1))))
        grid.add_many(batch[1:])
        grid.probabilities()
        trinary(grid)
        grid.occupied_mask()
        if isinstance(grid, CarvedGrid):
            grid.trinary()


def _run_csv() -> None:
    """The readings CSV's compiled parser and the map CSV's compiled writer, in a temp folder.

    Both ways a map is written (whole, and streamed a block at a time as ``process`` does) and
    both ways a log is read (whole, and in chunks); and the occlusion map filter's kernels
    (``process --occlusion-depth``).
    """
    batch = warm_stream()
    with tempfile.TemporaryDirectory(prefix="sonarcarve-warm-") as folder:
        log = Path(folder) / "readings.csv"
        write_readings_csv(batch, log)
        read_readings_csv(log)
        method = make_method("centerline", MethodConfig())
        with map_csv_sink(Path(folder) / "streamed.csv") as sink:
            process_chunks(iter_readings_csv(log), method, sink=sink)
        write_map_csv(make_method("centerline").finish(), Path(folder) / "empty.csv")
        method = make_method("centerline")
        method.add_many(batch)
        points = method.finish()
        write_map_csv(points, Path(folder) / "map.csv")
        # Zero error bounds: every point may block (centerline's own here exceed half the
        # depth), so every kernel of the filter runs.
        occlusion_mask(points.xy, point_origins(points, batch), np.zeros(len(points)))


def _run_bag_output() -> None:
    """Bag output's compiled arc-marker kernels (:mod:`sonarcarve.io.marker_bytes`), for a ROS 1
    ``.bag`` and an ``.mcap``, in a temp folder; nothing without rosbags (the ``ros`` extra),
    which bag output needs anyway."""
    if importlib.util.find_spec("rosbags") is None:
        return
    from sonarcarve.io.bag_out import write_map_bag

    batch = warm_stream()
    with tempfile.TemporaryDirectory(prefix="sonarcarve-warm-") as folder:
        for name in ("arcs.bag", "arcs.mcap"):
            write_map_bag(Path(folder) / name, batch, make_method("centerline"))


def warm_lanes() -> list[Lane]:
    """The steps of :func:`warm_up` in lanes, longest first (they are handed out in order)."""
    def method(name: str, config: MethodConfig | None = None) -> Callable[[], None]:
        return lambda: _run_method(name, config or MethodConfig())

    carving = [("method carve", method("carve")),
               # Specular-aware carving (beta < 90 deg) takes other branches of the same
               # kernels; the carved grid's default method uses it.
               ("method carve, max_incidence 60 deg",
                method("carve", MethodConfig(max_incidence=math.radians(60)))),
               ("method combined", method("combined"))]
    lanes: list[Lane] = [
        # The carved grid runs evidence carving's kernels: alone it compiles about 20 more.
        [("method evidence", method("evidence")),
         ("grid carved", lambda: _run_grids(lambda: CarvedGrid.around(_EXTENT, 0.1)))],
        carving,
        [("grids range sensor layer and occupancy",
          lambda: _run_grids(lambda: RangeSensorLayer(0.1, _EXTENT),
                             lambda: OccupancyGrid.around(_EXTENT, 0.1)))],
        # Bag output maps with centerline, as the CSV steps do.
        [("CSV reader, map writer and occlusion filter", _run_csv),
         ("bag output's arc markers", _run_bag_output)],
    ]
    # Methods added later get a lane of their own (carve and combined are in carving's).
    lanes += [[(f"method {name}", method(name))] for name in METHODS
              if name not in ("carve", "combined", "evidence")]
    return lanes


def warm_steps() -> list[Step]:
    """Every step of :func:`warm_up`, lane after lane: a name and what it runs."""
    return [step for lane in warm_lanes() for step in lane]


#: Where Linux keeps its control groups (v2 at the top, v1 under ``cpu/``), and this process's
#: entry among them.
CGROUP_ROOT = Path("/sys/fs/cgroup")
PROC_CGROUP = Path("/proc/self/cgroup")


def default_jobs(cgroup_root: Path = CGROUP_ROOT, proc_cgroup: Path = PROC_CGROUP) -> int:
    """Processes for a parallel warm-up: one per core this process may use, and no more than
    the CPU time its control group may take (:func:`cgroup_cpus`).

    Why both: a container started with ``--cpus 2`` on a 64-core host sees all 64 cores in its
    affinity mask; 64 compiling processes would then share two cores' time (and hold 64 times
    the memory) for no gain.
    """
    if hasattr(os, "sched_getaffinity"):
        cores = len(os.sched_getaffinity(0))
    else:
        cores = os.cpu_count() or 1
    quota = cgroup_cpus(cgroup_root, proc_cgroup)
    return max(1, cores if math.isinf(quota) else min(cores, int(quota)))


def cgroup_cpus(cgroup_root: Path = CGROUP_ROOT, proc_cgroup: Path = PROC_CGROUP) -> float:
    """Cores' worth of CPU time this process's control group may use, rounded up: the quota
    over its period, in cgroup v2 (``cpu.max``, ``"200000 100000"``: 2) or v1
    (``cpu/cpu.cfs_quota_us`` over ``cpu.cfs_period_us``), of the group ``/proc/self/cgroup``
    names and of every group above it (inside a container's own namespace, the root); the
    smallest found. Infinite where none sets a quota (``max``, ``-1``) or nothing can be read."""
    v2_group = v1_group = ""
    for line in _text(proc_cgroup).splitlines():  # "number:controllers:/path"
        number, controllers, group = [*line.split(":", 2), "", ""][:3]
        if number == "0":
            v2_group = group.strip().lstrip("/")
        elif "cpu" in controllers.split(","):
            v1_group = group.strip().lstrip("/")
    limits = [math.inf]
    for folder in _with_ancestors(cgroup_root, v2_group):
        limits.append(_cores(_text(folder / "cpu.max")))
    for folder in _with_ancestors(cgroup_root / "cpu", v1_group):
        limits.append(_cores(f"{_text(folder / 'cpu.cfs_quota_us')} "
                             f"{_text(folder / 'cpu.cfs_period_us')}"))
    return min(limits)


def _with_ancestors(root: Path, group: str) -> list[Path]:
    """``root / group`` and every folder above it up to ``root``: a quota set on a parent
    group (a systemd slice's ``CPUQuota=``, docker's ``--cgroup-parent``) bounds its children."""
    parts = [part for part in group.split("/") if part]
    return [root.joinpath(*parts[:k]) for k in range(len(parts), -1, -1)]


def _text(path: Path) -> str:
    """The file's text, or nothing where it cannot be read."""
    try:
        return path.read_text()
    except OSError:
        return ""


def _cores(quota_and_period: str) -> float:
    """``"QUOTA PERIOD"`` as cores, rounded up; infinite for no quota or anything else."""
    with suppress(ValueError):  # "max" (no quota) and any other word that is no number
        quota, period = (int(word) for word in quota_and_period.split()[:2])
        if quota > 0 and period > 0:
            return float(math.ceil(quota / period))
    return math.inf


#: Collect the name of every function numba compiles (not loads from cache) meanwhile.
counting_compiles = watching_compiles


def warm_up(on_progress: Progress | None = None,
            steps: Sequence[Step] | None = None,
            *, lanes: Callable[[], list[Lane]] | None = None, jobs: int = 1,
            ) -> list[tuple[str, float, int]]:
    """Run every compiled path once so numba's cache holds it; return what each step took.

    Parameters
    ----------
    on_progress : callable, optional
        Called after each step with its name and its wall time in seconds.
    steps : list of (str, callable), optional
        What to run, in this process; by default :func:`warm_steps`.
    lanes : callable, optional
        For ``jobs > 1``: a module-level function returning the lanes (see :func:`warm_lanes`,
        the default; the command adds the demo's own kernel, which the product may not import).
        A function rather than the lanes themselves because each process builds its own.
    jobs : int
        Processes compiling at once; 1 runs ``steps`` here, one after another (``steps``
        with ``jobs > 1`` is a ``ValueError``: processes build their steps from ``lanes``).

    Returns
    -------
    list of (str, float, int)
        Per step: its name, its wall time in seconds and how many functions numba compiled in
        it (0 when the cache already held them all). A parallel warm-up adds a last row,
        :data:`CHECK_STEP`, for its in-process pass.
    """
    if jobs > 1:
        if steps is not None:
            raise ValueError("warm_up: steps run in this process; give lanes for jobs > 1")
        return _warm_up_in_processes(lanes or warm_lanes, jobs, on_progress)
    done: list[tuple[str, float, int]] = []
    for what, step in warm_steps() if steps is None else steps:
        with counting_compiles() as names:
            tic = time.perf_counter()
            step()
            seconds = time.perf_counter() - tic
        done.append((what, seconds, len(names)))
        if on_progress is not None:
            on_progress(what, seconds)
    return done


def _warm_lane(lanes: Callable[[], list[Lane]], index: int) -> list[tuple[str, float, int]]:
    """In a worker process: the steps of lane ``index``."""
    return warm_up(steps=lanes()[index])


def _warm_up_in_processes(lanes: Callable[[], list[Lane]], jobs: int,
                          on_progress: Progress | None) -> list[tuple[str, float, int]]:
    """Lanes in ``jobs`` fresh processes, longest first; then every step once more here."""
    count = len(lanes())
    # Spawned, not forked: a fork would copy this process's numba and LLVM state mid-flight.
    context = multiprocessing.get_context("spawn")
    by_lane: dict[int, list[tuple[str, float, int]]] = {}
    try:
        pool = ProcessPoolExecutor(max_workers=min(jobs, count), mp_context=context)
    except OSError:  # no processes to be had here (a sandbox without semaphores)
        pool = None
    if pool is not None:
        _run_lanes(pool, lanes, count, by_lane, on_progress)
    # The lanes left (none, unless processes failed) run here, one after another.
    for k in sorted(set(range(count)) - set(by_lane)):
        by_lane[k] = warm_up(on_progress, steps=lanes()[k])
    done = [row for k in range(count) for row in by_lane[k]]
    tic = time.perf_counter()
    with counting_compiles() as names:
        for _, step in (step for lane in lanes() for step in lane):
            step()
    done.append((CHECK_STEP, time.perf_counter() - tic, len(names)))
    if on_progress is not None:
        on_progress(CHECK_STEP, done[-1][1])
    return done


def _run_lanes(pool: ProcessPoolExecutor, lanes: Callable[[], list[Lane]], count: int,
               by_lane: dict[int, list[tuple[str, float, int]]],
               on_progress: Progress | None) -> None:
    """Every lane in ``pool``; each one's rows into ``by_lane`` as it ends."""
    try:
        futures = {pool.submit(_warm_lane, lanes, k): k for k in range(count)}
        for future in as_completed(futures):
            by_lane[futures[future]] = future.result()
            for what, seconds, _ in by_lane[futures[future]]:
                if on_progress is not None:
                    on_progress(what, seconds)
    except BrokenProcessPool:
        pass  # a worker died (out of memory): what the others did is cached
    except BaseException:
        # A step failed, or Ctrl-C: drop the lanes not started rather than compile them.
        pool.shutdown(wait=False, cancel_futures=True)
        raise
    pool.shutdown()


def cache_location() -> str:
    """Where numba keeps the compiled kernels: ``NUMBA_CACHE_DIR`` or the package's folders."""
    chosen = os.environ.get("NUMBA_CACHE_DIR")
    if chosen:
        return f"{chosen} (NUMBA_CACHE_DIR)"
    package = Path(__file__).resolve().parent
    return f"__pycache__ folders under {package} (set NUMBA_CACHE_DIR to choose another)"
