"""The map CSV written by ``sonarcarve process`` (design contract).

Header ``id,t,sensor,x,y,source,width,max_error,confidence``; one row per surviving reading,
``id`` the reading's 0-based row in the input, ``source`` one of ``centerline|carved|atm``,
``width`` the final angular width (radians), ``max_error`` the bound in metres. The first eight
columns are the original contract and keep their meaning exactly; ``confidence`` (appended) is
the probability that the point is a real surface, empty where the method does not model it.

:func:`write_map_csv` writes a whole map; :func:`map_csv_sink` writes one as it is made, from a
method's global-map sink (:meth:`~sonarcarve.methods.base.SonarMethod.set_global_sink`), to the
same bytes.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

import numpy as np

from sonarcarve.errors import ConfigError
from sonarcarve.io.atomic import atomic_text
from sonarcarve.io.errors import InputError, parse_number
from sonarcarve.io.readings_csv import READINGS_COLUMNS
from sonarcarve.maps import GlobalMap, PointSource
from sonarcarve.typing import Int8Array

__all__ = [
    "APPENDED_COLUMNS",
    "BLOCK_ROWS",
    "MAP_COLUMNS",
    "MapCsvSink",
    "map_csv_sink",
    "read_map_csv",
    "write_map_csv",
]

#: The original contract's eight columns, in order.
MAP_COLUMNS = ("id", "t", "sensor", "x", "y", "source", "width", "max_error")
#: Columns appended since, in order (readers of the first eight ignore them).
APPENDED_COLUMNS = ("confidence",)
_SOURCE_BY_LABEL = {source.label: source for source in PointSource}
#: Labels by source code (``PointSource`` values are 0, 1, 2, ...).
_LABELS = tuple(PointSource(code).label for code in range(len(PointSource)))
#: Rows formatted at a time by :func:`write_map_csv`.
BLOCK_ROWS = 8_192
#: Largest id or sensor index read back exactly (int64 and float64 agree up to 2**53).
_MAX_INDEX = 2**53


def write_map_csv(points: GlobalMap, path: str | Path, *, block_rows: int = BLOCK_ROWS) -> None:
    """Write a map in the contract format, atomically.

    Floats are written as Python's ``repr`` (the shortest text that reads back to the same
    float: ``0.1``, ``-0.0``, ``inf``, ``5e-324``), ids and sensors as integers, a NaN
    confidence as an empty cell. The text is built row by row by a compiled kernel
    (:func:`~sonarcarve.io.float_text.map_rows_text`), ``block_rows`` rows at a time, so memory
    stays bounded whatever the map's size.

    Raises
    ------
    ConfigError
        ``block_rows`` < 1.
    """
    _check_block_rows(block_rows)
    _check_sources(points.source)
    with map_csv_sink(path, block_rows=block_rows) as sink:
        sink.commit(points)


@contextmanager
def map_csv_sink(path: str | Path, *, block_rows: int = BLOCK_ROWS) -> Iterator[MapCsvSink]:
    """A global-map sink that writes the map CSV at ``path`` as points arrive, atomically.

    The rows go to a temporary file beside ``path`` (:func:`~sonarcarve.io.atomic.atomic_text`)
    that is renamed onto ``path`` when the block ends without error: a failed run, or one
    killed mid-way, leaves ``path`` as it was. The bytes are those of :func:`write_map_csv` on
    the whole map; at most about ``block_rows`` points are held at a time.

    Examples
    --------
    Stream a method's global map to a file::

        with map_csv_sink("map.csv") as sink:
            process_chunks(iter_readings_csv("log.csv"), method, sink=sink)

    Raises
    ------
    OutputError
        As :func:`~sonarcarve.io.atomic.atomic_path`.
    """
    _check_block_rows(block_rows)
    with atomic_text(path) as handle:
        sink = MapCsvSink(handle, block_rows)
        yield sink
        sink.flush()


class MapCsvSink:
    """Appends committed points to an open map CSV, ``block_rows`` rows formatted at a time
    (made by :func:`map_csv_sink`, which writes the header and renames the file at the end)."""

    def __init__(self, handle: IO[str], block_rows: int = BLOCK_ROWS) -> None:
        _check_block_rows(block_rows)
        self._handle = handle
        self._block_rows = block_rows
        self._pending: list[GlobalMap] = []
        self._pending_rows = 0
        self.points = 0  #: points written or waiting to be
        handle.write(",".join(MAP_COLUMNS + APPENDED_COLUMNS) + "\n")

    def commit(self, points: GlobalMap) -> None:
        """Append ``points`` (formatted once ``block_rows`` rows are waiting).

        Raises
        ------
        ValueError
            A ``source`` code that is no :class:`~sonarcarve.maps.PointSource`.
        """
        if not len(points):
            return
        _check_sources(points.source)
        self._pending.append(points)
        self._pending_rows += len(points)
        self.points += len(points)
        if self._pending_rows >= self._block_rows:
            self._write(whole_blocks=True)

    def flush(self) -> None:
        """Write every waiting point (the last, short block)."""
        if self._pending_rows:
            self._write(whole_blocks=False)

    def _write(self, *, whole_blocks: bool) -> None:
        pending = self._pending
        points = pending[0] if len(pending) == 1 else GlobalMap.concatenate(pending)
        n = len(points)
        size = self._block_rows
        stop = n - n % size if whole_blocks else n
        for start in range(0, stop, size):
            self._handle.write(_rows_text(points, slice(start, min(start + size, stop))))
        rest = points.select(np.arange(stop, n)) if stop < n else None  # a copy: frees the rest
        self._pending = [] if rest is None else [rest]
        self._pending_rows = n - stop


def _check_block_rows(block_rows: int) -> None:
    if block_rows < 1:
        msg = f"block_rows must be at least 1, got {block_rows}"
        raise ConfigError(msg)


def _rows_text(points: GlobalMap, rows: slice) -> str:
    """Rows ``rows`` of the map CSV, each ending with a line break.

    Built by a compiled kernel (:mod:`sonarcarve.io.float_text`, Python's ``repr`` of each
    float, byte for byte): formatting floats with ``repr`` bounded the writer at about half a
    million rows a second. Fields are joined by commas as they are: ``csv.writer`` would quote
    none of them (no field holds a comma, a quote or a line break), so the text is the same.
    """
    from sonarcarve.io.float_text import map_rows_text  # numba: only once rows are written

    return map_rows_text(points.reading_id[rows], points.t[rows], points.sensor[rows],
                         points.xy[rows], points.source[rows], points.width[rows],
                         points.max_error[rows], points.confidence[rows], _LABELS)


def _check_sources(source: Int8Array) -> None:
    """Every code a :class:`PointSource` (as the labels are looked up by position)."""
    bad = (source < 0) | (source >= len(_LABELS))
    if bad.any():
        PointSource(int(source[np.argmax(bad)]))  # raises ValueError naming the code


def read_map_csv(path: str | Path) -> GlobalMap:
    """Read a map CSV back (``range`` is not in the file and comes back as NaN).

    ``confidence`` is read when the header has it (an empty cell is NaN, "not modelled");
    other columns after the first eight are ignored: the contract only ever appends new ones.

    Raises
    ------
    InputError
        One line naming the file and the line of the first problem: a missing file, a header
        that does not start with the eight contract columns, a line with too few fields, an
        ``id`` or ``sensor`` that is not a whole number >= 0, an unknown ``source`` label, a
        negative ``width`` or ``max_error``, a NaN anywhere or an infinite value anywhere but
        ``max_error`` (ATM's bound may be ``inf``), bytes that are not UTF-8.
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            reader = csv.reader(handle)
            rows = [(reader.line_num, row) for row in reader]
    except OSError as err:
        msg = f"{path}: cannot read ({err.strerror})"
        raise InputError(msg) from None
    except UnicodeDecodeError:
        raise InputError(_not_utf8(path)) from None
    except csv.Error as err:
        msg = f"{path}: cannot read as CSV ({err})"
        raise InputError(msg) from None
    while rows and not rows[-1][1]:
        rows.pop()  # blank lines at the end
    header = tuple(name.strip() for name in rows[0][1]) if rows else ()
    if header[: len(MAP_COLUMNS)] != MAP_COLUMNS:
        msg = f"{path}: line 1, expected header {','.join(MAP_COLUMNS)}"
        if set(READINGS_COLUMNS) <= set(header):  # the readings instead of their map
            msg += (f"; it is a readings CSV ({','.join(header)}): a map CSV is what "
                    "sonarcarve process writes")
        raise InputError(msg)
    body = rows[1:]
    confidence_at = header.index("confidence") if "confidence" in header else None
    confidence = np.full(len(body), np.nan)
    numbers = np.empty((len(body), 7))
    source = np.empty(len(body), dtype=np.int8)
    for k, (line, row) in enumerate(body):
        where = f"{path}: line {line}"
        if len(row) < len(MAP_COLUMNS):
            msg = f"{where} has {len(row)} fields, expected at least {len(MAP_COLUMNS)}"
            raise InputError(msg)
        label = row[5].strip()
        if label not in _SOURCE_BY_LABEL:
            choices = ", ".join(_SOURCE_BY_LABEL)
            msg = f"{where}, column 'source' is {label!r}, expected one of {choices}"
            raise InputError(msg)
        source[k] = _SOURCE_BY_LABEL[label]
        for j, i in enumerate((0, 1, 2, 3, 4, 6, 7)):
            numbers[k, j] = _cell(row[i], where, MAP_COLUMNS[i])
        if confidence_at is not None and confidence_at < len(row) and row[confidence_at].strip():
            confidence[k] = _probability(row[confidence_at], where)
    return GlobalMap(
        reading_id=numbers[:, 0].astype(np.int64), t=numbers[:, 1],
        sensor=numbers[:, 2].astype(np.int64), xy=numbers[:, 3:5].copy(),
        source=source, width=numbers[:, 5],
        max_error=numbers[:, 6], range=np.full(len(body), np.nan), confidence=confidence,
    )


def _not_utf8(path: Path) -> str:
    """The message for a file that is not UTF-8, naming the line and byte as the readings CSV
    reader does (the text reader's own error gives an offset within a buffer)."""
    data = path.read_bytes()
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data.count(b"\n", 0, err.start) + 1
        return (f"{path}: line {line}, cannot read as CSV: not UTF-8 text "
                f"(byte 0x{data[err.start]:02x})")
    return f"{path}: cannot read as CSV: not UTF-8 text"


def _probability(text: str, where: str) -> float:
    """A ``confidence`` cell: a number in [0, 1]."""
    value = parse_number(text, where, "confidence", finite=False)
    if not 0.0 <= value <= 1.0:
        msg = f"{where}, column 'confidence' must lie in [0, 1], got {text.strip()!r}"
        raise InputError(msg)
    return value


def _cell(text: str, where: str, column: str) -> float:
    """One numeric cell; ``max_error`` alone may be ``inf`` (an ATM bound with ψ = 0)."""
    value = parse_number(text, where, column, finite=False)
    if math.isnan(value):
        msg = f"{where}, column {column!r} is NaN"
        raise InputError(msg)
    if math.isinf(value) and not (column == "max_error" and value > 0):
        msg = f"{where}, column {column!r} is not finite: {text!r}"
        raise InputError(msg)
    if column in ("id", "sensor") and not (0 <= value <= _MAX_INDEX and value.is_integer()):
        msg = f"{where}, column {column!r} is not a whole number >= 0: {text!r}"
        raise InputError(msg)
    if column in ("width", "max_error") and value < 0.0:
        unit = "radians" if column == "width" else "metres"
        msg = f"{where}, column {column!r} must be >= 0 {unit}, got {text.strip()!r}"
        raise InputError(msg)
    return value
