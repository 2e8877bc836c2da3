"""Compiled-kernel plumbing: one decorator for every numba kernel under :data:`KERNEL_FOLDERS`.

Why not plain ``numba.njit(cache=True)``: numba keys a function's on-disk cache on the
modification time and size of *that function's own file*. A kernel that calls a compiled function
of another module (``methods/carving.py`` calls :func:`~sonarcarve.geometry.carve_arcs`, which
calls the specular helpers of ``geometry/specular.py``) has the callee's machine code inlined into
its own cache entry, so editing the callee's file would leave the caller running the old code.

:func:`compiled` therefore keys every cache entry on :data:`SOURCES_STAMP`, a hash of the source
files of every module that may hold a kernel (:data:`KERNEL_FOLDERS`): any edit to any of them
invalidates every cached kernel at once, and an unchanged tree reuses the cache. The rule that
keeps this sound: a compiled kernel calls only kernels defined under :data:`KERNEL_FOLDERS`.

The exception: the kernels of ``io/float_text.py`` (the CSV number parser), ``lab/metrics.py``
and ``history.py`` (storing a block of arcs in the history) use plain ``numba.njit(cache=True)``.
Each calls only kernels of its own file and no kernel elsewhere calls it, so numba's own per-file
key is sound for them, and an edit to the geometry does not make the CSV reader recompile.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TypeVar, cast

from numba import njit
from numba.core.caching import FunctionCache, IndexDataCacheFile

__all__ = ["KERNEL_FOLDERS", "SOURCES_STAMP", "compiled", "compiled_borrowing", "compiled_inline"]

_F = TypeVar("_F", bound=Callable[..., Any])

#: Folders of the ``sonarcarve`` package whose modules may define compiled kernels.
KERNEL_FOLDERS = ("geometry", "grids", "methods")


def _sources_stamp(package: Path | None = None) -> str:
    """SHA-256 over the paths and contents of every ``.py`` file in :data:`KERNEL_FOLDERS`
    of ``package`` (default: this ``sonarcarve``), their subpackages included: kernels live in
    packages such as ``grids/carved/``, and a file left out would let an edit to it run stale
    compiled code from the cache."""
    package = Path(__file__).resolve().parent.parent if package is None else package
    digest = hashlib.sha256()
    for folder in KERNEL_FOLDERS:
        for path in sorted((package / folder).rglob("*.py")):
            digest.update(f"{path.relative_to(package).as_posix()}\0".encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


#: The cache key of every compiled kernel (see the module docstring).
SOURCES_STAMP = _sources_stamp()


class _SourcesKeyedCache(FunctionCache):
    """numba's function cache with the index stamped by :data:`SOURCES_STAMP`.

    Everything else (where the files go, ``NUMBA_CACHE_DIR``, the index format) is numba's; only
    the freshness stamp, which numba takes from the function's own file, is replaced.
    """

    def __init__(self, py_func: Callable[..., Any]) -> None:
        super().__init__(py_func)  # type: ignore[no-untyped-call]  # numba is untyped
        self._cache_file = IndexDataCacheFile(  # type: ignore[no-untyped-call]
            cache_path=self._cache_path, filename_base=self._impl.filename_base,
            source_stamp=SOURCES_STAMP,
        )

    def save_overload(self, sig: Any, data: Any) -> None:
        """numba's save, one process at a time (:func:`_cache_lock`)."""
        with _cache_lock(self._cache_path):
            super().save_overload(sig, data)  # type: ignore[no-untyped-call]


#: The lock file :func:`_cache_lock` takes, in each cache folder.
CACHE_LOCK_NAME = "sonarcarve-cache.lock"


@contextlib.contextmanager
def _cache_lock(folder: str) -> Iterator[None]:
    """Hold an exclusive lock on ``folder``'s :data:`CACHE_LOCK_NAME` while saving to it.

    numba saves an overload by reading the function's index, naming a free data file and
    rewriting the index whole. Two processes saving overloads of one function at once (the
    lanes of a parallel ``sonarcarve warm`` share small kernels) could both pick ``.1.nbc`` and
    leave the index pointing one signature at the other's machine code, which numba loads
    without checking; a lock makes the saves take turns (numba/numba#10128 suggests the same).
    Where ``fcntl`` is missing (Windows) the saves are not guarded.
    """
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not on POSIX
        yield
        return
    Path(folder).mkdir(parents=True, exist_ok=True)
    with (Path(folder) / CACHE_LOCK_NAME).open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def compiled(func: _F) -> _F:
    """``numba.njit`` with an on-disk cache keyed on all kernel sources (module docstring).

    Typed so that mypy keeps the function's own signature.
    """
    return _compile(func, inline=False)


def compiled_inline(func: _F) -> _F:
    """:func:`compiled`, inlined into its callers by numba (``inline="always"``).

    For the helpers of a hot loop: numba does not inline one compiled function into another
    by itself, and a call that passes arrays costs reference counting on top of the call
    (``benchmarks/carve_kernel.py``: inlining the exact carving path made ``carve_arc`` 30 %
    faster). Inlining changes no arithmetic, so results stay bit-identical.
    """
    return _compile(func, inline=True)


def compiled_borrowing(func: _F) -> _F:
    """:func:`compiled` without numba's reference counting (``_nrt=False``): for kernels that
    only *borrow* the arrays they are given, which their caller owns for the whole call.

    numba counts references to every array it binds to a name: each argument of an inlined
    helper, each array taken from a tuple, each call passing one costs an atomic increment and
    decrement (``NRT_incref``/``NRT_decref``). In carving's kernel that was about 300 atomic
    operations per reading, half of its CPU time (``perf record`` on ``benchmarks/ab_trees.py``'s
    stream at history 250); without them the same code does the same arithmetic (bit for bit
    the same results). The price: such a kernel cannot allocate (no ``np.empty``; its caller
    passes the work arrays) and must not return or keep an array. Helpers inlined into it
    (:func:`compiled_inline`) are compiled with it, so they count nothing either.
    """
    return _compile(func, inline=False, nrt=False)


def _numba_knows_nrt_option() -> bool:
    """Whether this numba has the ``_nrt`` target option (0.59 to 0.68 have it).

    It is private: a numba without it would refuse every kernel at its first call ("Unrecognized
    options"), so it is asked for only where it exists. Without it the borrowing kernels count
    references like the others: the same results, only slower (they allocate nothing).
    """
    try:
        from numba.core.cpu import CPUTargetOptions
        from numba.core.options import TargetOptions
    except ImportError:
        return False
    return isinstance(getattr(CPUTargetOptions, "_nrt", None), TargetOptions.Mapping)


#: Whether :func:`compiled_borrowing` can switch reference counting off in this numba.
SKIPS_REFERENCE_COUNTS = _numba_knows_nrt_option()


def _compile(func: _F, *, inline: bool, nrt: bool = True) -> _F:
    options: dict[str, Any] = {"inline": "always" if inline else "never"}
    if not nrt and SKIPS_REFERENCE_COUNTS:
        options["_nrt"] = False  # numba's target option; not in its typed signature
    dispatcher = njit(**options)(func)
    # numba's Dispatcher.enable_caching does exactly this with its own FunctionCache.
    dispatcher._cache = _SourcesKeyedCache(func)  # numba internal
    return cast(_F, dispatcher)
