"""Another commit's package, for the benchmarks that compare code with code in one run.

``ab_trees.py``, ``process_speed.py``, ``add_many_overhead.py`` and ``speed.py`` measure a
commit's ``src`` beside this checkout's: exported with ``git archive`` (no work tree, no
checkout of the repository changed), run in a child process with it first on ``PYTHONPATH``
and with its own numba cache, so no kernel compiled from one tree is loaded by the other.
"""

from __future__ import annotations

import io
import os
import subprocess
import tarfile
from pathlib import Path

#: The repository the commits are read from.
REPO = Path(__file__).resolve().parent.parent


def export_src(commit: str, into: Path) -> Path:
    """``commit``'s ``src`` folder, extracted under ``into`` (made if missing)."""
    into.mkdir(parents=True, exist_ok=True)
    archive = subprocess.run(["git", "-C", str(REPO), "archive", commit, "src"], check=True,
                             capture_output=True).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(into, filter="data")
    return into / "src"


def child_env(src: Path, numba_cache: Path | None = None) -> dict[str, str]:
    """This process's environment with ``src`` first on ``PYTHONPATH`` (and a numba cache)."""
    env = {**os.environ, "PYTHONPATH": str(src)}
    if numba_cache is not None:
        env["NUMBA_CACHE_DIR"] = str(numba_cache)
    return env
