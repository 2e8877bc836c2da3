import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.io import InputError, bundled_robond_dir, read_robond
from sonarcarve.io.sanity import likely_mistakes

# Lines 46-51 of the real log (poses.txt and measurement.txt), unchanged.
POSES = """1697168 0 0 0
1697377 0 0 0
1697590 10 0 3600
1697802 33 0 0
1698013 71 0 0
1698233 122 0 1
"""
MEASUREMENTS = """1697168 5110 5110 2320 2360 5110 5110 2160 1180
1697377 5110 5110 2320 2360 5110 5110 2170 1190
1697590 5110 5110 2310 2360 5110 5110 2170 1190
1697802 5110 5110 2310 2360 5110 5110 2150 1180
1698013 5110 5110 2290 2310 5060 5110 2150 1180
1698233 5110 5110 2290 2310 5060 5110 2100 1190
"""
BEARINGS_DEG = [-90, -37.5, -22.5, -7.5, 7.5, 22.5, 37.5, 90]


def _write(folder: Path, poses: str = POSES, measurements: str = MEASUREMENTS) -> Path:
    folder.mkdir(exist_ok=True)
    (folder / "poses.txt").write_text(poses)
    (folder / "measurement.txt").write_text(measurements)
    return folder


def test_cut_from_the_real_log_by_hand(tmp_path: Path) -> None:
    log = read_robond(_write(tmp_path / "log"))
    # Worked by hand, (record, sensor) of each kept echo:
    # r0 first record: s2 s3 s6 s7.  r1 robot still: s2 s3 repeat (duplicates), s6 s7 new.
    # r2 moved: s2 new; s3 s6 s7 stale.  r3 moved: s2 s3 stale; s6 s7 new.
    # r4 moved: s2 s3 s4 new; s6 s7 stale.  r5 moved: s2 s3 s4 stale; s6 s7 new.
    expected = [(0, 2), (0, 3), (0, 6), (0, 7), (1, 6), (1, 7), (2, 2), (3, 6), (3, 7),
                (4, 2), (4, 3), (4, 4), (5, 6), (5, 7)]
    assert list(zip(log.record.tolist(), log.batch.sensor.tolist(), strict=True)) == expected
    r = log.report
    assert (r.records, r.values, r.no_echo) == (6, 48, 4 + 4 + 4 + 4 + 3 + 3)
    # Repeats while moving, no-echo included: r2 7, r3 6, r4 5, r5 6.
    assert (r.repeats, r.stale, r.duplicates, r.readings) == (24, 10, 2, 14)
    # r2 s2: t 1697590 ms, robot at (10 mm, 0), heading 3600 tenths = 360°, range 2310 mm.
    reading = log.batch[6]
    assert reading.t == pytest.approx(1697.590)
    assert (reading.x, reading.y, reading.range) == pytest.approx((0.010, 0.0, 2.310))
    assert math.cos(reading.theta - math.radians(-22.5)) == pytest.approx(1.0)
    assert reading.beam_width == pytest.approx(math.radians(20))
    # r5 s6: heading 1 tenth of a degree plus the 37.5° bearing.
    last = log.batch[12]
    assert last.theta == pytest.approx(math.radians(0.1 + BEARINGS_DEG[6]))
    assert last.range == pytest.approx(2.100)


def test_duplicates_can_be_kept(tmp_path: Path) -> None:
    log = read_robond(_write(tmp_path / "log"), keep_duplicates=True)
    assert log.report.readings == 16
    assert (1, 2) in zip(log.record.tolist(), log.batch.sensor.tolist(), strict=True)


def _independent_counts(folder: Path) -> tuple[int, int, int]:
    """Records, repeats-while-moving and no-echo values, counted with plain Python."""
    poses = [line.split() for line in (folder / "poses.txt").read_text().splitlines()]
    meas = [line.split() for line in (folder / "measurement.txt").read_text().splitlines()]
    repeats = 0
    for k in range(1, len(meas)):
        moved = poses[k][1:] != poses[k - 1][1:]
        repeats += sum(1 for a, b in zip(meas[k][1:], meas[k - 1][1:], strict=True)
                       if moved and a == b)
    no_echo = sum(1 for row in meas for v in row[1:] if v == "5110")
    return len(meas), repeats, no_echo


def test_bundled_copy_matches_the_readme() -> None:
    folder = bundled_robond_dir()
    assert {p.name for p in folder.iterdir()} >= {
        "README.md", "LICENSE", "poses.txt", "measurement.txt", "reference-grid-map.png"}
    records, repeats, no_echo = _independent_counts(folder)
    assert (records, repeats) == (413, 1877)  # the data README's numbers
    log = read_robond()
    r = log.report
    assert (r.records, r.values, r.repeats, r.no_echo) == (records, 8 * records, repeats, no_echo)
    assert r.readings == r.values - r.no_echo - r.stale - r.duplicates == len(log.batch)
    assert np.all(log.batch.range <= 5.110)
    # About 93 s and 25 m of path (README).
    assert log.batch.t[-1] - log.batch.t[0] == pytest.approx(93, abs=2)


def test_headings_past_a_full_turn_are_wrapped(tmp_path: Path) -> None:
    # Heading 359.9° (3599 tenths) plus sensor 7's 90° bearing is 449.9°, the same axis as
    # 89.9°; the readings CSV is radians, and an axis past ±2π reads as a unit mistake there.
    poses = "1000 0 0 3599\n1200 100 0 1\n"
    measurements = "1000 5110 5110 5110 5110 5110 5110 5110 1180\n" \
                   "1200 900 5110 5110 5110 5110 5110 5110 1190\n"
    log = read_robond(_write(tmp_path / "log", poses, measurements))
    assert log.batch.theta.tolist() == pytest.approx([math.radians(89.9), math.radians(-89.9),
                                                      math.radians(90.1)])


def test_bundled_log_reads_as_radians() -> None:
    batch = read_robond().batch
    assert np.all(np.abs(batch.theta) <= math.pi)
    assert likely_mistakes(batch) == []  # no "is it in degrees?" on our own conversion


def _broken(tmp_path: Path) -> list[tuple[Path, str]]:
    pose_lines = POSES.splitlines(keepends=True)
    meas_lines = MEASUREMENTS.splitlines(keepends=True)
    cases = {
        "columns": ("".join([*pose_lines[:2], "1697590 10 0\n", *pose_lines[3:]]), MEASUREMENTS,
                    "poses.txt: line 3, expected 4 columns (t x y theta), found 3"),
        "text": (POSES, "".join([*meas_lines[:4], meas_lines[4].replace("2290", "abc"),
                                 *meas_lines[5:]]),
                 "measurement.txt: line 5, column 'r2' is not a number: 'abc'"),
        "mismatch": (POSES, MEASUREMENTS.replace("1697802", "1697803"),
                     "measurement.txt: line 4, time 1697803 ms does not match poses.txt line 4 "
                     "(1697802 ms)"),
        "backwards": ("".join([pose_lines[0], pose_lines[2], pose_lines[1], *pose_lines[3:]]),
                      MEASUREMENTS,
                      "poses.txt: line 3, time 1697377 ms is not after the previous line's "
                      "1697590 ms"),
        "short": (POSES, "".join(meas_lines[:5]),
                  "measurement.txt: line 6, file ends after 5 records but poses.txt has 6"),
        "zero": (POSES, MEASUREMENTS.replace("1180\n1697377", "0\n1697377"),
                 "measurement.txt: line 1, column 'r7' must be > 0 mm, got 0"),
        "nan": (POSES.replace("33 0 0", "nan 0 0"), MEASUREMENTS,
                "poses.txt: line 4, column 'x' is not finite"),
        "empty": ("", MEASUREMENTS, "poses.txt: empty file"),
    }
    out = []
    for name, (poses, meas, text) in cases.items():
        out.append((_write(tmp_path / name, poses, meas), text))
    missing = tmp_path / "missing"
    missing.mkdir()
    (missing / "poses.txt").write_text(POSES)
    out.append((missing, "measurement.txt: no such file"))
    return out


def test_malformed_files_give_one_line_errors(tmp_path: Path) -> None:
    for folder, text in _broken(tmp_path):
        with pytest.raises(InputError) as err:
            read_robond(folder)
        message = str(err.value)
        assert text in message, (folder.name, message)
        assert "\n" not in message
        assert str(folder) in message  # names the file with its folder
