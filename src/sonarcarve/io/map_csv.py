"""The map CSV written by ``sonarcarve process`` (design contract).

Header ``id,t,sensor,x,y,source,width,max_error``; one row per surviving reading, ``id`` the
reading's 0-based row in the input, ``source`` one of ``centerline|carved|atm``, ``width`` the
final angular width (radians), ``max_error`` the bound in metres.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import InputError
from sonarcarve.maps import GlobalMap, PointSource

__all__ = ["MAP_COLUMNS", "read_map_csv", "write_map_csv"]

MAP_COLUMNS = ("id", "t", "sensor", "x", "y", "source", "width", "max_error")
_SOURCE_BY_LABEL = {source.label: source for source in PointSource}


def write_map_csv(points: GlobalMap, path: str | Path) -> None:
    """Write a map in the contract format, atomically."""
    labels = points.source_labels()
    with atomic_text(path) as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(MAP_COLUMNS)
        for i in range(len(points)):
            writer.writerow([
                int(points.reading_id[i]), repr(float(points.t[i])), int(points.sensor[i]),
                repr(float(points.xy[i, 0])), repr(float(points.xy[i, 1])), labels[i],
                repr(float(points.width[i])), repr(float(points.max_error[i])),
            ])


def read_map_csv(path: str | Path) -> GlobalMap:
    """Read a map CSV back (``range`` is not in the file and comes back as NaN)."""
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
    except OSError as err:
        msg = f"{path}: cannot read ({err.strerror})"
        raise InputError(msg) from None
    if not rows or tuple(name.strip() for name in rows[0]) != MAP_COLUMNS:
        msg = f"{path}: line 1, expected header {','.join(MAP_COLUMNS)}"
        raise InputError(msg)
    body = rows[1:]
    try:
        source = [_SOURCE_BY_LABEL[row[5]] for row in body]
        numbers = np.array([[float(row[i]) for i in (0, 1, 2, 3, 4, 6, 7)] for row in body])
    except (KeyError, ValueError, IndexError) as err:
        msg = f"{path}: malformed row ({err})"
        raise InputError(msg) from None
    numbers = numbers.reshape(-1, 7)
    return GlobalMap(
        reading_id=numbers[:, 0].astype(np.int64), t=numbers[:, 1],
        sensor=numbers[:, 2].astype(np.int64), xy=numbers[:, 3:5].copy(),
        source=np.array(source, dtype=np.int8).reshape(-1), width=numbers[:, 5],
        max_error=numbers[:, 6], range=np.full(len(body), np.nan),
    )
