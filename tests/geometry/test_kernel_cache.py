"""Compiled kernels never run stale machine code from numba's on-disk cache.

numba keys a cached kernel on its own file only; ``methods/carving.py``'s kernel inlines the
geometry kernels, so an edit to ``geometry/`` must invalidate it too
(:mod:`sonarcarve.geometry._compiled` keys every cache on all kernel sources). The test runs a
small script twice in fresh processes sharing one cache folder, with a copy of the package whose
geometry is changed between the runs, and checks that the second run sees the change.

The script calls the carving module's smallest kernel that inlines geometry kernels,
``_clear_of_sector`` (the carving kernel's trigonometry-free "this freespace leaves the arc
unchanged" test, inlining :func:`~sonarcarve.geometry.bounds.arc_clear_of_disk`), rather than
``CarvingMethod``: the cache and its key are the same for every kernel (:func:`~sonarcarve.
geometry._compiled.compiled`), and compiling the whole carving kernel twice from a cold cache
cost about 40 s of the test suite (this one compiles in about 2 s).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import sonarcarve

# An arc at 1 m over bearings ±0.1 rad, and the freespace of a reading from the same place that
# heard nothing up to 2 m over ±0.2 rad: the arc lies in the freespace's disk, so it is not clear
# of it (carving would remove it, paper eq. 3.2).
SCRIPT = """
import math
import numpy as np
from sonarcarve.geometry.sector import Sector
from sonarcarve.methods.arrays import CarvedArcs, HistoryRows
from sonarcarve.methods.carving import _clear_of_sector
sector = Sector(0.0, 0.0, 2.0, -0.2, math.cos(-0.2), math.sin(-0.2),
                0.2, math.cos(0.2), math.sin(0.2), 1.0)
zero = np.zeros(1)
history = HistoryRows(zero, zero, np.ones(1), zero, zero, zero, zero)
arcs = CarvedArcs(np.array([-0.1]), np.array([0.1]), np.zeros((1, 3)), np.full((1, 4), np.nan),
                  np.zeros(1, dtype=np.int8), np.zeros(1, dtype=bool))
print(_clear_of_sector(0, history, arcs, sector))
"""


def _run(package_root: Path, cache: Path) -> str:
    env = {**os.environ, "PYTHONPATH": str(package_root), "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                          text=True, timeout=300, check=True, cwd=package_root)
    return done.stdout.strip()


def test_editing_geometry_invalidates_the_dependent_carving_kernel(tmp_path: Path) -> None:
    root = tmp_path / "src"
    shutil.copytree(Path(sonarcarve.__file__).parent, root / "sonarcarve",
                    ignore=shutil.ignore_patterns("__pycache__"))
    cache = tmp_path / "numba-cache"
    assert _run(root, cache) == "False"
    assert any(cache.rglob("carving._clear_of_sector-*.nbi")), "the kernel was cached"
    # The disk test of the copy now calls every arc clear of every freespace (no reach left).
    # Nothing in methods/ changes.
    bounds = root / "sonarcarve" / "geometry" / "bounds.py"
    text = bounds.read_text()
    reach = "    reach = radius + 1e-6 * (1.0 + abs(ox) + abs(oy) + r + radius)\n"
    assert text.count(reach) == 1
    bounds.write_text(text.replace(reach, "    reach = 0.0\n"))
    assert _run(root, cache) == "True"


def test_this_numba_lets_borrowing_kernels_skip_reference_counts() -> None:
    # The option is private to numba: if a release drops it, the kernels still work (next
    # test) but lose half their speed, and this test says why.
    from sonarcarve.geometry._compiled import SKIPS_REFERENCE_COUNTS

    assert SKIPS_REFERENCE_COUNTS


def test_a_borrowing_kernel_gives_the_same_result_with_and_without_reference_counts(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import numpy as np

    from sonarcarve.geometry import _compiled

    def scaled_sum(values: np.ndarray, out: np.ndarray) -> float:
        total = 0.0
        for k in range(values.shape[0]):
            out[k] = 2.0 * values[k]
            total += out[k]
        return total

    values = np.arange(5.0)
    results = []
    for skips in (True, False):  # False: a numba without the private ``_nrt`` option
        monkeypatch.setattr(_compiled, "SKIPS_REFERENCE_COUNTS", skips)
        kernel = _compiled.compiled_borrowing(scaled_sum)
        out = np.zeros(5)
        results.append((kernel(values, out), out.tolist()))
    assert results == [(20.0, [0.0, 2.0, 4.0, 6.0, 8.0])] * 2


def test_saving_a_kernel_holds_the_cache_folders_lock(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Two processes saving overloads of one kernel at once take turns (the index race)."""
    import fcntl

    from numba.core.caching import FunctionCache

    from sonarcarve.geometry import _compiled
    from sonarcarve.geometry.bounds import arc_clear_of_disk

    lock_file = tmp_path / _compiled.CACHE_LOCK_NAME
    held: list[bool] = []

    def numbas_save(self: FunctionCache, sig: object, data: object) -> None:
        with lock_file.open("a") as other:  # another process's attempt, in effect
            try:
                fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                held.append(True)
            else:
                held.append(False)
                fcntl.flock(other, fcntl.LOCK_UN)

    monkeypatch.setattr(FunctionCache, "save_overload", numbas_save)
    cache = _compiled._SourcesKeyedCache(arc_clear_of_disk.py_func)
    cache._cache_path = str(tmp_path)
    cache.save_overload("signature", "machine code")
    assert held == [True]
    with lock_file.open("a") as other:  # released after the save
        fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)


def test_every_kernel_in_the_kernel_folders_is_keyed_on_all_kernel_sources() -> None:
    """A kernel decorated with plain ``numba.njit(cache=True)`` there would keep running its
    old machine code after an edit to a kernel it inlines (the module docstring's rule)."""
    import importlib
    import pkgutil

    from numba.core.registry import CPUDispatcher

    from sonarcarve.geometry._compiled import KERNEL_FOLDERS, _SourcesKeyedCache

    kernels = 0
    for folder in KERNEL_FOLDERS:
        package = importlib.import_module(f"sonarcarve.{folder}")
        for info in pkgutil.walk_packages(package.__path__, f"sonarcarve.{folder}."):
            module = importlib.import_module(info.name)
            for name, value in vars(module).items():
                if isinstance(value, CPUDispatcher) and value.__module__ == module.__name__:
                    kernels += 1
                    assert isinstance(value._cache, _SourcesKeyedCache), f"{info.name}.{name}"
    assert kernels > 50
