"""`process --method evidence --min-confidence P --stamp-error M --stamp-heading-error D`:
evidence carving's certainty per point (issue 9, part 5; the paper's section 6) from the
command line. The oracles are the map written with every point kept (`--min-confidence 0`),
filtered here with numpy, and each reading's range from the readings CSV."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.io import read_map_csv, read_readings_csv


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("certainty") / "doorway.csv"
    assert main(["simulate", "--world", "doorway", "--seed", "0", "--out", str(path)]) == 0
    return path


def _map(log: Path, out: Path, *options: str) -> Path:
    assert main(["process", str(log), "--method", "evidence", "--out", str(out),
                 *options]) == 0
    return out


def test_min_confidence_keeps_exactly_the_points_at_or_above_it(log: Path,
                                                                tmp_path: Path) -> None:
    every = read_map_csv(_map(log, tmp_path / "all.csv", "--min-confidence", "0"))
    assert every.confidence.min() < 0.5 < every.confidence.max()  # the cut has work to do
    for threshold, options in ((0.5, ()), (0.9, ("--min-confidence", "0.9"))):
        kept = read_map_csv(_map(log, tmp_path / f"{threshold}.csv", *options))
        expected = every.confidence >= threshold
        assert kept.reading_id.tolist() == every.reading_id[expected].tolist(), threshold
        np.testing.assert_array_equal(kept.xy, every.xy[expected])
        assert np.all(kept.confidence >= threshold)


def test_the_summary_counts_every_reading_as_a_point_or_removed(
        log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    capsys.readouterr()
    points = len(read_map_csv(_map(log, tmp_path / "m.csv", "--min-confidence", "0.9")))
    text = " ".join(capsys.readouterr().out.split())
    readings = len(read_readings_csv(log))
    assert f"removed (carved, low confidence) │ {readings - points:,}" in text
    assert "split (dropped)" not in text  # evidence carving keeps a piece of a split arc


def test_stamp_errors_widen_each_bound_by_the_origin_error_and_the_heading_chord(
        log: Path, tmp_path: Path) -> None:
    base = read_map_csv(_map(log, tmp_path / "base.csv"))
    wide = read_map_csv(_map(log, tmp_path / "wide.csv", "--stamp-error", "0.1",
                             "--stamp-heading-error", "2"))
    assert wide.reading_id.tolist() == base.reading_id.tolist()  # the bound, not the map
    ranges = read_readings_csv(log).range[base.reading_id]
    chord = 2.0 * ranges * math.sin(math.radians(1.0))  # 2 r sin(δ/2), δ = 2°
    np.testing.assert_allclose(wide.max_error, base.max_error + 0.1 + chord, atol=1e-12)


@pytest.mark.parametrize(("options", "message"), [
    (["--method", "carve", "--min-confidence", "0.8"],
     "--min-confidence applies to --method evidence only"),
    (["--stamp-error", "0.1", "--stamp-heading-error", "1"],
     "--stamp-error and --stamp-heading-error apply to --method evidence only"),
    (["--method", "evidence", "--min-confidence", "1.5"],
     "--min-confidence must lie in [0, 1], got 1.5"),
    (["--method", "evidence", "--stamp-error", "nan"],
     "--stamp-error must lie in [0, 10000] metres, got nan"),
    (["--method", "evidence", "--stamp-error", "1e300"],
     "--stamp-error must lie in [0, 10000] metres"),
    (["--method", "carve", "--min-confidence", "0.5", "--stamp-error", "0.1",
      "--stamp-heading-error", "1"],
     "--min-confidence, --stamp-error and --stamp-heading-error apply to --method evidence"),
    (["--method", "bogus", "--min-confidence", "0.5"], "--method must be one of"),
    (["--method", "evidence", "--stamp-heading-error", "-3"],
     "--stamp-heading-error must lie in [0, 90] degrees, got -3"),
])
def test_certainty_options_are_refused_in_one_line(
        log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], options: list[str],
        message: str) -> None:
    out = tmp_path / "never.csv"
    capsys.readouterr()
    assert main(["process", str(log), "--out", str(out), *options]) == 2
    err = capsys.readouterr().err
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_view_refuses_the_options_for_other_methods_in_one_line(
        log: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "never.rrd"
    capsys.readouterr()
    assert main(["view", str(log), "--out", str(out), "--method", "combined",
                 "--stamp-heading-error", "2"]) == 2
    err = capsys.readouterr().err
    assert "--stamp-heading-error applies to --method evidence only" in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_fleet_maps_each_log_with_the_options_as_one_log_is_mapped(log: Path,
                                                                     tmp_path: Path) -> None:
    options = ["--min-confidence", "0.9", "--stamp-error", "0.05"]
    alone = _map(log, tmp_path / "alone.csv", *options)
    fleet = tmp_path / "fleet"
    assert main(["process", str(log), "--out-dir", str(fleet), "--method", "evidence",
                 "--workers", "1", *options]) == 0
    assert (fleet / "doorway.map.csv").read_bytes() == alone.read_bytes()
    default = _map(log, tmp_path / "default.csv")
    assert default.read_bytes() != alone.read_bytes()  # the options reached the fleet
