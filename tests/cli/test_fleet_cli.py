"""`sonarcarve process LOGS... --out-dir DIR`: one map per log, the same map `process --out`
writes for it; a bad log is one line in the summary, the others go on, and the exit code says."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from sonarcarve.cli import main

pytest.importorskip("rosbags")


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Two simulated CSVs, one simulated bag, one broken CSV."""
    folder = tmp_path_factory.mktemp("fleet-logs")
    made = []
    for name, seed in (("a.csv", "1"), ("b.csv", "2"), ("c.mcap", "3")):
        path = folder / name
        assert main(["simulate", "--world", "doorway", "--seed", seed, "--out", str(path)]) == 0
        made.append(path)
    broken = folder / "broken.csv"
    broken.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,oops\n")
    return [made[0], broken, made[1], made[2]]


def _summary(folder: Path) -> list[dict[str, str]]:
    with (folder / "summary.csv").open() as handle:
        return list(csv.DictReader(handle))


def test_each_log_gets_the_map_process_out_writes(
    logs: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch
) -> None:
    # Logs named relative to their folder: the printed table folds a long path over lines, and
    # how long pytest's temporary path is must not decide whether "broken.csv" reads whole.
    monkeypatch.chdir(logs[0].parent)
    logs = [Path(p.name) for p in logs]
    out = tmp_path / "maps"
    code = main(["process", *map(str, logs), "--out-dir", str(out), "--method", "carve",
                 "--workers", "1"])
    captured = capsys.readouterr()
    assert code == 2  # one log failed
    assert sorted(p.name for p in out.iterdir()) == ["a.map.csv", "b.map.csv", "c.map.csv",
                                                       "summary.csv"]
    for log in (logs[0], logs[2], logs[3]):  # the single-log command, an independent path
        alone = tmp_path / f"{log.stem}-alone.csv"
        assert main(["process", str(log), "--method", "carve", "--out", str(alone)]) == 0
        assert (out / f"{log.stem}.map.csv").read_bytes() == alone.read_bytes(), log
    rows = _summary(out)
    assert [row["log"] for row in rows] == [str(p) for p in logs]
    assert [bool(row["error"]) for row in rows] == [False, True, False, False]
    assert "oops" in rows[1]["error"]
    assert "\n" not in rows[1]["error"]
    assert int(rows[3]["points"]) > 0
    assert "broken.csv" in captured.out
    assert captured.err == ("sonarcarve: error: 1 of 4 logs failed; the summary gives each "
                            "one's reason\n")


def test_all_good_exits_0_and_a_cluster_gives_the_same_maps(
    logs: list[Path], tmp_path: Path
) -> None:
    good = [str(p) for i, p in enumerate(logs) if i != 1]
    serial, cluster = tmp_path / "serial", tmp_path / "cluster"
    assert main(["process", *good, "--out-dir", str(serial), "--workers", "1"]) == 0
    pytest.importorskip("distributed")
    assert main(["process", *good, "--out-dir", str(cluster), "--workers", "2"]) == 0
    for name in ("a.map.csv", "b.map.csv", "c.map.csv"):
        assert (cluster / name).read_bytes() == (serial / name).read_bytes(), name
    strip = [{k: v for k, v in row.items() if k not in ("seconds", "map")}
             for row in _summary(cluster)]
    assert strip == [{k: v for k, v in row.items() if k not in ("seconds", "map")}
                     for row in _summary(serial)]


@pytest.mark.parametrize(("extra", "words"), [
    (["--out", "m.csv"], "either --out (one log) or --out-dir"),
    (["--map-rate", "3"], "--map-rate applies to a bag output"),
    (["--workers", "0"], "--workers must be at least 1"),
    (["--method", "nope"], "--method must be one of"),
    (["--robot", "no-such-robot"], "unknown robot 'no-such-robot'"),
])
def test_bad_fleet_requests_fail_before_mapping(
    logs: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture[str],
    extra: list[str], words: str,
) -> None:
    out = tmp_path / "maps"
    assert main(["process", str(logs[0]), "--out-dir", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert words in err, err
    assert err.count("\n") == 1, err
    assert not out.exists()


def test_two_logs_with_one_map_name_are_refused(logs: list[Path], tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    twin = tmp_path / "a.csv"
    twin.write_bytes(logs[0].read_bytes())
    assert main(["process", str(logs[0]), str(twin), "--out-dir", str(tmp_path / "m"),
                 "--workers", "1"]) == 2
    assert "would both write a.map.csv" in capsys.readouterr().err


def test_the_summary_counts_each_bag_s_no_echo_readings_dropped(
    logs: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The bag's silent firings are dropped unless --no-echo maps them: the summary's last
    column says how many per log, the terminal once for all. The oracle: the inf rows
    `simulate --no-echo` writes for the bag's run (seed 3); a readings CSV drops none."""
    silent_csv = tmp_path / "silent.csv"
    assert main(["simulate", "--world", "doorway", "--seed", "3", "--no-echo",
                 "--out", str(silent_csv)]) == 0
    silent = sum(row.split(",")[5] == "inf" for row in silent_csv.read_text().splitlines()[1:])
    assert silent > 0
    good = [str(p) for i, p in enumerate(logs) if i != 1]
    capsys.readouterr()
    assert main(["process", *good, "--out-dir", str(tmp_path / "dropped"), "--workers", "1"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"dropped: {silent:,} no-echo readings of 1 bag (--no-echo" in text
    assert [row["no_echo_dropped"] for row in _summary(tmp_path / "dropped")] == [
        "0", "0", str(silent)]
    assert main(["process", *good, "--out-dir", str(tmp_path / "mapped"), "--workers", "1",
                 "--no-echo"]) == 0
    assert "no-echo readings of" not in capsys.readouterr().out
    assert [row["no_echo_dropped"] for row in _summary(tmp_path / "mapped")] == ["0", "0", "0"]
