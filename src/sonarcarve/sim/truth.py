"""Ground truth of a simulated readings CSV: ``READINGS.truth.json`` beside ``READINGS.csv``.

The file holds the world's walls and, per reading, what produced it::

    {"world": {"name": "doorway", "segments": [[x1, y1, x2, y2], ...]},
     "readings": [
      {"id": 0, "kind": "direct", "reflection": [x, y]},
      {"id": 1, "kind": "floor", "reflection": null},
      ...
     ]}

``id`` is the reading's 0-based row in the CSV; ``kind`` one of ``direct``, ``crosstalk``,
``floor``, ``multipath``, or ``none`` for a no-echo reading (a firing that heard nothing,
``range`` = inf in the CSV; files written before no-echo readings existed have none);
``reflection`` the true reflection point in metres (world frame), or
``null`` where there is none (floor and crosstalk echoes). One reading per line, so the file
diffs and greps well.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.io.atomic import atomic_paths, atomic_text
from sonarcarve.io.errors import InputError, finite_number
from sonarcarve.io.readings_csv import write_readings_csv
from sonarcarve.sim.sonar import NO_ECHO, EchoKind
from sonarcarve.sim.world import World, WorldError

if TYPE_CHECKING:
    from sonarcarve.sim.simulate import Simulation

__all__ = [
    "TRUTH_SUFFIX",
    "GroundTruth",
    "read_truth_json",
    "truth_path",
    "write_simulation",
    "write_truth_json",
]

#: What replaces ``.csv`` in a readings file name to name its truth file.
TRUTH_SUFFIX = ".truth.json"

_KIND_CODES = {kind.label: int(kind) for kind in EchoKind} | {"none": NO_ECHO}
_KIND_LABELS = {code: label for label, code in _KIND_CODES.items()}


class GroundTruth(NamedTuple):
    """A truth file in memory.

    Attributes
    ----------
    world : World
        The walls the readings were simulated in.
    kind : ndarray of int64, shape (n,)
        :class:`~sonarcarve.sim.sonar.EchoKind` code per reading, in CSV row order.
    reflection : ndarray, shape (n, 2)
        True reflection point per reading, metres; NaN rows where there is none.
    """

    world: World
    kind: npt.NDArray[np.int64]
    reflection: npt.NDArray[np.float64]


def truth_path(readings_path: str | Path) -> Path:
    """The truth file beside a readings CSV: ``a/run.csv`` -> ``a/run.truth.json``."""
    path = Path(readings_path)
    stem = path.name[: -len(path.suffix)] if path.suffix.lower() == ".csv" else path.name
    return path.with_name(stem + TRUTH_SUFFIX)


def write_truth_json(path: str | Path, world: World, kind: npt.ArrayLike,
                     reflection: npt.ArrayLike) -> None:
    """Write a truth file atomically.

    Parameters
    ----------
    path : str or Path
        Where to write (see :func:`truth_path`).
    world : World
        Its segments are written.
    kind : array-like of int, shape (n,)
        Echo kind codes per reading (:data:`~sonarcarve.sim.sonar.NO_ECHO`: no echo).
    reflection : array-like, shape (n, 2)
        Reflection points per reading, metres; rows with NaN are written as ``null``.
    """
    codes = np.asarray(kind, dtype=np.int64).reshape(-1)
    points = np.asarray(reflection, dtype=np.float64).reshape(-1, 2)
    if points.shape[0] != codes.shape[0]:
        msg = f"{path}: {codes.shape[0]} kinds but {points.shape[0]} reflection points"
        raise ValueError(msg)
    lines = [
        json.dumps({"id": i, "kind": _KIND_LABELS[code],
                    "reflection": None if np.isnan(p).any() else [float(p[0]), float(p[1])]})
        for i, (code, p) in enumerate(zip(codes.tolist(), points, strict=True))
    ]
    segments = json.dumps([[float(v) for v in row] for row in world.segments])
    with atomic_text(path) as handle:
        handle.write(f'{{"world": {{"name": {json.dumps(world.name)}, "segments": {segments}}},\n')
        handle.write(' "readings": [\n')
        handle.write(",\n".join(f"  {line}" for line in lines))
        handle.write("\n ]}\n")


def read_truth_json(path: str | Path) -> GroundTruth:
    """Read a truth file.

    Raises
    ------
    InputError
        One line naming the file and the first problem (missing file, bad JSON, a reading with
        an unknown kind, ids out of order, a malformed reflection).
    """
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        msg = f"{path}: no such file"
        raise InputError(msg) from None
    except (OSError, UnicodeDecodeError) as err:
        msg = f"{path}: cannot read ({err})"
        raise InputError(msg) from None
    except json.JSONDecodeError as err:
        msg = f"{path}: line {err.lineno}, column {err.colno}: not valid JSON ({err.msg})"
        raise InputError(msg) from None
    if not isinstance(data, dict) or not isinstance(data.get("readings"), list):
        msg = f"{path}: expected an object with 'world' and 'readings'"
        raise InputError(msg)
    world = _world(path, data.get("world"))
    rows = data["readings"]
    kind = np.empty(len(rows), dtype=np.int64)
    reflection = np.full((len(rows), 2), np.nan)
    for i, row in enumerate(rows):
        kind[i], point = _reading(path, i, row)
        if point is not None:
            reflection[i] = point
    return GroundTruth(world, kind, reflection)


def _world(path: Path, value: Any) -> World:
    if not isinstance(value, dict) or not isinstance(value.get("segments"), list):
        msg = f"{path}: 'world' must be an object with 'segments' [[x1, y1, x2, y2], ...]"
        raise InputError(msg)
    bad = f"{path}: world segments must be rows of four numbers [x1, y1, x2, y2]"
    try:
        segments = np.array(value["segments"], dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        raise InputError(bad) from None
    if segments.size == 0:
        segments = segments.reshape(0, 4)
    if segments.ndim != 2 or segments.shape[1] != 4:  # not [[1, 2], [3, 4]] read as one wall
        raise InputError(bad)
    name = str(value.get("name", path.name))
    try:
        return World(segments, name=name)
    except WorldError as err:  # its message starts with the world's name, not the file's
        msg = f"{path}: world {name!r}: {str(err).removeprefix(f'{name}: ')}"
        raise InputError(msg) from None


def _reading(path: Path, index: int, row: Any) -> tuple[int, tuple[float, float] | None]:
    where = f"{path}: readings[{index}]"
    if not isinstance(row, dict):
        msg = f"{where} must be an object {{id, kind, reflection}}"
        raise InputError(msg)
    if type(row.get("id")) is not int or row["id"] != index:  # not True, 0.0 or "0"
        msg = f"{where}: id {row.get('id')!r}, expected {index} (ids are CSV rows, in order)"
        raise InputError(msg)
    label = row.get("kind")
    if not isinstance(label, str) or label not in _KIND_CODES:
        msg = f"{where}: unknown kind {label!r}; expected one of {', '.join(_KIND_CODES)}"
        raise InputError(msg)
    point = row.get("reflection")
    if point is None:
        return _KIND_CODES[label], None
    if (not isinstance(point, list) or len(point) != 2
            or not all(finite_number(v) is not None for v in point)):
        msg = f"{where}: reflection must be null or [x, y] (finite numbers), got {point!r}"
        raise InputError(msg)
    return _KIND_CODES[label], (float(point[0]), float(point[1]))


def write_simulation(simulation: Simulation, readings_path: str | Path) -> Path:
    """Write a simulation's readings CSV and, beside it, its truth file; return the truth path.

    Both are written to temporary files first and renamed into place only when both are
    complete, so a failure leaves both targets as they were: never a new readings CSV beside an
    old truth file, nor an orphan truth file.

    Raises
    ------
    OutputError
        One of the two files cannot be written (nothing was replaced).
    """
    truth = truth_path(readings_path)
    with atomic_paths(truth, readings_path) as (truth_tmp, readings_tmp):
        write_truth_json(truth_tmp, simulation.world, simulation.truth.kind,
                         simulation.truth.reflection)
        write_readings_csv(simulation.readings, readings_tmp)
    return truth
