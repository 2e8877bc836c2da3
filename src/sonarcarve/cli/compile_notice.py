"""One stderr line when a command has to compile numba kernels (a cold cache).

sonarcarve's kernels are compiled by numba on first use and cached on disk; a run on a cold
cache (a fresh installation that skipped ``sonarcarve warm``, a new ``NUMBA_CACHE_DIR``, an
upgrade) spends from half a minute (one method) to a few minutes (the demo, every method and
grid) compiling before it gets going, which looked like a hang.

The test for "cold" is numba's own: its ``numba:compile`` event fires only when a function is
really compiled, never when its machine code is loaded from the cache (``sonarcarve.warm``
counts compiles the same way). So the line appears exactly when compiling starts, once per
process, and never on a warm cache; no stamp file can go stale. It goes to stderr through
``print``, which a rich progress bar on screen redirects above itself.

``SONARCARVE_COMPILE_NOTICE=0`` switches it off (the test suite does, so that its checks of a
command's exact stderr do not depend on the state of the cache).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["COMPILE_NOTICE", "announce_compiling", "notice_enabled"]

#: The line printed on stderr when the first kernel starts compiling.
COMPILE_NOTICE = ("sonarcarve: first run on this machine: compiling kernels, once (up to a few "
                  "minutes); `sonarcarve warm` does it ahead")


def notice_enabled() -> bool:
    """False when ``SONARCARVE_COMPILE_NOTICE`` is ``0`` (or ``false``/``no``/``off``)."""
    return os.environ.get("SONARCARVE_COMPILE_NOTICE", "1").strip().lower() not in {
        "0", "false", "no", "off"}


@contextmanager
def announce_compiling() -> Iterator[list[str]]:
    """While inside, print :data:`COMPILE_NOTICE` once when numba starts compiling anything.

    Yields the list of functions whose compiling started (for tests). Imports numba: use it
    only around a command that runs kernels anyway.
    """
    from sonarcarve.compiles import watching_compiles

    started: list[str] = []

    def note(name: str) -> None:
        if not started:
            print(COMPILE_NOTICE, file=sys.stderr, flush=True)
        started.append(name)

    with watching_compiles(on_start=note):
        yield started
