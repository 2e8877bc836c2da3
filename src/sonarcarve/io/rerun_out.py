"""A run as a Rerun recording (``.rrd``): the robot's path, each reading's arc, the live map.

:func:`write_rerun` streams readings through a method and logs, on a ``time`` timeline in the
readings' seconds (and a ``reading`` sequence timeline, the reading's id), under ``world/``:

- ``walls``: the true walls of a simulated run (static), light grey.
- ``robot/sensors``: the latest origin of every sensor heard so far (the robot's pose, as
  the readings know it), every reading.
- ``robot/path/tail``: each sensor's origins since the last finished piece, one line strip per
  sensor, every ``every`` readings and at the end; ``robot/path/<k>``: the ``k``-th finished
  piece (about :data:`PATH_PIECE` vertices in all), logged once. Logging the whole path every
  ``every`` readings made a recording grow with the square of the log (97,960 readings: over
  776 MB); in pieces it grows with the log.
- ``reading``: the new reading's beam (its two edges and its full arc of radius r), every
  reading.
- ``arcs``: every surviving arc in the history as carved so far (the point's final width about
  its bearing), coloured by source, every ``every`` readings.
- ``map``: the local map, coloured by source (the colours of :mod:`sonarcarve.plotting`), each
  point's radius its error bound ``max_error`` (capped), every ``every`` readings.
- ``global_map``: the global map at the end of the log.

rerun-sdk is an extra (``pip install 'sonarcarve[viz]'``), imported only when a recording is
written.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import ConfigError
from sonarcarve.extras import require
from sonarcarve.io.atomic import atomic_path
from sonarcarve.maps import GlobalMap, LocalMap, PointSource
from sonarcarve.readings import Reading, ReadingBatch, reading_ids
from sonarcarve.typing import IntArray

__all__ = ["DEFAULT_EVERY", "PATH_PIECE", "SOURCE_RGB", "RerunMapper", "write_rerun"]

#: Readings between two logs of the local map, the carved arcs and the path.
DEFAULT_EVERY = 5
#: Largest point radius drawn for a map point, metres (an ATM bound may be infinite).
_MAX_RADIUS = 0.5
#: Smallest point radius, metres, so that exact points stay visible.
_MIN_RADIUS = 0.01
#: Samples per arc in a line strip.
_ARC_SAMPLES = 24
#: A sensor's path gets a new vertex when its origin has moved this far, metres.
_PATH_STEP = 0.02
#: Vertices (all sensors together) after which the path's tail is logged as a finished piece.
PATH_PIECE = 2000

#: Colours by point source, as in :data:`sonarcarve.plotting.SOURCE_COLORS` (RGB 0-255).
SOURCE_RGB = {
    PointSource.CENTERLINE: (214, 39, 40),
    PointSource.CARVED: (31, 119, 180),
    PointSource.ATM: (44, 160, 44),
}
_READING_RGB = (255, 170, 0)
_WALL_RGB = (150, 150, 150)
_PATH_RGB = (90, 90, 90)


class RerunMapper(Protocol):
    """What :func:`write_rerun` needs of a method (any :class:`~sonarcarve.methods.SonarMethod`)."""

    def add(self, reading: Reading, reading_id: int | None = None) -> None:
        """Process one reading."""

    def local_map(self) -> LocalMap:
        """One point per surviving arc in the history."""

    def finish(self) -> GlobalMap:
        """End the log; the global map."""


def write_rerun(
    path: str | Path,
    batch: ReadingBatch,
    method: RerunMapper,
    *,
    walls: npt.ArrayLike | None = None,
    every: int = DEFAULT_EVERY,
    application_id: str = "sonarcarve",
    ids: npt.ArrayLike | None = None,
    on_progress: Callable[[int], None] | None = None,
) -> GlobalMap:
    """Stream ``batch`` through ``method`` and write the run as a Rerun recording at ``path``.

    The file appears whole or not at all (written beside ``path`` and renamed).

    Parameters
    ----------
    path : str or Path
        The ``.rrd`` file to write.
    batch : ReadingBatch
        The readings in time order; reading ids are row positions.
    method : RerunMapper
        A fresh method (e.g. ``make_method("combined")``).
    walls : array-like, shape (n, 4), optional
        True wall segments x1, y1, x2, y2 in metres (simulated runs), logged once (static).
    every : int
        Log the local map, the carved arcs and the path every ``every`` readings (and after
        the last one); the new reading and the sensor origins are logged for every reading.
    application_id : str
        The recording's application id (what the viewer groups recordings by).
    ids : array-like of int, optional
        Each reading's id (the "reading" timeline and the map's ids): the input rows of
        readings a filter kept; default, row positions.
    on_progress : callable, optional
        Called with the number of readings logged so far every ``every`` readings and after
        the last one (with ``len(batch)``): for a progress bar.

    Returns
    -------
    GlobalMap
        The method's global map (as ``sonarcarve process`` would write it).

    Raises
    ------
    ConfigError
        ``every`` < 1.
    ReadingsError
        A reading the method refuses, or ``ids`` not one increasing integer per reading (the
        file is not written).
    OutputError
        ``path`` cannot be written.
    MissingExtraError
        rerun-sdk is not installed.
    """
    if every < 1:
        msg = f"every must be at least 1 reading, got {every}"
        raise ConfigError(msg)
    rr = require("rerun", "viz", "Rerun recordings")
    batch.validate()
    row_ids = reading_ids(len(batch), ids)
    target = Path(path)
    with atomic_path(target, suffix=".rrd") as tmp:
        recording = rr.RecordingStream(application_id)
        recording.save(tmp)
        try:
            global_map = _log_run(rr, recording, batch, row_ids, method, walls, every,
                                  on_progress)
        finally:
            recording.flush()
            recording.disconnect()
    return global_map


def _log_run(rr: Any, rec: Any, batch: ReadingBatch, ids: IntArray, method: RerunMapper,
             walls: npt.ArrayLike | None, every: int,
             on_progress: Callable[[int], None] | None = None) -> GlobalMap:
    if walls is not None:
        segments = np.asarray(walls, dtype=np.float64).reshape(-1, 2, 2)
        rec.log("world/walls", rr.LineStrips2D(segments, colors=_WALL_RGB, radii=0.02),
                static=True)
    paths = _Paths()
    pieces = 0
    latest: dict[int, tuple[float, float]] = {}
    n = len(batch)
    for k, reading in enumerate(batch):
        method.add(reading, int(ids[k]))
        rec.set_time("time", duration=reading.t)
        rec.set_time("reading", sequence=int(ids[k]))
        latest[reading.sensor] = (reading.x, reading.y)
        paths.add(reading.sensor, reading.x, reading.y)
        rec.log("world/robot/sensors", rr.Points2D(list(latest.values()), radii=0.03,
                                                   colors=_PATH_RGB))
        beam = _beam(reading, method)
        if beam:
            rec.log("world/reading", rr.LineStrips2D(beam, colors=_READING_RGB, radii=0.01))
        if (k + 1) % every == 0 or k == n - 1:
            if paths.tail_size() >= PATH_PIECE:
                rec.log(f"world/robot/path/{pieces}", _path(rr, paths.take_piece()))
                pieces += 1
            rec.log("world/robot/path/tail", _path(rr, paths.strips()))
            _log_points(rr, rec, "world/map", method.local_map(), batch, ids,
                        arcs="world/arcs")
            if on_progress is not None:
                on_progress(k + 1)
    global_map = method.finish()
    _log_points(rr, rec, "world/global_map", global_map, batch, ids, arcs=None)
    return global_map


def _path(rr: Any, strips: Sequence[npt.NDArray[np.float64]]) -> Any:
    return rr.LineStrips2D(strips, colors=_PATH_RGB, radii=0.005)


def _beam(reading: Reading, method: RerunMapper) -> list[npt.NDArray[np.float64]]:
    """The reading's sector outline: its two edges and its arc (none for a no-echo reading)."""
    if not np.isfinite(reading.range):
        return []
    width = reading.beam_width
    if not np.isfinite(width):
        width = float(getattr(method, "beam_width", np.nan))
    if not np.isfinite(width):
        return []
    origin = np.array([reading.x, reading.y])
    tau = reading.theta + 0.5 * width * np.linspace(-1.0, 1.0, _ARC_SAMPLES)
    arc = origin + reading.range * np.column_stack((np.cos(tau), np.sin(tau)))
    return [arc, np.array([arc[0], origin, arc[-1]])]


def _log_points(rr: Any, rec: Any, entity: str, points: LocalMap | GlobalMap,
                batch: ReadingBatch, ids: IntArray, arcs: str | None) -> None:
    colors = np.array([SOURCE_RGB[PointSource(int(code))] for code in points.source],
                      dtype=np.uint8).reshape(-1, 3)
    bound = np.where(np.isfinite(points.max_error), points.max_error, _MAX_RADIUS)
    radii = np.clip(bound, _MIN_RADIUS, _MAX_RADIUS)
    rec.log(entity, rr.Points2D(points.xy, colors=colors, radii=radii))
    if arcs is not None:
        rec.log(arcs, rr.LineStrips2D(_arc_strips(points, batch, ids), colors=colors, radii=0.008))


def _arc_strips(points: LocalMap | GlobalMap, batch: ReadingBatch,
                ids: IntArray) -> npt.NDArray[np.float64]:
    """Each point's arc as carved: radius r about its reading's origin, ``width`` wide, centred
    on the point's bearing; shape (n, samples, 2). ``ids``: the readings' ids, increasing."""
    rows = np.searchsorted(ids, points.reading_id)  # a point's reading, by its id
    origin = np.column_stack((batch.x[rows], batch.y[rows]))
    delta = points.xy - origin
    bearing = np.arctan2(delta[:, 1], delta[:, 0])
    tau = bearing[:, None] + 0.5 * points.width[:, None] * np.linspace(-1, 1, _ARC_SAMPLES)
    r = batch.range[rows][:, None]
    return np.stack((origin[:, :1] + r * np.cos(tau), origin[:, 1:] + r * np.sin(tau)), axis=-1)


class _Paths:
    """Each sensor's origins since the last finished piece, a vertex whenever it moved
    :data:`_PATH_STEP`; a sensor's tail starts at the last vertex of its previous piece, so
    the pieces join."""

    def __init__(self) -> None:
        self._vertices: dict[int, list[tuple[float, float]]] = {}
        self._size = 0

    def add(self, sensor: int, x: float, y: float) -> None:
        line = self._vertices.setdefault(sensor, [])
        if not line or np.hypot(x - line[-1][0], y - line[-1][1]) >= _PATH_STEP:
            line.append((x, y))
            self._size += 1

    def tail_size(self) -> int:
        """Vertices added since the last piece was taken."""
        return self._size

    def strips(self) -> Sequence[npt.NDArray[np.float64]]:
        """The tail, one strip per sensor that moved."""
        return [np.array(line) for line in self._vertices.values() if len(line) > 1]

    def take_piece(self) -> Sequence[npt.NDArray[np.float64]]:
        """The tail as a finished piece; each sensor's tail then restarts at its last vertex."""
        piece = self.strips()
        self._vertices = {sensor: line[-1:] for sensor, line in self._vertices.items()}
        self._size = 0
        return piece
