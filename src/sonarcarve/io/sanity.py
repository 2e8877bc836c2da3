"""Likely mistakes named: readings that parse but are probably in the wrong units or layout.

A log in degrees, in millimetres, or a ``--beam-width`` given in radians runs without error and
gives a map 8-10 times worse; these checks name the likely cause in one line each, for the
command line to print as a warning (exit code still 0). A table that does not parse at all gets
a hint from :func:`csv_shape_hint` (semicolons, tabs, a header in capitals).

Nothing here changes the readings or refuses them: the numbers may be right.
"""

from __future__ import annotations

import math

import numpy as np

from sonarcarve.readings import ReadingBatch

__all__ = ["beam_width_mistake", "csv_shape_hint", "likely_mistakes"]

#: A log whose finite ranges have this median or more, metres, is probably not in metres:
#: ultrasonic sensors reach 3-10 m, and the median range of a log lies near 0.5-3 m (the T
#: junction 0.84 m, the office 2.3 m, the real roboND log 2.29 m), so a median of 20 "metres" is
#: centimetres (84 cm passed as metres with a threshold of 100).
SUSPECT_MEDIAN_RANGE = 20.0
#: A suspect median of this many "metres" or more is probably millimetres, below it
#: centimetres: 0.5-3 m is 500-3000 mm or 50-300 cm, and 400 parts them (838 mm read as
#: centimetres with a boundary of 1000).
MILLIMETRE_MEDIAN_RANGE = 400.0
#: Echoes at exactly their ``max_range`` from this share of a log's echoes on are probably a
#: driver's "nothing heard" (a real echo lands exactly on the limit rarely: 1 in 255 range
#: steps of a Scout2 sonar, evenly spread).
MAX_RANGE_ECHO_SHARE = 0.05
#: Without a ``max_range`` column, the longest range counts as a clamp only in a log of this
#: many echoes or more, and only when it is this many times the median range: a handful of
#: readings, or a robot in a long hall, reads the same longest range a few times honestly.
_CLAMPED_MIN_ECHOES = 100
_CLAMPED_OVER_MEDIAN = 1.5
#: Sensors moving faster than this between their consecutive readings, m/s (the median over a
#: log's moves), probably have positions in another unit than the ranges': robots drive at
#: 0.2-2 m/s and a car parks at 1-2 m/s, while a 0.4 m/s robot whose x, y are in millimetres
#: moves at 400 "m/s" (and its ranges, in metres, pass the range check).
SUSPECT_SPEED = 50.0
#: A ``--beam-width`` (degrees) below this is probably radians: sonar beams are 7-60 degrees,
#: and 22.5 degrees is 0.39 radians.
SUSPECT_BEAM_WIDTH_DEG = 2.0

_COLUMNS = ("t", "sensor", "x", "y", "theta", "range")


def likely_mistakes(batch: ReadingBatch) -> list[str]:
    """One line per probable unit mistake in ``batch`` (empty when it looks right).

    - ``theta`` beyond ±2π: probably degrees, if it is so from the first reading on or jumps
      by more than 2π between two readings (a ring of sensors in degrees does at every turn
      of its firing order). A log in radians whose heading was unwrapped (as ``convert
      rosbag`` writes it) starts within ±2π and drifts by small steps beyond it as the robot
      turns round: that is no mistake;
    - ranges with a median of :data:`SUSPECT_MEDIAN_RANGE` m or more: probably centimetres or
      millimetres;
    - a ``beam_width`` below 1 degree: probably another unit (beams are 7-60 degrees);
    - sensors moving at :data:`SUSPECT_SPEED` m/s or more between their readings: probably
      positions in millimetres;
    - :data:`MAX_RANGE_ECHO_SHARE` or more of the echoes at exactly their ``max_range``:
      probably a driver's "nothing heard".

    Examples
    --------
    >>> batch = ReadingBatch.from_arrays(t=[0, 1], sensor=[0, 0], x=[0, 0], y=[0, 0],
    ...                                  theta=[90.0, 180.0], range=[2.0, 3.0])
    >>> likely_mistakes(batch)
    ['theta reaches 180 rad, beyond ±2π: is it in degrees? (readings CSV theta is radians)']
    >>> likely_mistakes(ReadingBatch.from_arrays(t=[0], sensor=[0], x=[0], y=[0], theta=[0.5],
    ...                                          range=[2.0]))
    []
    >>> turning = np.linspace(0.0, 20.0, 200)  # radians, unwrapped: three turns and more
    >>> likely_mistakes(ReadingBatch.from_arrays(t=turning, sensor=np.zeros(200, int),
    ...     x=np.zeros(200), y=np.zeros(200), theta=turning, range=np.full(200, 2.0)))
    []
    """
    found: list[str] = []
    if len(batch.theta):
        full_turn = 2.0 * math.pi + 1e-9
        biggest = float(np.max(np.abs(batch.theta)))
        if biggest > full_turn and (abs(float(batch.theta[0])) > full_turn
                                    or float(np.max(np.abs(np.diff(batch.theta)),
                                                    initial=0.0)) > full_turn):
            found.append(f"theta reaches {biggest:g} rad, beyond ±2π: is it in degrees? "
                         "(readings CSV theta is radians)")
    ranges = batch.range[np.isfinite(batch.range)]
    if ranges.size:
        median = float(np.median(ranges))
        if median >= SUSPECT_MEDIAN_RANGE:
            unit = "millimetres" if median >= MILLIMETRE_MEDIAN_RANGE else "centimetres"
            found.append(f"the median range is {median:g} m: is it in {unit}? "
                         "(readings CSV range is metres)")
    fast = _positions_too_fast(batch)
    if fast:
        found.append(fast)
    at_limit = _echoes_at_max_range(batch)
    if at_limit:
        found.append(at_limit)
    widths = batch.beam_width[np.isfinite(batch.beam_width)]
    if widths.size and float(np.min(widths)) < math.radians(1.0):
        found.append(f"beam_width is as small as {float(np.min(widths)):g} rad "
                     f"({math.degrees(float(np.min(widths))):.2g} degrees): sonar beams are "
                     "7-60 degrees; is it in another unit?")
    return found


def _positions_too_fast(batch: ReadingBatch) -> str | None:
    """A warning when the sensors move faster than :data:`SUSPECT_SPEED` between their
    consecutive readings (median over the moves; standing still is left out), else None:
    positions in millimetres beside ranges in metres (times in seconds)."""
    order = np.lexsort((batch.t, batch.sensor))  # each sensor's readings in time order
    sensor, t = batch.sensor[order], batch.t[order]
    x, y = batch.x[order], batch.y[order]
    same = (sensor[1:] == sensor[:-1]) & (t[1:] > t[:-1])
    step = np.hypot(np.diff(x), np.diff(y))[same]
    moved = step > 0.0
    if not moved.any():
        return None
    speed = float(np.median(step[moved] / np.diff(t)[same][moved]))
    if speed < SUSPECT_SPEED:
        return None
    return (f"the sensors move at {speed:.3g} m/s between readings (median): are x and y in "
            "millimetres? (readings CSV x, y are metres and t seconds)")


def _echoes_at_max_range(batch: ReadingBatch) -> str | None:
    """A warning when :data:`MAX_RANGE_ECHO_SHARE` or more of the echoes that have a
    ``max_range`` read exactly it (without that column: the log's longest range, well above its
    median): drivers and simulators that report ``max_range`` for "nothing
    heard" (Gazebo's sonar plugin, clamping drivers) make those rows phantom walls at the limit
    in a readings CSV, where only ``inf`` is silence (bags are read with ``--no-echo``)."""
    echo = np.isfinite(batch.range) & np.isfinite(batch.max_range)
    if echo.any():
        limit, r = batch.max_range[echo], batch.range[echo]
        named = "their max_range"
    else:  # no max_range column: a clamped reading is the log's longest, many times over
        r = batch.range[np.isfinite(batch.range)]
        if r.size < _CLAMPED_MIN_ECHOES or r.max() < _CLAMPED_OVER_MEDIAN * np.median(r):
            return None
        limit = np.full(r.shape, r.max())
        named = f"the log's longest range, {r.max():g} m"
    # Relative 1e-6: a range written as 6.477 beside a max_range stored as float32.
    at_limit = int(np.sum(np.abs(r - limit) <= 1e-6 * limit))
    if at_limit < MAX_RANGE_ECHO_SHARE * r.size:
        return None
    # "checked": process looks at a log's first block only, as for the unit warnings.
    return (f"{at_limit:,} of {r.size:,} echoes checked read exactly {named}: if the sensor "
            "reports its maximum range when it hears nothing, write those rows as range inf "
            "(free space up to max_range), or they map as walls at the limit")


def beam_width_mistake(degrees: float, name: str = "beam width") -> str | None:
    """A warning if a beam width given in degrees looks like radians; ``name`` names the value
    in it (the command line passes its option, ``--beam-width``).

    Examples
    --------
    >>> beam_width_mistake(0.39)
    'beam width 0.39 is in degrees: did you mean 22.3 (0.39 radians)?'
    >>> beam_width_mistake(0.39, "--beam-width")
    '--beam-width 0.39 is in degrees: did you mean 22.3 (0.39 radians)?'
    >>> beam_width_mistake(22.5) is None
    True
    """
    if 0.0 < degrees < SUSPECT_BEAM_WIDTH_DEG:
        return (f"{name} {degrees:g} is in degrees: did you mean "
                f"{math.degrees(degrees):.3g} ({degrees:g} radians)?")
    return None


def csv_shape_hint(first_line: str) -> str | None:
    """A hint for a readings CSV whose header does not parse, from its first line; or None.

    Examples
    --------
    >>> csv_shape_hint("t;sensor;x;y;theta;range")
    "the file looks separated by ';': the readings CSV is comma-separated"
    >>> csv_shape_hint("t\\tsensor\\tx\\ty\\ttheta\\trange")
    'the file looks separated by tabs: the readings CSV is comma-separated'
    >>> csv_shape_hint("T,Sensor,X,Y,Theta,Range")
    'column names are case-sensitive: write the header in lower case (t,sensor,x,y,theta,range)'
    >>> csv_shape_hint("t,sensor,x,y,theta,range") is None
    True
    """
    line = first_line.lstrip("\ufeff").strip()
    commas = line.count(",")
    for separator, name in ((";", "';'"), ("\t", "tabs"), ("|", "'|'")):
        if line.count(separator) >= 3 and line.count(separator) > commas:
            return f"the file looks separated by {name}: the readings CSV is comma-separated"
    names = [cell.strip().strip('"') for cell in line.split(",")]
    lower = {name.lower() for name in names}
    if set(_COLUMNS) <= lower and not set(_COLUMNS) <= set(names):
        return ("column names are case-sensitive: write the header in lower case "
                "(t,sensor,x,y,theta,range)")
    return None
