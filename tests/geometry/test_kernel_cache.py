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
