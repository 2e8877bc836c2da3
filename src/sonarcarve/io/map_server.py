"""ROS map_server maps: a trinary occupancy image (PGM) beside its YAML description.

The format ROS ``map_server`` loads and ``map_saver`` writes (design, "Grids"):

- ``NAME.yaml``: ``image`` (the PGM's file name, relative to the YAML), ``resolution`` (metres
  per cell), ``origin`` ``[x, y, yaw]`` (the pose of the image's lower-left corner), ``negate``
  0, ``occupied_thresh`` and ``free_thresh``, ``mode`` trinary;
- ``NAME.pgm``: binary greyscale (P5, maximum 255), row 0 the *top* of the map: occupied cells 0,
  free 254, unknown 205. With ``negate`` 0 map_server reads a pixel ``p`` as occupancy
  ``(255 - p) / 255``: 1.0 (> ``occupied_thresh`` 0.65: occupied), 0.004 (< ``free_thresh``
  0.196: free) and 0.196 (between: unknown), so the image reads back exactly (map_saver's values).

Cells come in as the trinary convention of ``nav_msgs/OccupancyGrid`` (100 occupied, 0 free, -1
unknown; :func:`~sonarcarve.grids.trinary`), row 0 the *bottom* (y up, as the grids store them).
Both files are written atomically (:func:`~sonarcarve.io.atomic.atomic_paths`): on any error
neither appears and existing files are left as they were.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import NamedTuple, NoReturn

import numpy as np
import numpy.typing as npt

from sonarcarve.io.atomic import atomic_paths
from sonarcarve.io.errors import InputError, OutputError, finite_number, load_yaml, shorten

__all__ = [
    "FREE_THRESH",
    "OCCUPIED_THRESH",
    "PIXEL_FREE",
    "PIXEL_OCCUPIED",
    "PIXEL_UNKNOWN",
    "MapServerMap",
    "read_map_server",
    "write_map_server",
]

#: Pixel values of the trinary image (map_saver's).
PIXEL_OCCUPIED = 0
PIXEL_FREE = 254
PIXEL_UNKNOWN = 205
#: Largest PGM image read back, bytes (a 16384 x 16384 grid).
MAX_PGM_BYTES = 2**28 + 64
#: Thresholds written to the YAML (map_saver's): they read the three pixels back exactly.
OCCUPIED_THRESH = 0.65
FREE_THRESH = 0.196

_OCCUPIED, _FREE, _UNKNOWN = 100, 0, -1


class MapServerMap(NamedTuple):
    """A map_server map read back.

    Attributes
    ----------
    cells : ndarray of int8, shape (rows, cols)
        100 occupied, 0 free, -1 unknown; row 0 the bottom (y up).
    resolution : float
        Metres per cell.
    origin : tuple of 3 floats
        ``(x, y, yaw)`` of the lower-left corner.
    occupied_thresh, free_thresh : float
        As written in the YAML.
    image : str
        The image file name as written in the YAML.
    """

    cells: npt.NDArray[np.int8]
    resolution: float
    origin: tuple[float, float, float]
    occupied_thresh: float
    free_thresh: float
    image: str


def _pixels(cells: npt.ArrayLike) -> npt.NDArray[np.uint8]:
    c = np.asarray(cells)
    if c.ndim != 2 or not c.size:
        msg = f"map_server map: cells must be a non-empty 2-D array, got shape {c.shape}"
        raise OutputError(msg)
    bad = ~np.isin(c, (_OCCUPIED, _FREE, _UNKNOWN))
    if bad.any():
        row, col = (int(v) for v in np.argwhere(bad)[0])
        msg = (f"map_server map: cell ({row}, {col}) is {c[row, col]!r}; expected 100 "
               "(occupied), 0 (free) or -1 (unknown)")
        raise OutputError(msg)
    pixels = np.full(c.shape, PIXEL_UNKNOWN, dtype=np.uint8)
    pixels[c == _OCCUPIED] = PIXEL_OCCUPIED
    pixels[c == _FREE] = PIXEL_FREE
    return np.ascontiguousarray(pixels[::-1])  # image row 0 is the top


def write_map_server(cells: npt.ArrayLike, resolution: float, origin: tuple[float, float],
                     path: str | Path) -> tuple[Path, Path]:
    """Write ``path`` (the YAML) and the PGM beside it (same stem, ``.pgm``), atomically.

    Parameters
    ----------
    cells : array-like of int, shape (rows, cols)
        100 occupied, 0 free, -1 unknown; row 0 the bottom (y up).
    resolution : float
        Metres per cell, finite and > 0.
    origin : tuple of 2 floats
        ``(x, y)`` of the lower-left corner of cell ``(0, 0)``, metres (yaw 0).
    path : str or Path
        The YAML file; its folder must exist.

    Returns
    -------
    (Path, Path)
        The YAML and the PGM written.

    Raises
    ------
    OutputError
        Bad cells, resolution or origin (nothing written), or a path that cannot be written
        (one line naming it; nothing written, existing files untouched).

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> yaml_path, pgm_path = write_map_server([[100, 0], [-1, 0]], 0.1, (1.0, 2.0),
    ...                                       folder / "grid.yaml")
    >>> pgm_path.read_bytes()
    b'P5\\n2 2\\n255\\n\\xcd\\xfe\\x00\\xfe'
    >>> read_map_server(yaml_path).cells.tolist()
    [[100, 0], [-1, 0]]
    """
    pixels = _pixels(cells)
    h = finite_number(resolution)
    if h is None or h <= 0.0:
        msg = f"map_server map: resolution must be a finite number > 0 metres, got {resolution!r}"
        raise OutputError(msg)
    ox, oy = (finite_number(v) for v in origin)
    if ox is None or oy is None:
        msg = f"map_server map: origin must be two finite numbers, got {origin!r}"
        raise OutputError(msg)
    yaml_path = Path(path)
    pgm_path = yaml_path.with_suffix(".pgm")
    if yaml_path.suffix.lower() not in (".yaml", ".yml"):
        msg = f"{yaml_path}: a map_server map needs a .yaml file name"
        raise OutputError(msg)
    rows, cols = pixels.shape
    header = f"P5\n{cols} {rows}\n255\n".encode("ascii")
    text = (f"image: {pgm_path.name}\n"
            f"mode: trinary\n"
            f"resolution: {h!r}\n"
            f"origin: [{ox!r}, {oy!r}, 0.0]\n"
            f"negate: 0\n"
            f"occupied_thresh: {OCCUPIED_THRESH}\n"
            f"free_thresh: {FREE_THRESH}\n")
    with atomic_paths(yaml_path, pgm_path) as (yaml_tmp, pgm_tmp):
        pgm_tmp.write_bytes(header + pixels.tobytes())
        yaml_tmp.write_text(text, encoding="utf-8")
    return yaml_path, pgm_path


def _fail(path: Path, problem: str) -> NoReturn:
    msg = f"{path}: {problem}"
    raise InputError(msg)


def _pgm_header(data: bytes) -> tuple[list[bytes], int] | None:
    """The four header fields of a PGM (magic, width, height, maxval) and where its raster
    starts: after the one whitespace byte that ends the header. Comments (``#`` to the end of
    the line, as map_saver's ``# CREATOR: ...``) may come between the fields. None when the
    header is incomplete."""
    fields: list[bytes] = []
    i = 0
    while len(fields) < 4:
        while i < len(data) and (data[i:i + 1].isspace() or data[i:i + 1] == b"#"):
            if data[i:i + 1] == b"#":
                end = data.find(b"\n", i)
                if end < 0:
                    return None
                i = end
            i += 1
        start = i
        while i < len(data) and not data[i:i + 1].isspace() and data[i:i + 1] != b"#":
            i += 1
        if start == i:
            return None
        fields.append(data[start:i])
    if not data[i:i + 1].isspace():
        return None
    return fields, i + 1


def _read_pgm(yaml_path: Path, image: str) -> npt.NDArray[np.uint8]:
    """The pixels of a binary 8-bit PGM (P5, maxval 255), shape (rows, cols), top row first.

    The raster is the ``rows * cols`` bytes right after the header; bytes after it (a trailing
    newline, a second image) are ignored, as netpbm readers do."""
    where = f"image {shorten(image, 120)}"
    image_path = yaml_path.parent / image
    try:
        with image_path.open("rb") as handle:
            data = handle.read(MAX_PGM_BYTES + 1)  # bounded: a device or a huge file fails
    except FileNotFoundError:
        _fail(yaml_path, f"{where}: no such file")
    except IsADirectoryError:
        _fail(yaml_path, f"{where}: is a directory")
    except OSError as err:
        _fail(yaml_path, f"{where}: cannot read ({err.strerror or err})")
    if len(data) > MAX_PGM_BYTES:
        _fail(yaml_path, f"{where}: larger than the limit of {MAX_PGM_BYTES:,} bytes")
    header = _pgm_header(data)
    if header is None:
        _fail(yaml_path, f"{where}: not a binary 8-bit PGM")
    (magic, width, height, maxval), start = header
    if magic != b"P5" or maxval != b"255" or not (width.isdigit() and height.isdigit()):
        _fail(yaml_path, f"{where}: not a binary 8-bit PGM")
    cols, rows = int(width), int(height)
    body = data[start:start + rows * cols]
    if len(body) != rows * cols:
        _fail(yaml_path, f"{where}: {cols} x {rows} pixels but {len(body):,} bytes of them "
                         "(truncated?)")
    return np.frombuffer(body, dtype=np.uint8).reshape(rows, cols)


def read_map_server(path: str | Path) -> MapServerMap:
    """Read a map written by :func:`write_map_server` (a trinary P5 PGM and its YAML).

    Raises
    ------
    InputError
        Unreadable YAML, missing keys, an image that is not a binary 8-bit PGM, or pixels
        other than 0, 205 and 254.
    """
    yaml_path = Path(path)
    meta = load_yaml(yaml_path)
    if not isinstance(meta, dict):
        _fail(yaml_path, "top level must be a mapping")
    for key in ("image", "resolution", "origin", "occupied_thresh", "free_thresh"):
        if key not in meta:
            _fail(yaml_path, f"missing key {key!r}")
    origin = meta["origin"]
    if not isinstance(origin, list) or len(origin) != 3:
        _fail(yaml_path, f"origin must be [x, y, yaw], got {shorten(repr(origin), 40)}")
    numbers = [finite_number(v) for v in (meta["resolution"], meta["occupied_thresh"],
                                          meta["free_thresh"], *origin)]
    if any(v is None for v in numbers):
        _fail(yaml_path, "resolution, thresholds and origin must be finite numbers")
    h, occ, free, ox, oy, yaw = (float(v) for v in numbers)  # type: ignore[arg-type]
    if not h > 0.0:
        _fail(yaml_path, f"resolution must be > 0, got {h:g}")
    image = str(meta["image"])
    pixels = _read_pgm(yaml_path, image)[::-1]
    cells = np.full(pixels.shape, _UNKNOWN, dtype=np.int8)
    cells[pixels == PIXEL_OCCUPIED] = _OCCUPIED
    cells[pixels == PIXEL_FREE] = _FREE
    if not np.isin(pixels, (PIXEL_OCCUPIED, PIXEL_FREE, PIXEL_UNKNOWN)).all():
        _fail(yaml_path, f"image {image}: pixels other than 0, 205 and 254 (not trinary)")
    if not math.isclose(yaw, 0.0, abs_tol=0.0):
        _fail(yaml_path, f"origin yaw must be 0, got {yaw}")
    return MapServerMap(cells, h, (ox, oy, yaw), occ, free, image)
