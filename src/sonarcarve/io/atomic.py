"""Write files whole or not at all, and check output paths before the work that fills them.

A file is written to a temporary file beside its target and renamed into place, so a reader
never sees a half-written file and a failed write leaves an existing file as it was. The checks
(:func:`check_output_file`, :func:`check_output_dir`) let a command refuse a bad output path in
one line *before* it spends minutes computing what it would write there.

Every failure is an :class:`~sonarcarve.io.errors.OutputError` with a one-line message naming
the path and the reason. Missing parent directories of a file are never created: a typo in a
path is an error, not a new folder. A file name ending in ``/`` is refused (``out.csv/`` names a
folder, and pathlib would silently drop the slash), and so is a symbolic link to nothing; a link
to an existing file is followed: the file it points to is replaced, the link stays.

Temporary files are named ``.NAME.sc-PID-XXXXXXXX.SUFFIX`` beside the target (``NAME`` cut to 100
characters so the temporary name fits where the target's does). A process killed while writing
(``kill -9``, a power cut) cannot remove its own; so every write to a target first removes the
temporaries of that target whose process ``PID`` is no longer running (:func:`remove_stale`).
A live writer's temporary is never touched, so two commands writing beside each other are safe.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from collections.abc import Iterable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import IO

from sonarcarve.io.errors import OutputError

__all__ = [
    "atomic_path",
    "atomic_paths",
    "atomic_text",
    "check_output_dir",
    "check_output_file",
    "make_output_dir",
    "remove_stale",
]

#: Characters of the target's name kept in its temporary file's name.
_NAME_KEEP = 100
#: What marks a temporary file of ours after ``.NAME.``: ``sc-PID-``.
_TEMP_TAG = "sc-"


def check_output_file(path: str | Path, *, inputs: Iterable[str | Path] = (),
                      label: str | None = None) -> Path:
    """Check that a file can be written at ``path``; return it as a :class:`Path`.

    The target must not be a directory or another non-regular file (a device, a pipe), its
    directory must exist and accept new files (tested by creating and removing an empty
    temporary file there, which also catches read-only mounts and ``/proc`` when running as
    root), and it must not be one of ``inputs`` (an output that replaces its own input loses
    the input when the command fails halfway, and always loses it on success).

    Parameters
    ----------
    path : str or Path
        The file to be written.
    inputs : iterable of str or Path
        Files the command reads; the output may not be any of them.
    label : str, optional
        How to name the path in the message, e.g. ``"--out map.csv"``; default: the path.

    Raises
    ------
    OutputError
        One line naming the path and the reason.
    """
    where = label if label is not None else str(path)
    if str(path).strip() in ("", "."):  # typer turns an empty path into "."
        msg = f"{where}: empty, expected a file name"
        raise OutputError(msg)
    target = _file_target(path, where)
    for source in inputs:
        if _same_file(target, Path(source)):
            msg = f"{where}: is the input file {source}; write the output to another file"
            raise OutputError(msg)
    _probe_file(target.parent, where)
    return target


def check_output_dir(path: str | Path, *, label: str | None = None) -> Path:
    """Check that ``path`` is, or can be created as, a folder to write files into.

    An existing ``path`` must be a directory that accepts new files. A missing one is created
    later (with its missing parents) by :func:`make_output_dir`, so its nearest existing
    ancestor must be a directory that accepts new folders. Nothing is left behind: the test
    creates and removes an empty temporary file or folder.

    Raises
    ------
    OutputError
        One line naming the path and the reason.
    """
    target = Path(path)
    where = label if label is not None else str(target)
    if not str(path).strip():
        msg = f"{where.strip()}: empty, expected a folder name"
        raise OutputError(msg)
    existing = next((p for p in (target, *target.parents) if p.exists()), Path())
    if not existing.is_dir():
        msg = (f"{where}: exists and is not a directory" if existing == target
               else f"{where}: {existing} exists and is not a directory")
        raise OutputError(msg)
    if existing == target:
        _probe_file(target, where)
    else:
        try:
            tempfile.TemporaryDirectory(prefix=".sonarcarve-probe-", dir=existing).cleanup()
        except OSError as err:
            msg = f"{where}: cannot create a folder in {existing} ({_reason(err)})"
            raise OutputError(msg) from None
    return target


def make_output_dir(path: str | Path, *, label: str | None = None) -> Path:
    """Create the folder ``path`` and its missing parents (no error if it exists).

    Raises
    ------
    OutputError
        ``path`` or an ancestor is a file, or the folder cannot be created.
    """
    target = check_output_dir(path, label=label)
    try:
        target.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        where = label if label is not None else str(target)
        msg = f"{where}: cannot create the folder ({_reason(err)})"
        raise OutputError(msg) from None
    return target


@contextmanager
def atomic_path(path: str | Path, suffix: str = "") -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it onto ``path``.

    On any exception the temporary file is removed and ``path`` is left as it was, so a reader
    never sees a half-written file. The directory of ``path`` must exist.

    Raises
    ------
    OutputError
        ``path`` is a directory or not a regular file, its directory does not exist or refuses
        new files, or an :class:`OSError` occurred while writing or renaming (the message names
        ``path`` and the reason; the original error is chained).
    """
    target = _file_target(path, f"cannot write {path}")
    remove_stale(target)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=_temp_prefix(target) + f"{os.getpid()}-",
                                        suffix=suffix or ".tmp", dir=_parent(target))
    except OSError as err:
        msg = f"cannot write {target}: cannot create a file in {_parent(target)} ({_reason(err)})"
        raise OutputError(msg) from err
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        tmp.chmod(0o666 & ~_umask())  # mkstemp makes 0600; give the usual permissions
        yield tmp
        tmp.replace(target)
    except OutputError:
        tmp.unlink(missing_ok=True)
        raise
    except OSError as err:
        tmp.unlink(missing_ok=True)
        msg = f"cannot write {target}: {_reason(err)}"
        raise OutputError(msg) from err
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


@contextmanager
def atomic_paths(*paths: str | Path) -> Iterator[tuple[Path, ...]]:
    """Yield one temporary path per target; rename them all only when the block succeeds.

    For files that belong together (a readings CSV and its truth file): a failure anywhere in
    the block leaves every target as it was. Every target is checked before anything is
    written; the renames happen last to first, each one atomic.

    Raises
    ------
    OutputError
        As :func:`atomic_path`, for any of the targets.
    """
    targets = [_file_target(path, f"cannot write {path}") for path in paths]
    with ExitStack() as stack:
        temps = tuple(stack.enter_context(atomic_path(target, suffix=target.suffix))
                      for target in targets)
        try:
            yield temps
        except OutputError as err:
            # A writer that itself writes atomically names the temporary file: name the target.
            message = str(err)
            for tmp, target in zip(temps, targets, strict=True):
                message = message.replace(str(tmp), str(target))
            raise OutputError(message) from err
        except OSError as err:
            msg = f"cannot write {' and '.join(map(str, targets))}: {_reason(err)}"
            raise OutputError(msg) from err


@contextmanager
def atomic_text(path: str | Path) -> Iterator[IO[str]]:
    """Open a text file for writing that appears at ``path`` only when closed without error.

    Raises
    ------
    OutputError
        As :func:`atomic_path`.
    """
    with atomic_path(path) as tmp, tmp.open("w", newline="", encoding="utf-8") as handle:
        yield handle


def remove_stale(path: str | Path) -> list[Path]:
    """Remove the temporary files of ``path`` left by writers that are no longer running.

    Only files named as :func:`atomic_path` names them (``.NAME.sc-PID-XXXXXXXX.SUFFIX``)
    whose ``PID`` is not a running process are removed; a live writer's file stays. Never
    fails: a file that cannot be removed is left for the next write.

    Returns
    -------
    list of Path
        The files removed.
    """
    target = Path(path)
    prefix = _temp_prefix(target)
    pattern = re.compile(re.escape(prefix) + r"(\d+)-[A-Za-z0-9_]+")
    removed = []
    try:
        entries = list(os.scandir(_parent(target)))
    except OSError:
        return []
    for entry in entries:
        match = pattern.match(entry.name)
        if match is None or _running(int(match.group(1))):
            continue
        with contextlib.suppress(OSError):
            Path(entry.path).unlink()
            removed.append(Path(entry.path))
    return removed


def _temp_prefix(target: Path) -> str:
    return f".{target.name[:_NAME_KEEP]}.{_TEMP_TAG}"


def _running(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True  # someone else's live process (or a number we cannot judge): leave it
    return True


def _file_target(path: str | Path, where: str) -> Path:
    """``path`` checked as a file to write, a link to a file followed; else one OutputError."""
    text = os.fspath(path)
    if text.endswith(("/", os.sep)) or (os.altsep and text.endswith(os.altsep)):
        msg = f"{where}: ends in '/', expected a file name"
        raise OutputError(msg)
    target = Path(text)
    try:
        if target.is_symlink():
            if not target.exists():
                msg = (f"{where}: is a symbolic link to {target.readlink()}, which does not "
                       "exist")
                raise OutputError(msg)
            target = Path(os.path.realpath(target))
        _check_file_target(target, where)
    except OutputError:
        raise
    except OSError as err:  # a name longer than the file system allows, a loop of links, ...
        msg = f"{where}: {_reason(err)}"
        raise OutputError(msg) from None
    return target


def _check_file_target(target: Path, where: str) -> None:
    if target.is_dir():
        msg = f"{where}: is a directory, expected a file name"
        raise OutputError(msg)
    if target.exists() and not target.is_file():
        # Renaming onto a device or a pipe would replace it (as root, even /dev/null).
        msg = f"{where}: exists and is not a regular file"
        raise OutputError(msg)
    parent = _parent(target)
    if not parent.exists():
        msg = f"{where}: directory {parent} does not exist"
        raise OutputError(msg)
    if not parent.is_dir():
        msg = f"{where}: {parent} is not a directory"
        raise OutputError(msg)


def _probe_file(folder: Path, where: str) -> None:
    """Create and remove an empty file in ``folder``: the only sure test that it accepts one."""
    try:
        with tempfile.NamedTemporaryFile(prefix=".sonarcarve-probe-", dir=folder):
            pass
    except OSError as err:
        msg = f"{where}: cannot create a file in {folder} ({_reason(err)})"
        raise OutputError(msg) from None


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and a.samefile(b)
    except OSError:
        return False


def _parent(target: Path) -> Path:
    return target.parent if str(target.parent) else Path()


def _reason(err: OSError) -> str:
    return err.strerror or str(err)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
