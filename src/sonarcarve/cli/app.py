"""The typer application every command module registers on, and what the commands share.

- :data:`app`, :data:`console`, :data:`err_console`: where commands register and print.
- :func:`lazy_command`: list a command whose module is imported only when the command runs, so
  ``sonarcarve --help`` and each command load only what they use.
- :func:`summary_table`, :func:`progress`: the two-column result table and the progress bar
  every command prints.
- :func:`warn`: the one-line warnings of a command that still succeeds; :func:`cut_short`, the
  one for a log whose last line has no line end.
- :func:`flag_message`, :func:`reworded`: a library error, which names parameters, reworded to
  name the flags that set them.

The help screens are tidied here too (:class:`_Group`): usage lines show ``READINGS.csv`` rather
than typer's ``{readings}``, option rows show a metavar (``METRES``, ``NAME``) or click's plain
type names (``INTEGER``, ``FLOAT``) instead of ``<float>``/``<list[str]>``, flags show no type,
and float defaults print without trailing zeros (``20`` for 20.0). Every parameter refuses a
value ending in ``/`` that names an existing file (``--out map.csv/``): the path type would drop
the slash and the command would replace the file.
"""

from __future__ import annotations

import importlib
import re
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping
from contextlib import contextmanager
from functools import partial
from pathlib import Path
from typing import Any

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.table import Table
from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption

from sonarcarve.errors import SonarcarveError

__all__ = [
    "app",
    "console",
    "err_console",
    "flag_message",
    "lazy_command",
    "progress",
    "reworded",
    "summary_table",
    "warn",
]

#: Command name -> (module that registers it, the first paragraph of its help). Filled by
#: :func:`lazy_command` from ``sonarcarve/cli/main.py``.
LAZY_COMMANDS: dict[str, tuple[str, str]] = {}


def lazy_command(name: str, module: str, summary: str) -> None:
    """List command ``name``, registered by importing ``module`` when the command is run.

    ``summary`` is what ``sonarcarve --help`` shows for it without importing the module; it
    must be the first paragraph of the command's help (a test checks).
    """
    LAZY_COMMANDS[name] = (module, summary)


def _refuse_file_with_slash(param: Any, ctx: Any, value: Any) -> None:
    """Refuse ``out.csv/`` when ``out.csv`` is a file: the path type would drop the slash.

    pathlib turns ``out.csv/`` into ``out.csv``, so a command would read or replace the file
    the user wrote as a folder. A name ending in ``/`` must be a folder, or not exist yet.
    """
    for raw in value if isinstance(value, list | tuple) else [value]:
        if isinstance(raw, str) and raw.endswith("/") and raw.rstrip("/"):
            try:
                names_a_file = Path(raw).exists() and not Path(raw).is_dir()
            except OSError:
                names_a_file = False
            if names_a_file:
                msg = f"{raw!r} ends in '/' but {raw.rstrip('/')} is a file, not a folder"
                raise typer.BadParameter(msg, ctx=ctx, param=param)


class _Argument(TyperArgument):
    """An argument whose usage reads ``READINGS.csv`` / ``[FOLDER]``, with no type column."""

    def process_value(self, ctx: Any, value: Any) -> Any:
        _refuse_file_with_slash(self, ctx, value)
        return super().process_value(ctx, value)

    def _usage_display_name(self) -> str:
        name = self.display_name_raw if self.required else f"[{self.display_name_raw}]"
        return name + ("..." if self.nargs != 1 else "")

    def display_type_rich(self, ctx: Any) -> str | None:
        return None


#: Click's names for the plain types, shown for an option that has no metavar.
_TYPE_NAMES = {"int": "INTEGER", "float": "FLOAT", "str": "TEXT", "Path": "PATH"}


class _Option(TyperOption):
    """An option showing its metavar (or ``FLOAT``...), nothing for a flag, ``20`` for 20.0."""

    def process_value(self, ctx: Any, value: Any) -> Any:
        _refuse_file_with_slash(self, ctx, value)
        return super().process_value(ctx, value)

    def display_type_rich(self, ctx: Any) -> str | None:
        if self.metavar is not None:
            return self.metavar
        if self.is_flag or self.count:
            return None
        bare = self.bare_type().removeprefix("list[").removesuffix("]")
        return _TYPE_NAMES.get(bare, bare.upper())

    def _get_default_string(self, *, ctx: Any, show_default_is_str: bool,
                            default_value: Any) -> str:
        if isinstance(default_value, float) and not show_default_is_str:
            return f"{default_value:g}"
        return super()._get_default_string(ctx=ctx, show_default_is_str=show_default_is_str,
                                           default_value=default_value)


def _tidy_param(param: Any) -> None:
    # typer builds its own parameter classes and offers no hook to choose others; the
    # subclasses above change only how a parameter is displayed, never how it parses.
    if type(param) is TyperArgument:
        param.__class__ = _Argument
    elif type(param) is TyperOption:
        param.__class__ = _Option


#: Commands that run no compiled kernel, so need no word about compiling them (``warm``
#: compiles on purpose and says so itself).
_NO_KERNELS = frozenset({"warm", "worlds"})


class _Command(TyperCommand):
    """A command with tidied parameters (including the ``--help`` flag, made on demand), that
    says in one stderr line when it has to compile kernels (:mod:`.compile_notice`)."""

    def get_help_option(self, ctx: Any) -> Any:
        option = super().get_help_option(ctx)
        _tidy_param(option)
        return option

    def invoke(self, ctx: Any) -> Any:
        # Reached once the options are parsed (never for --help), right before the command.
        from sonarcarve.cli.compile_notice import announce_compiling, notice_enabled

        if self.name in _NO_KERNELS or not notice_enabled():
            return super().invoke(ctx)
        with announce_compiling():
            return super().invoke(ctx)


def _tidy_command(command: Any) -> Any:
    if type(command) is TyperCommand:
        command.__class__ = _Command
    for param in command.params:
        _tidy_param(param)
    return command


class _LazyCommand(TyperCommand):
    """Stands in for a command in ``sonarcarve --help`` until the command is run."""

    def __init__(self, name: str, module: str, summary: str, markup: Any) -> None:
        super().__init__(name, help=summary, rich_markup_mode=markup)
        self.module = module


class _Group(TyperGroup):
    """The root group: lists lazy commands, loads one when it runs, tidies every help screen."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        for param in self.params:
            _tidy_param(param)
        for command in self.commands.values():
            _tidy_command(command)
        for name, (module, summary) in LAZY_COMMANDS.items():
            if name not in self.commands:
                self.commands[name] = _LazyCommand(name, module, summary, self.rich_markup_mode)

    def get_help_option(self, ctx: Any) -> Any:
        option = super().get_help_option(ctx)
        _tidy_param(option)
        return option

    def list_commands(self, ctx: Any) -> list[str]:
        # The order of LAZY_COMMANDS, whether or not a module happens to be imported already.
        names = [name for name in LAZY_COMMANDS if name in self.commands]
        return names + [name for name in self.commands if name not in LAZY_COMMANDS]

    def resolve_command(self, ctx: Any, args: list[str]) -> tuple[str | None, Any, list[str]]:
        name, command, rest = super().resolve_command(ctx, args)
        if isinstance(command, _LazyCommand) and name is not None:
            command = self.commands[name] = _load(name, command.module)
        return name, command, rest


def _load(name: str, module: str) -> Any:
    """Import ``module`` and build the click command it registered as ``name``."""
    importlib.import_module(module)
    for info in app.registered_commands:
        callback_name = info.callback.__name__ if info.callback is not None else ""
        if (info.name or typer.main.get_command_name(callback_name)) == name:
            command = typer.main.get_command_from_info(
                info, pretty_exceptions_short=app.pretty_exceptions_short,
                rich_markup_mode=app.rich_markup_mode)
            return _tidy_command(command)
    msg = f"module {module} registers no command {name!r}"  # a bug, not a user error
    raise RuntimeError(msg)


app = typer.Typer(
    name="sonarcarve",
    cls=_Group,
    help=(
        "Accurate, low-latency maps from ultrasonic range sensors.\n\n"
        "Arc carving (Silver et al.) removes from each sonar arc the parts that newer readings "
        "prove to be free space, so the map point of an echo gets sharper with every reading "
        "instead of waiting for enough readings to intersect (ATM).\n\n"
        "Start with `sonarcarve demo`; map your own readings with `sonarcarve process`."
    ),
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode="markdown",
)

console = Console()
err_console = Console(stderr=True)


def summary_table(title: str, rows: Iterable[tuple[str, str]]) -> Table:
    """The two-column table a command prints when done: label (bold), value (right-aligned)."""
    table = Table(title=title, show_header=False)
    table.add_column(style="bold")
    table.add_column(justify="right")
    for label, value in rows:
        table.add_row(label, value)
    return table


def progress(*, label_width: int = 0, elapsed: bool = False) -> Progress:
    """A transient progress bar on :data:`console`: label, bar, done/total, time.

    Parameters
    ----------
    label_width : int
        Right-align task labels to this many characters (0: as they come), so the bars of
        several tasks line up.
    elapsed : bool
        Show the time elapsed instead of the time remaining (for runs of several stages, where
        one stage's rate says little about the rest).
    """
    label = f"{{task.description:>{label_width}}}" if label_width else "{task.description}"
    clock: ProgressColumn = TimeElapsedColumn() if elapsed else TimeRemainingColumn()
    return Progress(TextColumn(label), BarColumn(), MofNCompleteColumn(), clock,
                    console=console, transient=True)


#: Logs of at least this many readings get a progress bar where each reading costs
#: milliseconds (a bag or Rerun output: the office tour's 13,534 readings took 33 s to a bag).
SLOW_PROGRESS_MIN_READINGS = 2_000


@contextmanager
def readings_progress(label: str, total: int,
                      minimum: int = SLOW_PROGRESS_MIN_READINGS,
                      ) -> Iterator[Callable[[int], None] | None]:
    """A transient progress bar over ``total`` readings, as the callback to pass on (readings
    done so far); None, and no bar, for fewer than ``minimum`` readings."""
    if total < minimum:
        yield None
        return
    with progress() as bar:
        task = bar.add_task(label, total=total)
        yield lambda done: bar.update(task, completed=done)


def flag_message(message: str, flags: Mapping[str, str]) -> str:
    """A library error's ``message`` in the command line's words: every parameter name of
    ``flags`` (parameter -> flag) that it mentions as a word of its own (not inside
    ```code```, and not a folder or file name in a path: ``/data/out_dir/x.csv`` stays)
    replaced by its flag, and a leading ``"label: "`` dropped when a flag follows it (the
    command has one thing of that kind).

    Examples
    --------
    >>> flag_message("carved grid: resolution must be > 0 metres, got 0", {"resolution":
    ...              "--resolution"})
    '--resolution must be > 0 metres, got 0'
    >>> flag_message("arcs needs readings", {"arcs": "--arcs", "readings": "--readings"})
    '--arcs needs --readings'
    >>> flag_message("start one with `dask scheduler`, or give no scheduler",
    ...              {"scheduler": "--scheduler"})
    'start one with `dask scheduler`, or give no --scheduler'
    >>> flag_message("out_dir /data/out_dir: cannot write /data/out_dir/a.csv",
    ...              {"out_dir": "--out-dir"})
    '--out-dir /data/out_dir: cannot write /data/out_dir/a.csv'
    """
    def reword(text: str) -> str:
        for name, flag in flags.items():
            # Not next to a word character, a backquote, a hyphen or a path separator.
            text = re.sub(rf"(?<![\w`/\\-]){re.escape(name)}(?![\w`/\\-])", flag, text)
        return text

    _, sep, rest = message.partition(": ")
    if sep and rest.partition(" ")[0] in flags:
        return reword(rest)
    return reword(message)


@contextmanager
def reworded(errors: type[SonarcarveError] | tuple[type[SonarcarveError], ...],
             flags: Mapping[str, str]) -> Iterator[None]:
    """Re-raise ``errors`` raised in the block as the same class with :func:`flag_message`'s
    wording: the library names its parameters, the command its flags."""
    try:
        yield
    except errors as err:
        raise type(err)(flag_message(str(err), flags)) from None


def warn(lines: Iterable[str | None]) -> None:
    """Each line (None: skipped) as ``sonarcarve: warning: ...`` on stderr: a likely mistake
    that does not stop the command (not through rich, which would wrap a long line or read
    brackets as markup)."""
    for line in lines:
        if line is not None:
            print(f"sonarcarve: warning: {line}", file=sys.stderr)


def cut_short(path: Path) -> str | None:
    """A warning when a text log's last line, after its first, has no line end, else None.

    A logger killed mid-line leaves such a file, and a number cut short still parses
    (``3.7845`` as ``3.7``), so the reader cannot tell; every tool that writes CSV ends its
    last line. Costs one byte read unless the warning is due (then one pass to number the
    line); None for anything but a non-empty regular file that can be read.
    """
    try:
        if not path.is_file() or path.stat().st_size == 0:  # a pipe would block, or be eaten
            return None
        with path.open("rb") as handle:
            handle.seek(-1, 2)
            if handle.read(1) in (b"\n", b"\r"):
                return None
            handle.seek(0)
            feeds = returns = 0
            for block in iter(partial(handle.read, 1 << 20), b""):
                feeds += block.count(b"\n")
                returns += block.count(b"\r")
            line = 1 + (feeds or returns)  # a file with bare CR line ends counts its CRs
    except OSError:
        return None
    if line == 1:
        return None  # the header alone: no reading to cut (the empty map is warned of)
    return (f"{path}: line {line:,}, the last, has no line end: if the file was cut short, "
            "its last reading may be wrong (a number cut short still reads as a number)")


def _show_version(value: bool) -> None:
    if value:
        from sonarcarve._version import __version__  # not the package: nothing else to load

        console.print(f"sonarcarve {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_show_version, is_eager=True,
        help="Print the version and exit.",
    ),
) -> None:
    """Accurate, low-latency maps from ultrasonic range sensors."""
