"""The CLI shell: one-line usage errors, help screens, lazy command loading."""

from __future__ import annotations

import ast
import inspect
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import typer

from sonarcarve.cli import main
from sonarcarve.cli.app import LAZY_COMMANDS, app

COMMANDS = ("process", "simulate", "convert", "worlds", "demo", "experiments", "grid", "plot",
            "view", "sweep", "warm")


@pytest.fixture(autouse=True, scope="module")
def _commands_registered() -> None:
    """Every command registered on ``app``, as a first ``main()`` does, so that a test run on
    its own (``-k``) finds them too."""
    assert main(["--version"]) == 0


@pytest.mark.parametrize(("args", "words"), [
    (["process", "r.csv", "--out", "m.csv", "--bogus"], ["no such option", "--bogus"]),
    (["process", "r.csv"], ["missing option", "--out"]),
    (["process"], ["missing argument", "READINGS.csv"]),
    (["process", "r.csv", "--out", "m.csv", "--history", "abc"],
     ["invalid value for '--history'", "'abc' is not a whole number"]),
    (["process", "r.csv", "--out", "m.csv", "--beam-width", "wide"],
     ["invalid value for '--beam-width'", "'wide' is not a number"]),
    (["nocmd"], ["no such command 'nocmd'"]),
    (["proces"], ["no such command 'proces'", "did you mean 'process'"]),
    (["simulate", "--world", "doorway", "--out", "x.csv", "--odometry=yes"],
     ["--odometry", "does not take a value"]),
    (["experiments", "--out", "o", "--seeds"], ["--seeds", "requires an argument"]),
    # User review: one value given to an option of two, and the next option read as the second.
    (["simulate", "--world", "doorway", "--pose-noise", "0.05", "--out", "x.csv"],
     ["invalid value for '--pose-noise': '--out' is not a number (--pose-noise takes 2 values: "
      "METRES DEGREES)"]),
    (["simulate", "--world", "doorway", "--out", "x.csv", "--pose-noise", "0.05"],
     ["--pose-noise", "requires 2 arguments"]),
    # User review: "unknown method 'carving'" named no option (grid's --model did).
    (["process", "r.csv", "--out", "m.csv", "--method", "carving"],
     ["--method must be one of centerline | carve | atm | combined | evidence, got 'carving'"]),
    (["view", "r.csv", "--method", "carving"], ["--method must be one of", "got 'carving'"]),
])
def test_usage_errors_are_one_plain_line_exit_2(
    args: list[str], words: list[str], capsys: pytest.CaptureFixture[str],
    tmp_path: object, monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(str(tmp_path))
    assert main(args) == 2
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("sonarcarve: error: ")
    for word in words:
        assert word.lower() in lines[0].lower(), (word, lines[0])
    # No rich panel, no usage block, no traceback, nothing on stdout.
    assert not re.search(r"[╭╰│]|Usage:|Traceback", captured.err)
    assert captured.out == ""


def test_help_and_version_exit_0(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    for name in COMMANDS:
        assert name in text
    assert main(["--version"]) == 0
    from sonarcarve import __version__

    assert capsys.readouterr().out.strip() == f"sonarcarve {__version__}"


def test_no_arguments_prints_the_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 2  # a usage error, as click has it; but the whole help, not one line
    captured = capsys.readouterr()
    assert "Commands" in captured.out
    assert "process" in captured.out
    assert "Traceback" not in captured.err


@pytest.mark.parametrize("name", COMMANDS)
def test_help_screens_have_no_typer_type_noise(
    name: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([name, "--help"]) == 0
    text = capsys.readouterr().out
    usage = next(line for line in text.splitlines() if "Usage:" in line)
    assert "{" not in usage, usage
    for noise in ("<bool>", "<path>", "<str>", "<int>", "<float>", "<list["):
        assert noise not in text, (name, noise)
    # Float defaults without trailing zeros: "[default: 20]", not "[default: 20.0]".
    assert not re.search(r"\[default: -?\d+\.0\]", text), text


def test_process_help_states_units_and_the_unprocessed_measure(
    capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["process", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.replace("│", " ").split())
    assert "Usage: sonarcarve process [OPTIONS] READINGS.csv" in text
    for phrase in ("t in seconds", "metres", "radians counter-clockwise from +x",
                   "range in metres", "beam_width in radians", "used only for readings "
                   "without a beam_width value", "mean % of history rows",
                   "count as processed", "[default: 20]",
                   # UX review, finding 15: the optional column, inf rows, units, off.
                   "max_range in metres (optional", "inf for a reading that heard nothing",
                   "--min-transversal DEGREES", "--range-tolerance METRES",
                   "--max-incidence DEGREES", "--max-range METRES", "--max-error METRES"):
        assert phrase in text, phrase
    assert " FLOAT " not in text
    assert "--driven-through ROBOT|METRES" in text
    assert "--late-echo-period SECONDS|ROBOT" in text
    assert text.count("[default: (off)]") == 9  # β and the eight optional filters


def test_worlds_help_shows_one_example_per_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["worlds", "--help"]) == 0
    lines = capsys.readouterr().out.splitlines()
    examples = [line for line in lines if "sonarcarve worlds" in line and "Usage" not in line]
    assert len(examples) == 3
    # Each starts its own line (a list item), not the middle of a sentence.
    assert all(line.lstrip().startswith("•") for line in examples), examples


def test_the_root_help_summaries_are_the_commands_own() -> None:
    """What `sonarcarve --help` shows without importing a command is its help's first paragraph."""
    from sonarcarve.cli.app import _load

    assert set(LAZY_COMMANDS) == set(COMMANDS)
    for name, (module, summary) in LAZY_COMMANDS.items():
        command = _load(name, module)
        first = inspect.cleandoc(command.help or "").split("\n\n")[0].replace("\n", " ")
        assert summary == first, name


def test_root_help_imports_no_command_module() -> None:
    code = ("import sys\nfrom sonarcarve.cli import main\nassert main(['--help']) == 0\n"
            "print('LOADED', sorted(m for m in sys.modules if m.startswith('sonarcarve.cli.')))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    loaded = next(line for line in done.stdout.splitlines() if line.startswith("LOADED"))
    assert loaded == "LOADED ['sonarcarve.cli.app', 'sonarcarve.cli.main']"


def test_a_command_runs_through_typers_own_runner_too() -> None:
    from typer.testing import CliRunner

    result = CliRunner().invoke(app, ["worlds", "--help"])
    assert result.exit_code == 0
    assert "[WORLD]..." in result.output
    assert isinstance(typer.main.get_command(app), typer.core.TyperGroup)


# -- cold start ---------------------------------------------------------------------------------

SRC = Path(__file__).resolve().parents[2] / "src" / "sonarcarve"
#: What the CLI's shell (entry point, root group, --version, --help) may import: the standard
#: library, typer (with click) and rich, and these light modules of the package.
SHELL_MAY_IMPORT = {"sonarcarve.errors", "sonarcarve._version", "sonarcarve.cli",
                    "sonarcarve.cli.app", "sonarcarve.cli.main",
                    # imported by a command as it runs; it imports numba only then
                    "sonarcarve.cli.compile_notice"}


def _imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module is not None:
            names.add(node.module)
    return names


@pytest.mark.parametrize("module", ["_version.py", "cli/__init__.py", "cli/main.py", "cli/app.py"])
def test_the_cli_shell_imports_nothing_heavy(module: str) -> None:
    for name in _imports(SRC / module):
        top = name.split(".")[0]
        if top == "sonarcarve":
            assert name in SHELL_MAY_IMPORT, (module, name)
        else:
            assert top in sys.stdlib_module_names or top in {"typer", "rich", "yaml"}, name


def test_version_is_the_projects() -> None:
    import sonarcarve
    from sonarcarve._version import __version__

    project = tomllib.loads((SRC.parents[1] / "pyproject.toml").read_text(encoding="utf-8"))
    assert __version__ == project["project"]["version"]
    assert sonarcarve.__version__ == __version__


@pytest.mark.parametrize("args", [["--version"], ["--help"]])
def test_version_and_help_load_no_numerics(args: list[str]) -> None:
    code = (f"import sys\nfrom sonarcarve.cli import main\nassert main({args!r}) == 0\n"
            "heavy = sorted(m for m in ('numba', 'numpy', 'scipy', 'matplotlib') "
            "if m in sys.modules)\nprint('HEAVY', heavy)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert "HEAVY []" in done.stdout


def test_the_entry_point_stays_a_function_after_a_run() -> None:
    code = ("import sonarcarve.cli as cli\nassert cli.main(['--version']) == 0\n"
            "from sonarcarve.cli import main\nprint('CALLABLE', callable(main))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert "CALLABLE True" in done.stdout


def test_ctrl_c_exits_130_with_one_line_saying_nothing_was_written(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    # UX review, finding 16: rc 130 and a clean state, but not a word on stderr.
    import sonarcarve.cli.simulate as simulate_cli

    def interrupted(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(simulate_cli, "simulate", interrupted)
    out = tmp_path / "sim.csv"
    assert main(["simulate", "--world", "doorway", "--out", str(out)]) == 130
    assert capsys.readouterr().err == "sonarcarve: interrupted; nothing written\n"
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_in_a_real_process_prints_the_line(tmp_path: Path) -> None:
    import os
    import signal
    import time

    # The child first restores Python's Ctrl-C handler: a suite started as a shell's background
    # job inherits SIGINT ignored, and Python then installs none (a terminal's process has it).
    code = ("import signal, sys, time\nsignal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "from sonarcarve.cli import main\nimport sonarcarve.cli.simulate "
            "as s\ndef slow(*a, **k):\n    print('READY', flush=True)\n    time.sleep(60)\n"
            "s.simulate = slow\nsys.exit(main(sys.argv[1:]))")
    out = tmp_path / "sim.csv"
    with subprocess.Popen([sys.executable, "-c", code, "simulate", "--world", "doorway",
                           "--out", str(out)], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True) as proc:
        try:
            assert proc.stdout is not None
            assert proc.stdout.readline().strip() == "READY"
            time.sleep(0.2)
            os.kill(proc.pid, signal.SIGINT)
            _, err = proc.communicate(timeout=60)
        finally:
            proc.kill()  # never left running past the test, whatever failed
    assert proc.returncode == 130
    assert err == "sonarcarve: interrupted; nothing written\n"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("args", "said"), [
    (["sweep", "--out", "sw"], "the runs finished so far are kept: the same command resumes"),
    (["process", "a.csv", "b.csv", "--out-dir", "fl"], "the maps finished before are kept"),
    (["grid", "r.csv", "--out", "g.yaml"], "interrupted; nothing written"),
])
def test_the_interrupted_line_tells_what_each_command_kept(args: list[str], said: str) -> None:
    from sonarcarve.cli.main import interrupted_message

    assert said in interrupted_message(args)


def test_python_dash_m_runs_the_command_line() -> None:
    """``python -m sonarcarve`` is the ``sonarcarve`` script: same output, same exit codes."""
    done = subprocess.run([sys.executable, "-m", "sonarcarve", "--version"], capture_output=True,
                          text=True, check=False, timeout=120)
    assert done.returncode == 0, done.stderr
    from sonarcarve import __version__

    assert done.stdout.strip() == f"sonarcarve {__version__}"
    bad = subprocess.run([sys.executable, "-m", "sonarcarve", "worlds", "--nope"],
                         capture_output=True, text=True, check=False, timeout=120)
    assert bad.returncode == 2
    assert "Traceback" not in bad.stderr
