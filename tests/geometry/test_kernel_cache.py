"""Compiled kernels never run stale machine code from numba's on-disk cache.

numba keys a cached kernel on its own file only; ``methods/carving.py``'s kernel inlines the
geometry kernels, so an edit to ``geometry/`` must invalidate it too
(:mod:`sonarcarve.geometry._compiled` keys every cache on all kernel sources). The test runs a
small carving script twice in fresh processes sharing one cache folder, with a copy of the
package whose carving kernel is changed between the runs, and checks that the second run sees
the change.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import sonarcarve

# An arc at 1 m, then a reading from the same place that heard nothing up to 2 m: its freespace
# covers the arc entirely (paper, eq. 3.2), so carving removes the arc (1 arc fully carved).
SCRIPT = """
from sonarcarve.methods import CarvingMethod
from sonarcarve.readings import Reading
method = CarvingMethod(range_tolerance=0.0)
method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0))
method.add(Reading(1.0, 0, 0.0, 0.0, 0.0, 2.0))
print(method.measures().fully_carved)
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
    assert _run(root, cache) == "1"
    assert any(cache.rglob("*.nbi")), "the kernels were cached"
    # The carving kernel of the copy now never carves: the bounding-circle shortcut and the
    # exact path both say "unchanged". Nothing in methods/ changes.
    bounds = root / "sonarcarve" / "geometry" / "bounds.py"
    text = bounds.read_text()
    assert "    return FULLY_CARVED if inside else UNDECIDED\n" in text
    bounds.write_text(text.replace("    return FULLY_CARVED if inside else UNDECIDED\n",
                                   "    return UNCHANGED\n"))
    assert _run(root, cache) == "0"


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
