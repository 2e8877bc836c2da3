"""The root of the library's errors: anything the CLI reports as a one-line message.

Each family of user-fixable problems has its own subclass, raised as
``msg = f"..."; raise SomeError(msg)``; all are also :class:`ValueError` where the problem is a
bad value, so callers that catch ``ValueError`` keep working.
"""

from __future__ import annotations

__all__ = ["ConfigError", "ReadingsError", "SonarcarveError"]


class SonarcarveError(Exception):
    """Base of every error caused by input the user can fix (files, names, parameters)."""


class ReadingsError(SonarcarveError, ValueError):
    """Readings that break the contract: bad values, missing columns, unsorted times."""


class ConfigError(SonarcarveError, ValueError):
    """A method parameter outside its valid range, or an unknown method name."""
