"""``--max-range`` as the run-wide max range of a readings CSV's no-echo rows (design.md: a row
with range ``inf`` and no ``max_range`` heard nothing up to the run's ``--max-range``).

The oracle of every test is the same log written with an explicit ``max_range`` column: the
command must give the same bytes either way.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

import sonarcarve.cli.grid  # noqa: F401  # registers the command on the app
from sonarcarve.cli import main

#: Sensor 0 drives along +x hearing a wall 1.5 m to its left; sensor 1 then drives the same
#: stretch looking the same way and hears nothing: free space through the wall's arcs.
_ECHOES = [(0.1 * k, 0, 0.05 * k, math.pi / 2, "1.5") for k in range(20)]
_SILENT = [(2.0 + 0.1 * k, 1, 0.05 * k, math.pi / 2, "inf") for k in range(20)]
#: Two long echoes (6 m), beyond a --max-range of 3 m.
_FAR = [(4.0, 0, 0.5, math.pi / 2, "6.0"), (4.1, 0, 0.55, math.pi / 2, "6.0")]


def _csv(path: Path, rows: list[tuple[float, int, float, float, str]], *,
         column: float | None = None) -> Path:
    """The rows as a readings CSV; ``column``: a max_range column holding it on no-echo rows."""
    header = "t,sensor,x,y,theta,range" + (",max_range" if column is not None else "")
    lines = [header]
    for t, sensor, x, theta, r in rows:
        line = f"{t!r},{sensor},{x!r},0.0,{theta!r},{r}"
        if column is not None:
            line += f",{column!r}" if r == "inf" else ","
        lines.append(line)
    path.write_text("\n".join(lines) + "\n")
    return path


def _process(readings: Path, out: Path, *options: str) -> int:
    return main(["process", str(readings), "--method", "carve", "--out", str(out), *options])


def test_process_reads_no_echo_rows_up_to_max_range(tmp_path: Path) -> None:
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT)
    given = _csv(tmp_path / "given.csv", _ECHOES + _SILENT, column=3.0)
    assert _process(bare, tmp_path / "a.csv", "--max-range", "3") == 0
    assert _process(given, tmp_path / "b.csv", "--max-range", "3") == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    # The silent beams carved the wall's arcs: fewer points than from the echoes alone.
    echoes = _csv(tmp_path / "echoes.csv", _ECHOES)
    assert _process(echoes, tmp_path / "c.csv") == 0
    lines = [len(p.read_text().splitlines()) for p in (tmp_path / "a.csv", tmp_path / "c.csv")]
    assert lines[0] < lines[1]


def test_rows_that_give_a_max_range_keep_theirs(tmp_path: Path) -> None:
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT)
    longer = _csv(tmp_path / "longer.csv", _ECHOES + _SILENT, column=1.6)
    shorter = _csv(tmp_path / "shorter.csv", _ECHOES + _SILENT, column=1.0)
    for log, out in ((bare, "a.csv"), (longer, "b.csv"), (shorter, "c.csv")):
        assert _process(log, tmp_path / out, "--max-range", "1.6") == 0
    a, b, c = ((tmp_path / n).read_text() for n in ("a.csv", "b.csv", "c.csv"))
    assert a == b
    # Silence up to 1.0 m ends before the wall (1.5 m, less ε): it carves nothing there.
    assert len(c.splitlines()) > len(a.splitlines())


def test_without_max_range_the_error_says_how_to_give_one(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT)
    view = (["view", str(bare), "--no-open", "--out", str(tmp_path / "v.rrd")]
            if importlib.util.find_spec("rerun") is not None else [])
    for args in (["process", str(bare), "--out", str(tmp_path / "m.csv")],
                 ["grid", str(bare), "--out", str(tmp_path / "g.yaml")], *([view] if view else [])):
        assert main(args) == 2
        err = capsys.readouterr().err.strip()
        assert err == (f"sonarcarve: error: {bare}: line 22, column 'range' is infinite but "
                       "'max_range' is not given (add a max_range column, or give the "
                       "sensors' max range with --max-range)")
    assert not (tmp_path / "m.csv").exists()


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "20000"])
@pytest.mark.parametrize("command", ["process", "grid", "view", "plot"])
def test_an_absurd_max_range_is_refused_before_reading(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], command: str, value: str) -> None:
    import sonarcarve.cli.plot  # registers the commands
    import sonarcarve.cli.view  # noqa: F401

    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT)
    out = tmp_path / {"process": "m.csv", "grid": "g.yaml", "view": "v.rrd", "plot": "p.png"}[
        command]
    if command == "plot":  # plot's argument is a map (its readings come with --readings)
        _process(bare, tmp_path / "map.csv", "--max-range", "3")
        bare = tmp_path / "map.csv"
    assert main([command, str(bare), "--max-range", value, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sonarcarve: error: --max-range must be a finite number > 0")
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_max_range_takes_up_to_the_readings_limit() -> None:
    """10,000 m is what a readings CSV accepts as a row's max_range: the option's limit too."""
    from sonarcarve.cli.options import MaxRangeError, check_max_range

    assert check_max_range(10_000.0) == 10_000.0
    assert check_max_range(None) is None
    with pytest.raises(MaxRangeError):
        check_max_range(10_000.5)


def test_grid_takes_max_range_as_process_does(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT + _FAR)
    given = _csv(tmp_path / "given.csv", _ECHOES + _SILENT, column=3.0)  # the far rows left out
    args = ["--resolution", "0.1"]
    assert main(["grid", str(bare), "--max-range", "3", "--out", str(tmp_path / "a.yaml"),
                 *args]) == 0
    assert "dropped: echoes beyond --max-range │ 2" in " ".join(capsys.readouterr().out.split())
    assert main(["grid", str(given), "--out", str(tmp_path / "b.yaml"), *args]) == 0
    assert (tmp_path / "a.pgm").read_bytes() == (tmp_path / "b.pgm").read_bytes()
    a, b = ((tmp_path / n).read_text().replace(f"{n[0]}.pgm", "") for n in ("a.yaml", "b.yaml"))
    assert a == b
    # And the silent rows made a difference: the echoes alone give another image.
    echoes = _csv(tmp_path / "echoes.csv", _ECHOES)
    assert main(["grid", str(echoes), "--out", str(tmp_path / "c.yaml"), *args]) == 0
    assert (tmp_path / "c.pgm").read_bytes() != (tmp_path / "a.pgm").read_bytes()


def test_a_fleet_reads_no_echo_rows_up_to_max_range(tmp_path: Path) -> None:
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT)
    assert main(["process", str(bare), "--method", "carve", "--out-dir", str(tmp_path / "maps"),
                 "--max-range", "3", "--workers", "1"]) == 0
    assert _process(bare, tmp_path / "single.csv", "--max-range", "3") == 0
    assert ((tmp_path / "maps" / "bare.map.csv").read_bytes()
            == (tmp_path / "single.csv").read_bytes())


def test_a_bag_or_recording_output_takes_max_range(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The map CSV output with the same --max-range is the oracle of the recording's points;
    the other filters stay refused for these outputs."""
    pytest.importorskip("rerun")
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT + _FAR)
    assert _process(bare, tmp_path / "map.csv", "--max-range", "3") == 0
    capsys.readouterr()
    map_points = len((tmp_path / "map.csv").read_text().splitlines()) - 1
    assert _process(bare, tmp_path / "run.rrd", "--max-range", "3") == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "readings in │ 42" in text
    assert "dropped: echoes beyond --max-range │ 2" in text
    assert f"points out │ {map_points:,}" in text
    assert _process(bare, tmp_path / "run.mcap", "--max-range", "3") == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "readings in │ 42" in text
    assert "dropped: echoes beyond --max-range │ 2" in text
    assert _process(bare, tmp_path / "bad.mcap", "--max-range", "3", "--min-range", "0.1") == 2
    assert "--max-range applies to every output" in capsys.readouterr().err
    assert not (tmp_path / "bad.mcap").exists()


def test_a_bags_arc_markers_keep_the_input_rows_as_ids(tmp_path: Path) -> None:
    """An echo dropped mid-log: the markers' ids are the map CSV's (rows of the input)."""
    from rosbags.highlevel import AnyReader

    from sonarcarve.io.bag_out import ARCS_TOPIC

    far = [(0.95, 0, 0.5, math.pi / 2, "6.0")]
    log = _csv(tmp_path / "log.csv", _ECHOES[:10] + far + _ECHOES[10:])
    args = ["--method", "centerline", "--max-range", "3"]
    assert main(["process", str(log), "--out", str(tmp_path / "map.csv"), *args]) == 0
    assert main(["process", str(log), "--out", str(tmp_path / "run.mcap"), *args]) == 0
    map_ids = [int(line.split(",")[0])
               for line in (tmp_path / "map.csv").read_text().splitlines()[1:]]
    assert 10 not in map_ids
    assert max(map_ids) == 20
    with AnyReader([tmp_path / "run.mcap"]) as reader:
        arrays = [reader.deserialize(raw, conn.msgtype)
                  for conn, _, raw in reader.messages()
                  if conn.topic == ARCS_TOPIC]
    assert sorted(m.id for m in arrays[-1].markers[1:]) == sorted(map_ids)


def test_plot_reads_the_no_echo_rows_with_max_range(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("matplotlib")
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT + _FAR)
    assert _process(bare, tmp_path / "map.csv", "--max-range", "3") == 0
    plot = ["plot", str(tmp_path / "map.csv"), "--readings", str(bare), "--arcs"]
    assert main([*plot, "--out", str(tmp_path / "a.png")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.endswith("give the sensors' max range with --max-range)\n"), err
    assert not (tmp_path / "a.png").exists()
    assert main([*plot, "--max-range", "3", "--out", str(tmp_path / "b.png")]) == 0
    assert (tmp_path / "b.png").read_bytes()[:4] == b"\x89PNG"
    # Without --readings the option has nothing to act on: said, not ignored.
    assert main(["plot", str(tmp_path / "map.csv"), "--max-range", "3", "--out",
                 str(tmp_path / "c.png")]) == 2
    assert "give --readings too" in capsys.readouterr().err
    assert not (tmp_path / "c.png").exists()


def test_a_fleet_names_how_to_give_a_max_range(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT)
    assert main(["process", str(bare), "--method", "carve", "--out-dir", str(tmp_path / "maps"),
                 "--workers", "1"]) != 0
    text = " ".join(capsys.readouterr().out.split())
    assert "give the run's max range: --max-range" in text.replace("│ ", "")
    summary = (tmp_path / "maps" / "summary.csv").read_text()
    assert "'max_range' is not given (add a max_range column, or give the run's max range: " \
           "--max-range, or ReadingFilter(max_range=...) in Python)" in summary


def test_view_takes_max_range(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                              capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("rerun")
    import sonarcarve.cli.view  # noqa: F401  # registers the command

    monkeypatch.delenv("DISPLAY", raising=False)
    bare = _csv(tmp_path / "bare.csv", _ECHOES + _SILENT + _FAR)
    assert main(["view", str(bare), "--max-range", "3", "--no-open", "--method", "carve",
                 "--out", str(tmp_path / "run.rrd")]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "dropped: echoes beyond --max-range │ 2" in text
    assert "readings in │ 42" in text  # every row read, as process counts them
    assert (tmp_path / "run.rrd").stat().st_size > 0
