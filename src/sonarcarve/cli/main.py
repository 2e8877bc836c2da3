"""Command-line interface: a thin layer over library calls.

Each command lives in its own module and registers itself on :data:`app`; the list below names
the module and the command's one-line summary, and the module is imported only when its command
runs (``sonarcarve --help`` imports none of them). :func:`main` turns every user-fixable error,
a usage error or a :class:`~sonarcarve.errors.SonarcarveError`, into one line on stderr and
exit code 2, with no traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import Any

import typer
from typer._click.exceptions import ClickException, NoArgsIsHelpError
from typer.exceptions import Abort

from sonarcarve.cli.app import app, lazy_command
from sonarcarve.errors import SonarcarveError

__all__ = ["app", "main"]

#: Exit code for bad input or usage, as click uses for usage errors.
EXIT_BAD_INPUT = 2

#: Exit code after Ctrl-C (128 + SIGINT), as a shell reports a process killed by it; typer
#: turns the KeyboardInterrupt into this code.
EXIT_INTERRUPTED = 130

#: What an interrupted command leaves behind, said in one line on stderr. Every output is
#: written atomically (a temporary file renamed when complete), so no file is ever
#: half-written; the commands with many outputs keep those finished before Ctrl-C.
_KEPT_WHEN_INTERRUPTED = {
    "sweep": "interrupted; the runs finished so far are kept: the same command resumes",
    "experiments": "interrupted; no file half-written (files finished before are kept)",
    "demo": "interrupted; no file half-written (files finished before are kept)",
    "warm": "interrupted; the kernels compiled so far stay cached",
}

# One line per command: name, module, and the first paragraph of its help.
lazy_command("demo", "sonarcarve.cli.demo",
             "Simulate a robot touring a building, map its sonar readings with every method, "
             "and compare the maps with the true walls.")
lazy_command("simulate", "sonarcarve.cli.simulate",
             "Simulate a sonar log with ground truth: drive a robot through a world, record "
             "echoes.")
lazy_command("process", "sonarcarve.cli.process",
             "Map a readings CSV or a ROS bag with one method and write its global map to --out.")
lazy_command("convert", "sonarcarve.cli.convert",
             "Convert a data set's files into the readings CSV "
             "(t,sensor,x,y,theta,range,beam_width).")
lazy_command("worlds", "sonarcarve.cli.worlds",
             "List the simulator's worlds: size, walls, area, gaps (doors, openings), tour "
             "length.")
lazy_command("grid", "sonarcarve.cli.grid",
             "Map a readings CSV or a ROS bag into an occupancy grid, written as a ROS "
             "map_server map.")
lazy_command("plot", "sonarcarve.cli.plot",
             "Draw a map CSV to a figure: points coloured by source, the robot's path, a grid "
             "map.")
lazy_command("view", "sonarcarve.cli.view",
             "Record a run for the Rerun viewer: robot path, each reading's arc, the map "
             "growing.")
lazy_command("sweep", "sonarcarve.cli.sweep",
             "Sweep method and simulation parameters over worlds and seeds: one tidy table "
             "(runs.csv, one row per run, every parameter and measure) and a figure of each "
             "measure against each parameter.")
lazy_command("experiments", "sonarcarve.cli.experiments",
             "Regenerate the paper's experiments (section 5) on the simulator, plus what the "
             "paper could not measure without ground truth.")
lazy_command("warm", "sonarcarve.cli.warm",
             "Compile every method's kernels now, so that their first run needs no compiling.")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI with ``argv`` (default: ``sys.argv[1:]``) and return the exit code.

    A usage error (unknown command or option, missing or malformed value) and a
    :class:`SonarcarveError` from the library both become one line ``sonarcarve: error: ...``
    on stderr and exit code 2; nothing prints a traceback for bad input. ``--help`` and
    ``--version`` exit 0; ``sonarcarve`` alone prints the help and exits 2. Ctrl-C exits 130
    with one line saying what was kept (:func:`interrupted_message`).
    """
    command = typer.main.get_command(app)
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        result = command.main(args=args, prog_name="sonarcarve", standalone_mode=False)
    except KeyboardInterrupt:  # outside the command (typer turns one inside it into 130)
        result = EXIT_INTERRUPTED
    except NoArgsIsHelpError:
        return EXIT_BAD_INPUT  # the help is already printed
    except ClickException as err:
        _error(usage_message(err))
        return EXIT_BAD_INPUT
    except SonarcarveError as err:
        _error(str(err))
        return EXIT_BAD_INPUT
    except Abort:
        _error("aborted")
        return 1
    except SystemExit as done:  # a broken pipe, as click handles it
        return done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
    if result == EXIT_INTERRUPTED:
        print(f"sonarcarve: {interrupted_message(args)}", file=sys.stderr)
    return result if isinstance(result, int) else 0


def interrupted_message(args: Sequence[str]) -> str:
    """What Ctrl-C left behind, for the command line ``args`` (see _KEPT_WHEN_INTERRUPTED)."""
    name = next((arg for arg in args if not arg.startswith("-")), "")
    if name == "process" and any(arg == "--out-dir" or arg.startswith("--out-dir=")
                                 for arg in args):
        return "interrupted; no map half-written (the maps finished before are kept)"
    return _KEPT_WHEN_INTERRUPTED.get(name, "interrupted; nothing written")


def usage_message(err: ClickException) -> str:
    """Click's message for ``err`` in plain words on one line, without the final full stop.

    Typer validates values with pydantic, whose message for ``--history abc`` is "Input should
    be a valid integer, unable to parse string as an integer"; the common cases are reworded
    as "'abc' is not a whole number".
    """
    message = err.format_message()
    cause = err.__cause__
    errors = getattr(cause, "errors", None)
    hint = _hint(err)
    if callable(errors) and hint:
        details: list[dict[str, Any]] = errors()
        plain = _plain_words(details[0]) if details else None
        if plain is not None:
            message = f"invalid value for {hint}: {plain}"
    message = " ".join(message.split()).rstrip(".") + _values_taken(err)
    return message[:1].lower() + message[1:] if message[1:2].islower() else message


def _hint(err: ClickException) -> str | None:
    given = getattr(err, "param_hint", None)
    if isinstance(given, str):
        return given
    param = getattr(err, "param", None)
    return str(param.get_error_hint()) if param is not None else None


def _values_taken(err: ClickException) -> str:
    """For an option of several values (``--pose-noise METRES DEGREES``), how many it takes:
    given one, the next option is read as its second value, and the message names only that
    (`'--out' is not a number`)."""
    param = getattr(err, "param", None)
    nargs = getattr(param, "nargs", 1)
    if not isinstance(nargs, int) or nargs < 2:
        return ""
    name = max(getattr(param, "opts", None) or [str(_hint(err))], key=len)
    metavar = getattr(param, "metavar", None)
    return f" ({name} takes {nargs} values" + (f": {metavar})" if metavar else ")")


_PLAIN = {
    "int_parsing": "is not a whole number",
    "int_from_float": "is not a whole number",
    "float_parsing": "is not a number",
    "bool_parsing": "is not true or false",
}


def _plain_words(detail: dict[str, Any]) -> str | None:
    problem = _PLAIN.get(str(detail.get("type")))
    if problem is None or "input" not in detail:
        return None
    return f"{detail['input']!r} {problem}"


#: Longest error line printed, characters: a message quoting a 100 kB header stays readable.
MAX_MESSAGE_CHARS = 300


def _error(message: str) -> None:
    # One physical line, whatever the message holds, cut in the middle if it quotes too much.
    line = " ".join(message.splitlines())
    if len(line) > MAX_MESSAGE_CHARS:
        keep = MAX_MESSAGE_CHARS - 5
        line = f"{line[:keep - keep // 3]} ... {line[len(line) - keep // 3:]}"
    print(f"sonarcarve: error: {line}", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
