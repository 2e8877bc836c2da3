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

each raised as the caller's :class:`~sonarcarve.errors.SonarcarveError` subclass (default
:class:`InputError`), so a world loader raises ``WorldError`` and a robot loader ``RobotError``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, NoReturn

from sonarcarve.errors import SonarcarveError
from sonarcarve.extras import require

__all__ = [
    "InputError",
    "OutputError",
    "finite_number",
    "load_json",
    "load_yaml",
    "parse_json",
    "parse_number",
    "parse_yaml",
    "read_text",
]

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


def read_text(path: str | Path, error_type: ErrorType = InputError) -> str:
    """The whole file as text: UTF-8 (a leading byte-order mark is dropped), newlines ``\\n``.

    Parameters
    ----------
    path : str or Path
        The file.
    error_type : type
        The :class:`~sonarcarve.errors.SonarcarveError` subclass to raise.

    Raises
    ------
    error_type
        One line: ``<path>: no such file``, ``is a directory``, ``permission denied``,
        ``line L: not UTF-8 text (byte 0x..)`` or ``cannot read (<reason>)``.

    Examples
    --------
    >>> read_text("/nonexistent/walls.json")
    Traceback (most recent call last):
    ...
    sonarcarve.io.errors.InputError: /nonexistent/walls.json: no such file
    """
    path = Path(path)
    try:
        data = path.read_bytes()
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
    """YAML text parsed with ``yaml.safe_load``; ``where`` prefixes the one-line error.

    Raises
    ------
    error_type
        ``<where>: line L, column C: invalid YAML (<reason>)`` (without the place when the YAML
        library gives none).
    """
    yaml = require("yaml", "cli", "YAML files (robots, map_server maps)")

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        place = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        reason = getattr(err, "problem", None) or getattr(err, "context", None) or "syntax error"
        _raise(error_type, where, f"{place}invalid YAML ({' '.join(str(reason).split())})")
    except RecursionError:
        _raise(error_type, where, "invalid YAML (nested too deeply)")
    except ValueError as err:  # a scalar its constructor rejects: a too-long integer, a bad date
        _raise(error_type, where, f"invalid YAML ({_first_clause(err)})")


def _first_clause(err: Exception) -> str:
    return " ".join(str(err).split(";")[0].split())


def load_json(path: str | Path, error_type: ErrorType = InputError) -> Any:
    """:func:`read_text` then :func:`parse_json`: a JSON file's value, or a one-line error."""
    return parse_json(read_text(path, error_type), Path(path), error_type)


def load_yaml(path: str | Path, error_type: ErrorType = InputError) -> Any:
    """:func:`read_text` then :func:`parse_yaml`: a YAML file's value, or a one-line error."""
    return parse_yaml(read_text(path, error_type), Path(path), error_type)


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
        msg = f"{where}, column {column!r} is not a number: {text!r}"
        raise error_type(msg) from None
    if finite and not math.isfinite(value):
        msg = f"{where}, column {column!r} is not finite: {text!r}"
        raise error_type(msg)
    return value
