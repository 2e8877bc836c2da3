# noqa: N999 - the module is named after the data set (roboND-sonar-8), as the CLI name
"""The roboND-sonar-8 log: a real 8-sensor sonar recording (bundled in ``sonarcarve/data``).

Two text files, one record per line, line ``k`` of one matching line ``k`` of the other:

- ``poses.txt``: ``t x y theta``, t in milliseconds, x and y in millimetres, theta in tenths of
  a degree, counter-clockwise, x forward at theta = 0;
- ``measurement.txt``: ``t r0 ... r7``, the same time stamps, ranges in millimetres;
  :data:`ROBOND_NO_ECHO` (5110) means that the sensor heard no echo.

Sensors 0..7 point at :data:`ROBOND_BEARINGS` from the robot heading and sit at the robot centre
(the layout the source repository assumes; see the data README).

Stale repeats
-------------
The log comes about every 210 ms, faster than the sensors refresh: more than half the values
equal the same sensor's value in the previous record although the robot moved. The rule used
here, per sensor and record ``k >= 1``, for a value that is an echo (not no-echo):

- equal to the sensor's value in record ``k - 1`` while the pose (x, y, theta) changed
  (theta compared modulo 360°):
  **stale**, dropped: it is the earlier reading again, and stamping it with the new pose would
  move its arc;
- equal to it while the pose did not change: a **duplicate**, dropped by default: it gives an
  arc identical to the one already kept, so it adds nothing to carving or ATM.

Limits: a sensor that truly measures the same range again after the robot moved (driving
parallel to a wall; ranges are quantised to 10 mm) loses that reading; a stale value is only
recognised while it repeats exactly; and a fresh value is stamped with its record's pose
although the sensor fired some time in the preceding record period (up to about 0.2 s, which
sonar polling, :mod:`sonarcarve.polling`, bounds when the firing order and timeouts are known;
for this robot they are not).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import numpy as np
import numpy.typing as npt

from sonarcarve.io.errors import InputError, parse_number, read_text
from sonarcarve.readings import ReadingBatch

__all__ = [
    "ROBOND_BEAM_WIDTH",
    "ROBOND_BEARINGS",
    "ROBOND_NO_ECHO",
    "RoboNDLog",
    "RoboNDReport",
    "bundled_robond_dir",
    "read_robond",
]

#: Sensor bearings relative to the robot heading, radians, sensors 0..7.
ROBOND_BEARINGS = tuple(math.radians(d) for d in (-90.0, -37.5, -22.5, -7.5, 7.5, 22.5, 37.5,
                                                  90.0))
#: The value (mm) a sensor reports when it heard no echo.
ROBOND_NO_ECHO = 5110
#: Beam width φ given by the data README ("about 20 degrees"), radians.
ROBOND_BEAM_WIDTH = math.radians(20.0)

_POSE_COLUMNS = ("t", "x", "y", "theta")
_MEASUREMENT_COLUMNS = ("t", *(f"r{i}" for i in range(len(ROBOND_BEARINGS))))


def bundled_robond_dir() -> Path:
    """The directory of the copy of the log shipped inside the package."""
    return Path(str(files("sonarcarve") / "data" / "roboND-sonar-8"))


@dataclass(frozen=True)
class RoboNDReport:
    """What :func:`read_robond` found.

    Attributes
    ----------
    records : int
        Lines (records) in each file.
    values : int
        Sensor values: records × 8.
    no_echo : int
        Values equal to :data:`ROBOND_NO_ECHO` (dropped).
    repeats : int
        Values after the first record equal to the same sensor's previous value while the pose
        changed, no-echo values included (the data README's count).
    stale : int
        Echoes dropped as stale (repeats that are echoes).
    duplicates : int
        Echoes equal to the sensor's previous value while the pose did not change.
    duplicates_kept : bool
        Whether the duplicates were kept as readings.
    readings : int
        Readings produced.
    """

    records: int
    values: int
    no_echo: int
    repeats: int
    stale: int
    duplicates: int
    duplicates_kept: bool
    readings: int


@dataclass(frozen=True, eq=False)
class RoboNDLog:
    """The readings of the log and where they came from.

    Attributes
    ----------
    batch : ReadingBatch
        One reading per kept echo, in record order then sensor order; seconds, metres, radians
        (world frame), beam width set.
    record : ndarray of int64, shape (len(batch),)
        0-based record (line) of each reading.
    report : RoboNDReport
        Counts.
    """

    batch: ReadingBatch
    record: npt.NDArray[np.int64]
    report: RoboNDReport


def _read_table(path: Path, columns: tuple[str, ...]) -> npt.NDArray[np.float64]:
    text = read_text(path, InputError)
    lines = text.splitlines()
    while lines and not lines[-1].strip():
        lines.pop()  # trailing blank lines are harmless
    if not lines:
        msg = f"{path}: empty file, expected lines of {' '.join(columns)}"
        raise InputError(msg)
    table = np.empty((len(lines), len(columns)))
    for number, line in enumerate(lines, start=1):
        fields = line.split()
        if len(fields) != len(columns):
            msg = (f"{path}: line {number}, expected {len(columns)} columns "
                   f"({' '.join(columns)}), found {len(fields)}")
            raise InputError(msg)
        for column, (name, field) in enumerate(zip(columns, fields, strict=True)):
            table[number - 1, column] = parse_number(field, f"{path}: line {number}", name)
    back = np.flatnonzero(np.diff(table[:, 0]) <= 0.0)
    if back.size:
        row = int(back[0]) + 1
        msg = (f"{path}: line {row + 1}, time {_amount(table[row, 0])} ms is not after the "
               f"previous line's {_amount(table[row - 1, 0])} ms")
        raise InputError(msg)
    return table


def _amount(value: float) -> str:
    """A logged quantity for a message: whole milliseconds (or millimetres) as integers.

    >>> _amount(1687560.0), _amount(-5.0), _amount(12.5)
    ('1687560', '-5', '12.5')
    """
    number = float(value)
    # Beyond 1e15 a float's integer digits are not all meaningful: keep its shortest repr.
    return str(int(number)) if number.is_integer() and abs(number) < 1e15 else repr(number)


def read_robond(
    directory: str | Path | None = None,
    *,
    beam_width: float = ROBOND_BEAM_WIDTH,
    keep_duplicates: bool = False,
) -> RoboNDLog:
    """Read ``poses.txt`` and ``measurement.txt`` into readings in the world frame.

    No-echo values are dropped, and so are stale repeats (see the module notes for the rule and
    its limits).

    Parameters
    ----------
    directory : path, optional
        Folder with the two files; default :func:`bundled_robond_dir`.
    beam_width : float
        φ to record with each reading, radians (README: about 20°).
    keep_duplicates : bool
        Keep values that repeat while the robot stands still (default: drop them).

    Raises
    ------
    InputError
        One line naming the file and line: a missing file, a wrong column count, a non-numeric
        or non-finite value, a range <= 0, time not increasing, time stamps differing between
        the two files, or files of different lengths.
    """
    folder = bundled_robond_dir() if directory is None else Path(directory)
    poses_path, meas_path = folder / "poses.txt", folder / "measurement.txt"
    poses = _read_table(poses_path, _POSE_COLUMNS)
    meas = _read_table(meas_path, _MEASUREMENT_COLUMNS)
    _check_match(poses_path, poses, meas_path, meas)
    values = meas[:, 1:]
    bad = np.argwhere(values <= 0.0)
    if bad.size:
        line, sensor = int(bad[0, 0]) + 1, int(bad[0, 1])
        msg = (f"{meas_path}: line {line}, column 'r{sensor}' must be > 0 mm, "
               f"got {_amount(values[line - 1, sensor])}")
        raise InputError(msg)
    return _readings(poses, values, beam_width, keep_duplicates)


def _check_match(poses_path: Path, poses: npt.NDArray[np.float64], meas_path: Path,
                 meas: npt.NDArray[np.float64]) -> None:
    n = min(len(poses), len(meas))
    differ = np.flatnonzero(poses[:n, 0] != meas[:n, 0])
    if differ.size:
        line = int(differ[0]) + 1
        msg = (f"{meas_path}: line {line}, time {_amount(meas[line - 1, 0])} ms does not match "
               f"{poses_path.name} line {line} ({_amount(poses[line - 1, 0])} ms)")
        raise InputError(msg)
    if len(poses) != len(meas):
        short, long_path = (meas_path, poses_path) if len(meas) < len(poses) else (poses_path,
                                                                                    meas_path)
        msg = (f"{short}: line {n + 1}, file ends after {n} records but {long_path.name} has "
               f"{max(len(poses), len(meas))}")
        raise InputError(msg)


def _readings(poses: npt.NDArray[np.float64], values: npt.NDArray[np.float64],
              beam_width: float, keep_duplicates: bool) -> RoboNDLog:
    records, sensors = values.shape
    echo = values != ROBOND_NO_ECHO
    same = np.zeros_like(echo)
    same[1:] = values[1:] == values[:-1]
    pose = poses[:, 1:].copy()
    pose[:, 2] %= 3600.0  # 3600 tenths of a degree is the same heading as 0
    moved = np.zeros(records, dtype=bool)
    moved[1:] = np.any(pose[1:] != pose[:-1], axis=1)
    repeat = same & moved[:, None]
    stale = repeat & echo
    duplicate = same & ~moved[:, None] & echo
    keep = echo & ~stale & (keep_duplicates | ~duplicate)
    record, sensor = np.nonzero(keep)  # row-major: record order, then sensor order
    axis = np.radians(poses[record, 3] / 10.0) + np.asarray(ROBOND_BEARINGS)[sensor]
    # Wrapped into [-π, π): a heading of 359.9° plus a 90° bearing would otherwise write
    # 7.85 rad, and the jump to the next record's -1.57 rad reads as degrees to likely_mistakes.
    theta = (axis + math.pi) % (2.0 * math.pi) - math.pi
    batch = ReadingBatch.from_arrays(
        t=poses[record, 0] / 1000.0, sensor=sensor, x=poses[record, 1] / 1000.0,
        y=poses[record, 2] / 1000.0, theta=theta,
        range=values[record, sensor] / 1000.0, beam_width=np.full(record.shape, beam_width),
        source="roboND log",
    )
    report = RoboNDReport(
        records=records, values=records * sensors, no_echo=int((~echo).sum()),
        repeats=int(repeat.sum()), stale=int(stale.sum()), duplicates=int(duplicate.sum()),
        duplicates_kept=keep_duplicates, readings=len(batch),
    )
    return RoboNDLog(batch=batch, record=record.astype(np.int64), report=report)
