"""The root of the library's errors: anything the CLI reports as a one-line message."""

from __future__ import annotations

__all__ = ["SonarcarveError"]


class SonarcarveError(Exception):
    """Base of every error caused by input the user can fix (files, names, parameters)."""
