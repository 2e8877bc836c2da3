"""Command-line interface: a thin layer over library calls.

Each command lives in its own module and registers itself on :data:`app`. :func:`main` turns
every user-fixable error into one line on stderr and exit code 2, with no traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

import typer

from sonarcarve.cli import (
    convert,  # noqa: F401 - registers the command
    demo,  # noqa: F401 - registers the command
    experiments,  # noqa: F401 - registers the command
    process,  # noqa: F401 - registers the command
    simulate,  # noqa: F401 - registers the command
    worlds,  # noqa: F401 - registers the command
)
from sonarcarve.cli.app import app
from sonarcarve.errors import SonarcarveError

__all__ = ["app", "main"]

#: Exit code for bad input or usage, as click uses for usage errors.
EXIT_BAD_INPUT = 2


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI with ``argv`` (default: ``sys.argv[1:]``) and return the exit code.

    Usage errors are reported by typer (exit code 2); a :class:`SonarcarveError` from the library
    becomes one line on stderr and exit code 2; nothing prints a traceback for bad input.
    """
    command = typer.main.get_command(app)
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        command.main(args=args, prog_name="sonarcarve", standalone_mode=True)
    except SystemExit as done:
        return done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    except SonarcarveError as err:
        print(f"sonarcarve: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
