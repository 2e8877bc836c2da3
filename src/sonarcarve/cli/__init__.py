"""Command-line interface: a thin layer over library calls (``sonarcarve --help``).

The commands need the ``cli`` extra (typer, rich, PyYAML). :func:`main` is the console entry
point; without the extra it says what to install, in one line, instead of a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence

__all__ = ["main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI with ``argv`` (default: ``sys.argv[1:]``); return the exit code."""
    try:
        import typer  # noqa: F401  (only to tell a missing extra apart)
        import yaml  # noqa: F401
        from rich import console  # noqa: F401
    except ModuleNotFoundError as err:
        print(f"sonarcarve: error: the command line needs {err.name}: "
              "pip install 'sonarcarve[cli]'", file=sys.stderr)
        return 2
    from sonarcarve.cli.main import main as run

    # Importing the submodule ``main`` rebinds this package's attribute ``main`` to it; put the
    # function back, so that ``from sonarcarve.cli import main`` gives it after a first run too.
    globals()["main"] = _MAIN
    return run(argv)


_MAIN = main


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
