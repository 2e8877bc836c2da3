"""Errors of the I/O layer."""

from __future__ import annotations

from sonarcarve.errors import SonarcarveError

__all__ = ["InputError"]


class InputError(SonarcarveError, ValueError):
    """A file that cannot be read as what it claims to be; the message names file and place."""
