"""Watching numba compile: the one listener behind ``sonarcarve warm``'s count and the command
line's cold-cache notice.

numba's ``numba:compile`` event fires only when a function is really compiled, never when its
machine code is loaded from the disk cache, so it says exactly whether a run had to compile.
numba is imported only when a watch starts (``import sonarcarve`` and ``--help`` stay free of it).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = ["watching_compiles"]


@contextmanager
def watching_compiles(on_start: Callable[[str], None] | None = None) -> Iterator[list[str]]:
    """Collect the name (``__qualname__``) of every function numba compiles meanwhile, as each
    compile ends; ``on_start(name)`` is called as each one starts."""
    from numba.core import event

    names: list[str] = []

    def name_of(ev: event.Event) -> str:
        return str(ev.data["dispatcher"].py_func.__qualname__)

    class _Listener(event.Listener):
        def on_start(self, ev: event.Event) -> None:
            if on_start is not None:
                on_start(name_of(ev))

        def on_end(self, ev: event.Event) -> None:
            names.append(name_of(ev))

    listener = _Listener()
    event.register("numba:compile", listener)  # type: ignore[no-untyped-call]  # numba
    try:
        yield names
    finally:
        event.unregister("numba:compile", listener)  # type: ignore[no-untyped-call]
