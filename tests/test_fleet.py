"""Fleets of logs: one map per log, the same maps on a Dask cluster as in this process, and a
bad log reported in the summary without stopping the others."""

from __future__ import annotations

import csv
import faulthandler
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from sonarcarve.fleet import FleetError, map_logs, map_name
from sonarcarve.io import write_readings_csv
from sonarcarve.io.errors import OutputError
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.runner import DaskRunner, RunnerSpec

TIME_LIMIT = 120


@pytest.fixture
def time_limit() -> Iterator[None]:
    faulthandler.dump_traceback_later(TIME_LIMIT, exit=True, file=sys.__stderr__)
    yield
    faulthandler.cancel_dump_traceback_later()


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    folder = tmp_path_factory.mktemp("logs")
    paths = []
    for seed in (0, 1, 2):
        path = folder / f"robot-{seed}.csv"
        write_readings_csv(run_simulation(Scenario("office", seed, max_length=4.0)).readings,
                           path)
        paths.append(path)
    bad = folder / "broken.csv"
    bad.write_text("t,sensor,x,y,theta,range\n0,0,0,0,0,oops\n")
    return [paths[0], bad, paths[1], paths[2]]


def _maps(folder: Path) -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted(folder.glob("*.map.csv"))}


def _summary(folder: Path) -> list[dict[str, str]]:
    with (folder / "summary.csv").open() as handle:
        return [{k: v for k, v in row.items() if k not in ("seconds", "map")}
                for row in csv.DictReader(handle)]


@pytest.fixture(scope="module")
def serial(logs: list[Path], tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("serial")
    rows = map_logs(logs, out, "carve")
    assert [row.ok for row in rows] == [True, False, True, True]
    return out


def test_each_log_gets_a_map_and_a_summary_line(logs: list[Path], serial: Path) -> None:
    assert sorted(_maps(serial)) == ["robot-0.map.csv", "robot-1.map.csv", "robot-2.map.csv"]
    summary = _summary(serial)
    assert [row["log"] for row in summary] == [str(p) for p in logs]
    broken = summary[1]
    assert broken["error"]
    assert "\n" not in broken["error"]
    # A failed log has empty measures, not zeros that read as data (UX review, finding 14).
    with (serial / "summary.csv").open() as handle:
        cells = list(csv.DictReader(handle))[1]
    assert {name: value for name, value in cells.items() if name not in ("log", "error")} == {
        "map": "", "readings": "", "points": "", "fully_carved": "", "split": "",
        "unprocessed": "", "seconds": "", "readings_filtered": "", "points_filtered": "",
        "no_echo_dropped": ""}
    assert int(summary[0]["points"]) > 0
    assert all(row["error"] == "" for i, row in enumerate(summary) if i != 1)


def test_a_cluster_fleet_equals_the_serial_one(
    logs: list[Path], serial: Path, tmp_path: Path, time_limit: None
) -> None:
    with DaskRunner(RunnerSpec(workers=2)) as runner:
        rows = map_logs(logs, tmp_path, "carve", runner=runner)
    assert [row.ok for row in rows] == [True, False, True, True]
    assert _maps(tmp_path) == _maps(serial)
    assert _summary(tmp_path) == _summary(serial)


def test_bad_requests_fail_before_mapping(logs: list[Path], tmp_path: Path) -> None:
    with pytest.raises(FleetError, match="no logs"):
        map_logs([], tmp_path)
    with pytest.raises(FleetError, match="both write"):
        map_logs([logs[0], replace_parent(logs[0], tmp_path)], tmp_path / "out")
    assert map_name("a/b.csv") == "b.map.csv"


def replace_parent(path: Path, folder: Path) -> Path:
    copy = folder / path.name
    copy.write_bytes(path.read_bytes())
    return copy


def test_unknown_method_fails_once(logs: list[Path], tmp_path: Path) -> None:
    from sonarcarve.errors import ConfigError

    with pytest.raises(ConfigError):
        map_logs(logs[:1], tmp_path, "nope")


def test_an_out_dir_that_cannot_be_made_names_the_parameter(tmp_path: Path) -> None:
    """map_logs is library: its error names out_dir, not the command's --out-dir (review
    finding 3); the command rewords it."""
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(OutputError) as caught:
        map_logs([tmp_path / "a.csv"], blocker / "maps", "carve")
    assert str(caught.value).startswith(f"out_dir {blocker / 'maps'}: ")


def test_a_folder_is_a_rosbag2_bag_and_a_csv_is_not(tmp_path: Path) -> None:
    from sonarcarve.fleet import is_bag

    folder = tmp_path / "rosbag2_2024_05_01"
    folder.mkdir()
    assert is_bag(folder)
    assert is_bag(tmp_path / "run.db3")
    assert not is_bag(tmp_path / "run.csv")
    assert map_name(folder) == "rosbag2_2024_05_01.map.csv"


def test_summary_measures_are_those_of_processing_the_log(logs: list[Path],
                                                           serial: Path) -> None:
    # The fleet maps each log "as sonarcarve process does": its row carries that run's
    # measures, the unprocessed share in percent.
    from sonarcarve.io import read_readings_csv
    from sonarcarve.methods import MethodConfig, make_method
    from sonarcarve.pipeline import process_readings

    batch = read_readings_csv(logs[0])
    result = process_readings(batch, make_method("carve", MethodConfig()))
    assert result.fully_carved != result.split  # a swap of the two would show
    row = _summary(serial)[0]
    data_lines = len(logs[0].read_text().splitlines()) - 1
    assert int(row["readings"]) == data_lines == result.readings
    assert int(row["points"]) == len(result.global_map)
    assert (int(row["fully_carved"]), int(row["split"])) == (result.fully_carved, result.split)
    assert float(row["unprocessed"]) == 100.0 * result.mean_unprocessed_share
    assert 1.0 < float(row["unprocessed"]) <= 100.0
    assert (row["readings_filtered"], row["points_filtered"]) == ("0", "0")  # no filter ran
    assert row["no_echo_dropped"] == "0"  # a readings CSV maps its no-echo rows


def test_summary_counts_what_the_filters_dropped(logs: list[Path], tmp_path: Path) -> None:
    # Counted here from the log and the unfiltered map, not from the filters' reports.
    import numpy as np

    from sonarcarve.filters import MapFilter, ReadingFilter
    from sonarcarve.io import read_readings_csv
    from sonarcarve.methods import MethodConfig, make_method
    from sonarcarve.pipeline import process_readings

    batch = read_readings_csv(logs[0])
    far = 2.0
    map_bound = 0.1
    rows = map_logs([logs[0]], tmp_path, "carve", reading_filter=ReadingFilter(max_range=far),
                    map_filter=MapFilter(max_error=map_bound))
    near = batch[batch.range <= far]
    unfiltered = process_readings(near, make_method("carve", MethodConfig())).global_map
    too_far = int(np.sum(batch.range > far))
    too_wide = int(np.sum(~(unfiltered.max_error <= map_bound)))
    assert too_far > 0
    assert too_wide > 0
    (row,) = _summary(tmp_path)
    assert (int(row["readings_filtered"]), int(row["points_filtered"])) == (too_far, too_wide)
    assert int(row["points"]) == len(unfiltered) - too_wide == rows[0].points


@pytest.mark.parametrize(("error", "reason"), [
    (ZeroDivisionError("float division by zero"), "ZeroDivisionError: float division by zero"),
    (RuntimeError(), "RuntimeError"),
    (OutputError("map.csv: disk full,\n  try again"), "map.csv: disk full, try again"),
])
def test_a_crash_on_one_log_is_one_line_naming_unexpected_errors(
        logs: list[Path], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        error: Exception, reason: str) -> None:
    from sonarcarve import fleet
    from sonarcarve.methods import MethodConfig

    def crash(*args: object, **kwargs: object) -> None:
        raise error

    monkeypatch.setattr(fleet, "process_readings", crash)
    row = fleet.map_log(str(logs[0]), str(tmp_path / "m.csv"), "carve", MethodConfig())
    assert (row.ok, row.error, row.map) == (False, reason, "")
    assert not (tmp_path / "m.csv").exists()
