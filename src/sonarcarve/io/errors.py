"""Errors of the I/O layer, and the shared way every loader reads a text, JSON or YAML file.

Every loader reads its file through :func:`read_text` (or :func:`load_json` /
:func:`load_yaml`, or :func:`parse_json` / :func:`parse_yaml` on text it already has), so a bad
file gives the same one-line wording whichever loader met it:

- ``<path>: no such file``
- ``<path>: is a directory``
- ``<path>: permission denied``
- ``<path>: line L: not UTF-8 text (byte 0xff)``
- ``<path>: line L, column C: invalid JSON (<reason>)``
- ``<path>: line L, column C: invalid YAML (<reason>)``
- ``<path>: larger than the limit of N bytes for this kind of file``
- ``<path>: not text (NUL byte at line L)``
- ``<path>: invalid YAML (aliases expand to more than N nodes)``

each raised as the caller's :class:`~sonarcarve.errors.SonarcarveError` subclass (default
:class:`InputError`), so a world loader raises ``WorldError`` and a robot loader ``RobotError``.

Limits that protect the machine from a hostile or mistaken file, whatever its name says:

- a configuration file (world JSON, waypoints) is read only up to :data:`MAX_CONFIG_BYTES`,
  a YAML file (robot, ``map.yaml``) up to :data:`MAX_YAML_BYTES`; :func:`load_json` and
  :func:`load_yaml` apply them, and :func:`read_text` takes ``max_bytes`` (logs pass None: they
  are streamed or may be large);
- every read stops at the first NUL byte, so ``/dev/zero`` or a binary file given as text fails
  at once instead of being read until memory runs out;
- YAML aliases may expand to at most :data:`MAX_YAML_NODES` nodes in all (a "billion laughs"
  file of a few hundred bytes would otherwise expand to billions), and recursive aliases are
  refused;
- any user text quoted in a message goes through :func:`shorten` (at most
  :data:`MAX_QUOTE_CHARS` characters).
"""

from __future__ import annotations

import functools
import json
import math
from pathlib import Path
from typing import Any, NoReturn

from sonarcarve.errors import SonarcarveError
from sonarcarve.extras import require

__all__ = [
    "MAX_CONFIG_BYTES",
    "MAX_QUOTE_CHARS",
    "MAX_YAML_BYTES",
    "MAX_YAML_NODES",
    "InputError",
    "OutputError",
    "finite_number",
    "load_json",
    "load_yaml",
    "parse_json",
    "parse_number",
    "parse_yaml",
    "read_text",
    "shorten",
]

#: Largest configuration file (robot YAML, world JSON, map.yaml, waypoints) read, bytes: ten
#: times a 100,000-wall world in JSON. Logs (readings, bags) are not configuration files.
MAX_CONFIG_BYTES = 16 * 2**20
#: Largest YAML file read, bytes: PyYAML parses about 120 kB a second, and a robot or a
#: map.yaml is a few kB (a thousand-sensor ring is about 60 kB).
MAX_YAML_BYTES = 256 * 2**10
#: Most YAML nodes a document may have once its aliases are expanded: a robot with a thousand
#: sensors has about 10,000; a "billion laughs" file of 500 bytes has billions.
MAX_YAML_NODES = 100_000
#: Longest piece of user input (a value, a header) quoted in a one-line message, characters.
MAX_QUOTE_CHARS = 80
#: Bytes read at a time, each checked for NUL bytes before the next is read.
_CHUNK = 2**20

#: The kind of error a reading helper raises: any SonarcarveError subclass taking one message.
ErrorType = type[SonarcarveError]


class InputError(SonarcarveError, ValueError):
    """A file that cannot be read as what it claims to be; the message names file and place."""


class OutputError(SonarcarveError, OSError):
    """A file or folder that cannot be written; the message names the path and the reason.

    Also an :class:`OSError`, so code that caught the operating system's error still does.
    """


# --------------------------------------------------------------------------------------------
# Reading files: one wording for every loader
# --------------------------------------------------------------------------------------------

def _raise(error_type: ErrorType, where: str | Path, problem: str) -> NoReturn:
    msg = f"{where}: {problem}"
    raise error_type(msg) from None  # the one line says it all; no chained traceback


def read_text(path: str | Path, error_type: ErrorType = InputError,
              max_bytes: int | None = None) -> str:
    """The whole file as text: UTF-8 (a leading byte-order mark is dropped), newlines ``\\n``.

    Parameters
    ----------
    path : str or Path
        The file.
    error_type : type
        The :class:`~sonarcarve.errors.SonarcarveError` subclass to raise.
    max_bytes : int, optional
        Refuse a file larger than this (a configuration file: :data:`MAX_CONFIG_BYTES`); None
        for no limit. Only ``max_bytes + 1`` bytes are ever read, so a device or a pipe that
        never ends fails too.

    Raises
    ------
    error_type
        One line: ``<path>: no such file``, ``is a directory``, ``permission denied``,
        ``line L: not UTF-8 text (byte 0x..)``, ``not text (NUL byte at line L)``, ``larger
        than the limit of N bytes for this kind of file`` or ``cannot read (<reason>)``.

    Examples
    --------
    >>> read_text("/nonexistent/walls.json")
    Traceback (most recent call last):
    ...
    sonarcarve.io.errors.InputError: /nonexistent/walls.json: no such file
    >>> read_text("/dev/zero")
    Traceback (most recent call last):
    ...
    sonarcarve.io.errors.InputError: /dev/zero: not text (NUL byte at line 1)
    """
    path = Path(path)
    try:
        data = _read_bytes(path, max_bytes, error_type)
    except FileNotFoundError:
        _raise(error_type, path, "no such file")
    except IsADirectoryError:
        _raise(error_type, path, "is a directory")
    except PermissionError:
        _raise(error_type, path, "permission denied")
    except OSError as err:
        _raise(error_type, path, f"cannot read ({err.strerror or err})")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        # Offsets count from after a byte-order mark, if any; lines are what people look for.
        offset = err.start + (3 if data.startswith(b"\xef\xbb\xbf") else 0)
        line = data.count(b"\n", 0, offset) + 1
        _raise(error_type, path, f"line {line}: not UTF-8 text (byte 0x{data[offset]:02x})")
    # What open(..., "r") would give: universal newlines.
    return text.replace("\r\n", "\n").replace("\r", "\n")


def _read_bytes(path: Path, max_bytes: int | None, error_type: ErrorType) -> bytes:
    """The file's bytes, read a chunk at a time: stops at a NUL byte or past ``max_bytes``."""
    chunks: list[bytes] = []
    size = 0
    with path.open("rb") as handle:
        while True:
            want = _CHUNK if max_bytes is None else min(_CHUNK, max_bytes + 1 - size)
            chunk = handle.read(want) if want > 0 else b""
            nul = chunk.find(b"\0")
            if nul >= 0:
                line = sum(c.count(b"\n") for c in chunks) + chunk.count(b"\n", 0, nul) + 1
                _raise(error_type, path, f"not text (NUL byte at line {line})")
            chunks.append(chunk)
            size += len(chunk)
            if max_bytes is not None and size > max_bytes:
                _raise(error_type, path, f"larger than the limit of {max_bytes:,} bytes for "
                                         "this kind of file")
            if not chunk:
                return b"".join(chunks)


def shorten(text: str, limit: int = MAX_QUOTE_CHARS) -> str:
    """``text`` on one line and at most ``limit`` characters, cut in the middle with ``...``.

    For quoting user input (a value, a header, a name) in a one-line message.

    Examples
    --------
    >>> shorten("t,sensor,x,y,theta,range")
    't,sensor,x,y,theta,range'
    >>> shorten("a" * 50 + "b" * 50, 21)
    'aaaaaaaaa...bbbbbbbbb'
    >>> shorten("two\\nlines")
    'two lines'
    """
    flat = " ".join(text.split("\n")) if "\n" in text else text
    if len(flat) <= limit:
        return flat
    keep = max(limit - 3, 2)
    return f"{flat[:(keep + 1) // 2]}...{flat[len(flat) - keep // 2:]}"


def parse_json(text: str, where: str | Path, error_type: ErrorType = InputError) -> Any:
    """JSON text parsed; ``where`` (usually the file) prefixes the one-line error.

    Raises
    ------
    error_type
        ``<where>: line L, column C: invalid JSON (<reason>)``, or ``invalid JSON (nested too
        deeply)`` for input that would exhaust Python's recursion limit.
    """
    try:
        return json.loads(text)
    except json.JSONDecodeError as err:
        _raise(error_type, where, f"line {err.lineno}, column {err.colno}: invalid JSON "
                                  f"({err.msg})")
    except RecursionError:
        _raise(error_type, where, "invalid JSON (nested too deeply)")
    except ValueError as err:  # an integer longer than Python's int_max_str_digits
        _raise(error_type, where, f"invalid JSON ({_first_clause(err)})")


def parse_yaml(text: str, where: str | Path, error_type: ErrorType = InputError) -> Any:
    """YAML text parsed like ``yaml.safe_load``, with aliases limited; ``where`` prefixes errors.

    A document whose aliases would expand to more than :data:`MAX_YAML_NODES` nodes (a
    "billion laughs" bomb), or with an alias inside its own anchor, is refused before any of it
    is built.

    Raises
    ------
    error_type
        ``<where>: line L, column C: invalid YAML (<reason>)`` (without the place when the YAML
        library gives none).

    Examples
    --------
    >>> parse_yaml("a: &x [1, 2]\\nb: *x", "f.yaml")
    {'a': [1, 2], 'b': [1, 2]}
    >>> bomb = "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\\n" + "".join(
    ...     f"{k}: &{k} [{', '.join([f'*{p}'] * 10)}]\\n" for p, k in zip("abcd", "bcde"))
    >>> parse_yaml(bomb, "f")
    Traceback (most recent call last):
    ...
    sonarcarve.io.errors.InputError: f: invalid YAML (aliases expand to more than 100,000 nodes)
    """
    yaml = require("yaml", "cli", "YAML files (robots, map_server maps)")

    try:
        return yaml.load(text, Loader=_limited_loader())  # a SafeLoader subclass
    except _AliasLimitError as err:
        _raise(error_type, where, f"invalid YAML ({err})")
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        place = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        reason = getattr(err, "problem", None) or getattr(err, "context", None) or "syntax error"
        _raise(error_type, where, f"{place}invalid YAML ({shorten(' '.join(str(reason).split()))})")
    except RecursionError:
        _raise(error_type, where, "invalid YAML (nested too deeply)")
    except ValueError as err:  # a scalar its constructor rejects: a too-long integer, a bad date
        _raise(error_type, where, f"invalid YAML ({shorten(_first_clause(err))})")


class _AliasLimitError(Exception):
    """A YAML document whose aliases expand too far or refer to themselves."""


@functools.cache
def _limited_loader() -> type[Any]:
    """``yaml.SafeLoader`` that weighs the composed node graph before constructing anything.

    PyYAML shares an aliased node instead of copying it, so parsing a bomb is cheap; the damage
    comes later, when the value is walked, printed or quoted. The weight of a node is 1 plus
    the weights of its children, each shared node counted every time it is referred to: the
    size the value has when walked. Memoised per node, so weighing costs one pass.
    """
    yaml = require("yaml", "cli", "YAML files (robots, map_server maps)")

    class LimitedLoader(yaml.SafeLoader):  # type: ignore[misc,name-defined]
        def get_single_node(self) -> Any:
            node = super().get_single_node()
            if node is not None:
                _check_weight(node, yaml)
            return node

    return LimitedLoader


def _check_weight(root: Any, yaml: Any) -> None:
    weights: dict[int, int] = {}
    active: set[int] = set()
    # Iterative post-order walk (a deep document must not exhaust Python's stack here).
    stack: list[tuple[Any, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        key = id(node)
        if done:
            active.discard(key)
            weights[key] = 1 + sum(weights[id(child)] for child in _children(node, yaml))
            if weights[key] > MAX_YAML_NODES:
                msg = f"aliases expand to more than {MAX_YAML_NODES:,} nodes"
                raise _AliasLimitError(msg)
            continue
        if key in weights:
            continue
        if key in active:
            msg = "an alias refers to the node that defines it"
            raise _AliasLimitError(msg)
        active.add(key)
        stack.append((node, True))
        stack.extend((child, False) for child in _children(node, yaml)
                     if id(child) not in weights)


def _children(node: Any, yaml: Any) -> list[Any]:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [item for pair in node.value for item in pair]
    return []


def _first_clause(err: Exception) -> str:
    return " ".join(str(err).split(";")[0].split())


def load_json(path: str | Path, error_type: ErrorType = InputError) -> Any:
    """:func:`read_text` (at most :data:`MAX_CONFIG_BYTES`) then :func:`parse_json`."""
    return parse_json(read_text(path, error_type, MAX_CONFIG_BYTES), Path(path), error_type)


def load_yaml(path: str | Path, error_type: ErrorType = InputError) -> Any:
    """:func:`read_text` (at most :data:`MAX_YAML_BYTES`) then :func:`parse_yaml`."""
    return parse_yaml(read_text(path, error_type, MAX_YAML_BYTES), Path(path), error_type)


def finite_number(value: object) -> float | None:
    """``value`` as a float if it is a finite JSON/YAML number (not a bool), else None.

    Examples
    --------
    >>> finite_number(3), finite_number(2.5), finite_number(True), finite_number("1")
    (3.0, 2.5, None, None)
    >>> finite_number(float("nan")), finite_number(10**400)  # too big for a float
    (None, None)
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def parse_number(text: str, where: str, column: str, *, finite: bool = True,
                 error_type: ErrorType = InputError) -> float:
    """One cell of a text table as a float, or a one-line error naming ``where`` and ``column``.

    ``where`` is the place, e.g. ``"poses.txt: line 4"``. With ``finite=False`` NaN and
    infinities pass (for callers that report them with their own, more specific message).

    Examples
    --------
    >>> parse_number(" 2.5", "f: line 3", "x")
    2.5
    >>> parse_number("abc", "f: line 3", "x")
    Traceback (most recent call last):
    ...
    sonarcarve.io.errors.InputError: f: line 3, column 'x' is not a number: 'abc'
    """
    try:
        value = float(text)
    except ValueError:
        msg = f"{where}, column {column!r} is not a number: {shorten(repr(text))}"
        raise error_type(msg) from None
    if finite and not math.isfinite(value):
        msg = f"{where}, column {column!r} is not finite: {shorten(repr(text))}"
        raise error_type(msg)
    return value
