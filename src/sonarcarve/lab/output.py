"""What every lab writer shares: strict-JSON values and marked Markdown sections.

A generated section of a Markdown file lives between a begin and an end marker (HTML comments,
for example ``<!-- experiments:begin -->`` and ``<!-- experiments:end -->``); the rest of the
file belongs to someone else. :func:`replace_marked_section` rewrites only that span. A file
without the markers is refused rather than appended to, unless the caller says the file is new
(``append_missing``): a wrong ``--results-md`` must not grow someone's README silently.
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Collection, Iterable, Sequence
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from sonarcarve.errors import SonarcarveError
from sonarcarve.io.atomic import atomic_path, atomic_text

__all__ = [
    "Markers",
    "check_marked_file",
    "copy_into",
    "find_marked_section",
    "json_ready",
    "links_from",
    "replace_marked_section",
    "write_marked_file",
]


def json_ready(value: Any) -> Any:
    """``value`` made strict-JSON: NaN and inf become None, tuples and arrays lists, numpy
    scalars Python numbers, dict keys strings (recursively).

    Examples
    --------
    >>> json_ready({"a": float("nan"), 1: (np.float64(2.5), np.arange(2))})
    {'a': None, '1': [2.5, [0, 1]]}
    """
    if isinstance(value, dict):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, bool) or value is None or isinstance(value, str | int):
        return value
    if hasattr(value, "item"):  # numpy scalars (np.float64 is a float, np.bool_ is not)
        value = value.item()
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    return value


def find_marked_section(
    text: str,
    begin: str,
    end: str,
    where: str,
    *,
    append_missing: bool = False,
    error: type[SonarcarveError] = SonarcarveError,
) -> tuple[int, int] | None:
    """Where the marked section of ``text`` is: ``(start, stop)`` character offsets spanning
    both markers, or None when it is to be appended (``text`` empty or blank, or
    ``append_missing`` and neither marker present).

    Raises
    ------
    error
        (one line naming ``where`` and the line) when one marker is missing, they are repeated
        or out of order, or neither is present in a non-blank ``text`` and not
        ``append_missing``.

    Examples
    --------
    >>> find_marked_section("a\\n<!-- b -->\\nx\\n<!-- e -->\\n", "<!-- b -->", "<!-- e -->", "f")
    (2, 25)
    >>> find_marked_section("", "<!-- b -->", "<!-- e -->", "f") is None
    True
    """
    begins, ends = text.count(begin), text.count(end)
    if begins == 0 and ends == 0:
        if append_missing or not text.strip():
            return None
        msg = (f"{where}: has no {begin} ... {end} markers; add them where the generated "
               "section should go (or give a file that does not exist yet)")
        raise error(msg)
    start, stop = text.find(begin), text.find(end)
    if begins != 1 or ends != 1 or stop < start:
        # Point at the first marker out of place: a lone or early end marker, else the begin.
        first = stop if stop >= 0 and (start < 0 or stop < start) else start
        line = text[:first].count("\n") + 1
        msg = f"{where}: line {line}: expected one {begin} followed by one {end}"
        raise error(msg)
    return start, stop + len(end)


def replace_marked_section(
    text: str,
    section: str,
    begin: str,
    end: str,
    where: str,
    *,
    append_missing: bool = False,
    error: type[SonarcarveError] = SonarcarveError,
) -> str:
    """``text`` with its span from ``begin`` to ``end`` (inclusive) replaced by ``section``.

    ``section`` must start with ``begin`` and end with ``end``. When :func:`find_marked_section`
    says to append (blank ``text``, or ``append_missing`` without markers), ``section`` goes at
    the end after a blank line. Raises as :func:`find_marked_section`.

    Examples
    --------
    >>> replace_marked_section("a\\n[b]\\nold\\n[e]\\nz\\n", "[b]\\nnew\\n[e]", "[b]", "[e]", "f")
    'a\\n[b]\\nnew\\n[e]\\nz\\n'
    >>> replace_marked_section("a", "[b]\\nnew\\n[e]", "[b]", "[e]", "f", append_missing=True)
    'a\\n\\n[b]\\nnew\\n[e]\\n'
    """
    span = find_marked_section(text, begin, end, where, append_missing=append_missing,
                               error=error)
    if span is None:
        if not text.strip():
            return f"{section}\n"
        joint = "" if text.endswith("\n\n") else ("\n" if text.endswith("\n") else "\n\n")
        return f"{text}{joint}{section}\n"
    return text[:span[0]] + section + text[span[1]:]


class Markers(NamedTuple):
    """The begin and end markers of one generated section, and the error a broken file raises."""

    begin: str
    end: str
    error: type[SonarcarveError] = SonarcarveError


def _read(path: Path) -> tuple[str, bool]:
    """The file's text and whether it is fresh (missing, or blank: nothing to keep)."""
    text = path.read_text(encoding="utf-8") if path.exists() else ""
    return text, not text.strip()


def check_marked_file(path: str | Path, markers: Iterable[Markers], *,
                      appendable: Collection[Markers] = ()) -> None:
    """Check that :func:`write_marked_file` can write these sections into ``path``: it does not
    exist (or is blank), or it holds each pair of ``markers`` once and in order (those in
    ``appendable`` may also be missing altogether).

    Raises
    ------
    SonarcarveError
        The ``error`` of the first pair of markers that is missing or broken.
    """
    md = Path(path)
    text, fresh = _read(md)
    for m in markers:
        find_marked_section(text, m.begin, m.end, str(md), append_missing=fresh or m in appendable,
                            error=m.error)


def write_marked_file(path: str | Path, sections: Sequence[tuple[Markers, str]], *,
                      appendable: Collection[Markers] = ()) -> Path:
    """Rewrite each ``(markers, section)`` span of the Markdown file ``path`` atomically.

    A missing or blank file is created with the sections one after the other. An existing one
    must hold every pair of markers, except that a section whose markers are in ``appendable``
    and missing is appended at the end (see :func:`check_marked_file`); nothing is written
    otherwise. Text outside the markers is kept as it is.
    """
    md = Path(path)
    text, fresh = _read(md)
    for m, section in sections:
        text = replace_marked_section(text, section, m.begin, m.end, str(md),
                                      append_missing=fresh or m in appendable, error=m.error)
    with atomic_text(md) as handle:
        handle.write(text)
    return md


def links_from(markdown: str | Path, paths: Iterable[str | Path]) -> list[str]:
    """``paths`` relative to the folder of the Markdown file ``markdown``, POSIX-style."""
    folder = Path(markdown).parent
    return [Path(os.path.relpath(Path(p), folder)).as_posix() for p in paths]


def copy_into(path: str | Path, folder: str | Path) -> Path:
    """Copy the file ``path`` into ``folder`` (created if missing) atomically; the copy."""
    source, target = Path(path), Path(folder)
    target.mkdir(parents=True, exist_ok=True)
    with atomic_path(target / source.name, suffix=source.suffix) as tmp:
        shutil.copyfile(source, tmp)
    return target / source.name
