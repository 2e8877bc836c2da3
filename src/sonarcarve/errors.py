"""The root of the library's errors: anything the CLI reports as a one-line message.

Each family of user-fixable problems has its own subclass, raised as
``msg = f"..."; raise SomeError(msg)``; all are also :class:`ValueError` where the problem is a
bad value, so callers that catch ``ValueError`` keep working. Every public error class is
re-exported from :mod:`sonarcarve` (``from sonarcarve import SonarcarveError``).

Two decisions about what counts as the user's error:

- **Wrong Python types** (a ``str`` or ``None`` range, a 6-tuple or a list given to ``add`` /
  ``add_many``, a string where a method is expected) are programmer errors, not bad data, but
  they are refused with a :class:`SonarcarveError` all the same: :class:`ReadingTypeError` is
  both a :class:`ReadingsError` and a :class:`TypeError`, so ``except TypeError`` and
  ``except SonarcarveError`` both catch it, and its message names the reading and the field
  (``reading 3, column 'range' must be a real number, got str 'abc'``). What is never raised
  for them is Python's own ``'<' not supported between ...``, which names no field.
- **A method used out of order** (``add`` after ``finish``, a sink set after readings were fed)
  raises :class:`MethodStateError`, a :class:`SonarcarveError` that is also a
  :class:`RuntimeError`, which these calls raised before (old ``except RuntimeError`` still
  works).
"""

from __future__ import annotations

__all__ = ["ConfigError", "MethodStateError", "ReadingTypeError", "ReadingsError",
           "SonarcarveError"]


class SonarcarveError(Exception):
    """Base of every error caused by input the user can fix (files, names, parameters)."""


class ReadingsError(SonarcarveError, ValueError):
    """Readings that break the contract: bad values, missing columns, unsorted times."""


class ReadingTypeError(ReadingsError, TypeError):
    """A reading (or batch) of the wrong Python type: a field that is no real number, a tuple
    of the wrong length, a list where a :class:`~sonarcarve.readings.ReadingBatch` is needed."""


class ConfigError(SonarcarveError, ValueError):
    """A method parameter outside its valid range, or an unknown method name."""


class MethodStateError(SonarcarveError, RuntimeError):
    """A method used out of order: fed after :meth:`finish`, given a sink after readings."""
