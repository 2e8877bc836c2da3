"""``sonarcarve warm``: help, table, quiet line, cache location (steps stubbed: no compiling).

That warming really fills the cache is checked in ``tests/test_warm.py`` with subprocesses.
"""

from __future__ import annotations

import inspect
from pathlib import Path

import pytest

from sonarcarve.cli import main


@pytest.fixture
def stub_steps(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Two quick steps instead of the real ones (which compile for about a minute)."""
    calls: list[str] = []
    steps = [("method alpha", lambda: calls.append("alpha")),
             ("CSV beta", lambda: calls.append("beta"))]
    import sonarcarve.cli.warm as command

    monkeypatch.setattr(command, "warm_lanes", lambda: [steps[:1], steps[1:]])
    monkeypatch.setattr(command, "_demo_metrics", lambda: calls.append("demo"))
    # Stubs cannot cross into other processes: one job, as on a 1-core machine.
    monkeypatch.setattr(command, "default_jobs", lambda: 1)
    return calls


def test_help_says_what_it_is_for(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["warm", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.replace("│", " ").split())
    for phrase in ("Usage: sonarcarve warm [OPTIONS]", "first run", "several seconds",
                   "NUMBA_CACHE_DIR", "__pycache__", "--quiet", "--jobs", "one per core"):
        assert phrase in text, phrase


def test_the_table_lists_every_step_and_the_cache(
    stub_steps: list[str], capsys: pytest.CaptureFixture[str], tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert main(["warm"]) == 0
    out = capsys.readouterr().out
    assert stub_steps == ["alpha", "beta", "demo"]
    for word in ("method alpha", "CSV beta", "demo's truth metrics", "total",
                 "functions compiled", "seconds"):
        assert word in out, word
    assert str(tmp_path) in out.replace("\n", "")
    assert "Nothing needed compiling" in out  # the stubs compile nothing


def test_quiet_prints_one_line(
    stub_steps: list[str], capsys: pytest.CaptureFixture[str], tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert main(["warm", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert stub_steps == ["alpha", "beta", "demo"]
    assert out.startswith("sonarcarve warm: 0 functions compiled in ")
    assert str(tmp_path) in out.replace("\n", "")
    assert "method alpha" not in out


def test_without_numba_cache_dir_it_names_the_package_folders(
    stub_steps: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert main(["warm", "-q"]) == 0
    out = capsys.readouterr().out.replace("\n", "")
    assert "__pycache__" in out
    assert "sonarcarve" in out


def test_more_jobs_hand_the_lanes_to_that_many_processes(
    stub_steps: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
) -> None:
    import sonarcarve.cli.warm as command

    asked: list[dict[str, object]] = []

    def recording_warm_up(*args: object, **kwargs: object) -> list[tuple[str, float, int]]:
        asked.append(kwargs)
        return [("lane one", 1.0, 3), ("every step again in one process", 0.5, 0)]

    monkeypatch.setattr(command, "warm_up", recording_warm_up)
    assert main(["warm", "--jobs", "3"]) == 0
    assert asked == [{"lanes": command.command_lanes, "jobs": 3}]
    out = " ".join(capsys.readouterr().out.replace("│", " ").split())
    assert "total, 3 processes at once (wall time) 3" in out
    assert stub_steps == []  # nothing ran here: the processes run the lanes
    # 0 (the default) is one per core; -1 is refused before anything runs.
    monkeypatch.setattr(command, "default_jobs", lambda: 5)
    assert main(["warm", "-q"]) == 0
    assert asked[-1] == {"lanes": command.command_lanes, "jobs": 5}
    assert main(["warm", "--jobs", "-1"]) == 2
    assert len(asked) == 2


def test_the_command_warms_every_product_lane_and_the_demo_kernel() -> None:
    from sonarcarve.cli.warm import command_lanes
    from sonarcarve.warm import warm_lanes

    names = [[name for name, _ in lane] for lane in command_lanes()]
    assert names == [[name for name, _ in lane] for lane in warm_lanes()] + [
        ["demo's truth metrics"]]


def test_an_unknown_option_is_one_line_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["warm", "--fast"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sonarcarve: error: ")
    assert len(err.splitlines()) == 1


def test_the_command_is_listed_with_its_first_paragraph() -> None:
    import sonarcarve.cli.main  # noqa: F401  # lists the commands (lazy_command)
    from sonarcarve.cli.app import LAZY_COMMANDS, _load

    module, summary = LAZY_COMMANDS["warm"]
    command = _load("warm", module)
    assert inspect.cleandoc(command.help or "").split("\n\n")[0].replace("\n", " ") == summary


def test_a_cold_cache_says_it_is_compiling_once_and_a_warm_one_says_nothing(
        tmp_path: Path) -> None:
    # UX review, finding 1: 38 s for 167 readings on a cold cache, and not a word why.
    import os
    import subprocess
    import sys

    from sonarcarve.cli.compile_notice import COMPILE_NOTICE

    log = tmp_path / "tiny.csv"
    log.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,1\n0.1,1,0,0,1,1\n")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"),
           "SONARCARVE_COMPILE_NOTICE": "1"}
    code = "import sys\nfrom sonarcarve.cli import main\nsys.exit(main(sys.argv[1:]))"

    def run(out: str) -> str:
        done = subprocess.run([sys.executable, "-c", code, "process", str(log), "--method",
                               "centerline", "--out", str(tmp_path / out)],
                              capture_output=True, text=True, env=env, timeout=600, check=False)
        assert done.returncode == 0, done.stderr
        return done.stderr

    assert run("cold.map.csv") == COMPILE_NOTICE + "\n"
    assert run("warm.map.csv") == ""
    env["SONARCARVE_COMPILE_NOTICE"] = "0"
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "other-cache")
    assert run("off.map.csv") == ""
