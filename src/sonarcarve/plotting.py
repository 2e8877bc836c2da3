"""Matplotlib figures of worlds, arcs and maps.

matplotlib is imported inside each function (never at import time), every function takes an
optional ``ax`` and returns the artists it drew, so callers own their figures. Nothing here picks
matplotlib's backend: a notebook keeps its inline one, a script its default; the command line
draws with Agg (:func:`sonarcarve.cli.drawing.draw_offscreen`).

A user's own map (what ``sonarcarve plot`` draws) is built from :func:`plot_map` (points by
source), :func:`plot_error_bounds` (each point's ``max_error`` as a circle), :func:`plot_map_arcs`
(each point's final arc), :func:`plot_path` (the sensor origins over time) and
:func:`plot_grid` (a ROS map_server map underneath), put together by :func:`plot_user_map`.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import DEFAULT_BEAM_WIDTH
from sonarcarve.errors import ConfigError
from sonarcarve.extras import require
from sonarcarve.io.atomic import atomic_path
from sonarcarve.io.errors import InputError, OutputError, finite_number, load_yaml
from sonarcarve.maps import PointSource

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from sonarcarve.maps import GlobalMap, LocalMap
    from sonarcarve.readings import ReadingBatch

__all__ = [
    "FIGURE_FORMATS",
    "SOURCE_COLORS",
    "TRINARY_COLORS",
    "GridImage",
    "MapOrigins",
    "check_figure_path",
    "map_origins",
    "new_axes",
    "new_figure",
    "plot_arc",
    "plot_carving_explainer",
    "plot_error_bounds",
    "plot_freespace",
    "plot_grid",
    "plot_map",
    "plot_map_arcs",
    "plot_path",
    "plot_sources",
    "plot_trinary",
    "plot_user_map",
    "plot_walls",
    "read_grid_image",
    "save_figure",
    "write_carving_explainer",
]

#: One colour per point source, the same in every figure.
SOURCE_COLORS = {
    PointSource.CENTERLINE: "#d62728",
    PointSource.CARVED: "#1f77b4",
    PointSource.ATM: "#2ca02c",
}


def new_figure(rows: int = 1, cols: int = 1, width: float = 7.0, height: float = 4.5,
               **options: Any) -> tuple[Figure, Any]:
    """A fresh constrained-layout pyplot figure of ``rows`` x ``cols`` axes, ``width`` x
    ``height`` inches, and its axes as a 2-D array (even for one); ``options`` go to
    ``plt.subplots`` (``sharex`` ...). The backend is left as the caller has it."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, cols, figsize=(width, height), layout="constrained",
                             squeeze=False, **options)
    return fig, axes


def new_axes(width: float = 7.0, height: float = 6.0) -> Axes:
    """A fresh figure with one equal-aspect axes (:func:`new_figure`; the backend is left as
    the caller has it)."""
    ax: Axes = new_figure(1, 1, width, height)[1][0, 0]
    ax.set_aspect("equal")
    return ax


def plot_walls(segments: npt.ArrayLike, ax: Axes | None = None, **style: Any) -> list[Any]:
    """Draw wall ``segments`` (shape (n, 4): x1, y1, x2, y2, metres) as light grey lines (the
    paper's "obstacles drawn in for display")."""
    from matplotlib.collections import LineCollection

    ax = ax or new_axes()
    options: dict[str, Any] = {"colors": "0.6", "linewidths": 1.5, "zorder": 1} | style
    walls = np.asarray(segments, dtype=np.float64).reshape(-1, 2, 2)
    lines = LineCollection(list(walls), **options)
    ax.add_collection(lines)
    ax.autoscale_view()
    return [lines]


def plot_map(
    points: LocalMap | GlobalMap, ax: Axes | None = None, size: float = 4.0, legend: bool = True
) -> list[Any]:
    """Scatter map points coloured by the model that placed them (:func:`plot_sources`)."""
    ax = ax or new_axes()
    artists = plot_sources(points.xy, points.source, ax, size)
    if legend and artists:
        ax.legend(loc="best", fontsize="small", markerscale=3)
    return artists


def plot_sources(xy: npt.ArrayLike, source: npt.ArrayLike, ax: Axes | None = None,
                 size: float = 4.0) -> list[Any]:
    """Scatter points ``xy`` (shape (n, 2), metres) coloured by ``source`` (shape (n,),
    :class:`~sonarcarve.maps.PointSource` codes), one series per source present, labelled
    with its count for a legend (``"carved (1,234)"``)."""
    ax = ax or new_axes()
    p = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    codes = np.asarray(source)
    artists = []
    for code, color in SOURCE_COLORS.items():
        mask = codes == code
        if np.any(mask):
            artists.append(ax.scatter(p[mask, 0], p[mask, 1], s=size, c=color,
                                      label=f"{code.label} ({int(mask.sum()):,})", zorder=3,
                                      linewidths=0))
    return artists


def plot_arc(
    origin: npt.ArrayLike, r: float, lo: float, hi: float, ax: Axes | None = None, **style: Any
) -> list[Any]:
    """Draw the arc of radius ``r`` about ``origin`` over bearings [lo, hi] (eq. 3.1)."""
    ax = ax or new_axes()
    o = np.asarray(origin, dtype=np.float64)
    tau = np.linspace(lo, hi, 64)
    return list(ax.plot(o[0] + r * np.cos(tau), o[1] + r * np.sin(tau), **style))


def plot_freespace(
    origin: npt.ArrayLike, r: float, lo: float, hi: float, ax: Axes | None = None, **style: Any
) -> list[Any]:
    """Shade the freespace sector F of a reading (eq. 3.2)."""
    ax = ax or new_axes()
    o = np.asarray(origin, dtype=np.float64)
    tau = np.linspace(lo, hi, 64)
    xs = np.concatenate(([o[0]], o[0] + r * np.cos(tau), [o[0]]))
    ys = np.concatenate(([o[1]], o[1] + r * np.sin(tau), [o[1]]))
    return list(ax.fill(xs, ys, **({"alpha": 0.2, "lw": 0} | style)))


def plot_carving_explainer(ax: Axes | None = None) -> list[Any]:
    """The idea of arc carving in one picture (paper, Fig. 2, 5 and 6).

    A robot passes a 0.9 m doorway. Reading ``i`` hears the right-hand door jamb at the edge of
    its 22.5° beam; the centerline model puts the echo at the centre of the arc, inside the
    doorway, and the door looks closed (Fig. 2). A newer reading ``j`` looks straight through
    the door and hears the far wall, so its beam was empty up to that range: the part of arc
    ``i`` inside that sector is carved away (eq. 3.4-3.5) and the point moves to the centre of
    what remains (eq. 3.6), next to the jamb. The door opens up in the map.
    """
    import math

    from sonarcarve.geometry import ArcFate, carve_arc

    ax = ax or new_axes(7.0, 5.5)
    half = DEFAULT_BEAM_WIDTH / 2
    jamb_left, jamb_right, wall_y = 0.5, 1.4, 2.0
    oi = np.array([0.2, 0.0])
    theta_i = math.atan2(wall_y - oi[1], 0.5 * (jamb_left + jamb_right) - oi[0])
    ri = float(np.hypot(jamb_right - oi[0], wall_y - oi[1]))  # the jamb is the nearest echo
    oj, theta_j, rj = np.array([0.95, 0.2]), math.pi / 2, 4.8  # through the door to a far wall
    lo_i, hi_i = theta_i - half, theta_i + half
    status, new_lo, new_hi = carve_arc(oi[0], oi[1], ri, lo_i, hi_i, oj[0], oj[1], rj,
                                       theta_j - half, theta_j + half)
    if status != ArcFate.SHRUNK:  # the picture is built to show a shrink; keep it honest
        msg = f"explainer geometry no longer shrinks the arc (outcome {status})"
        raise RuntimeError(msg)
    artists: list[Any] = []
    for x0, x1 in ((-0.7, jamb_left), (jamb_right, 2.6)):
        artists += ax.plot([x0, x1], [wall_y, wall_y], color="0.45", lw=4,
                           label="walls" if x0 < 0 else None)
    artists += plot_freespace(oj, rj, theta_j - half, theta_j + half, ax, color="#2ca02c",
                              alpha=0.18, label="free space of newer reading j")
    artists += plot_arc(oi, ri, lo_i, hi_i, ax, color="#d62728", ls="--", lw=1.5,
                        label="arc of older reading i (22.5° wide)")
    artists += plot_arc(oi, ri, new_lo, new_hi, ax, color="#1f77b4", lw=4,
                        label="arc i after carving")
    centre = oi + ri * np.array([math.cos(theta_i), math.sin(theta_i)])
    mid = 0.5 * (new_lo + new_hi)
    carved = oi + ri * np.array([math.cos(mid), math.sin(mid)])
    artists.append(ax.scatter(centre[0], centre[1], s=90, marker="x", color="#d62728", zorder=5,
                              label="centerline point: blocks the door"))
    artists.append(ax.scatter(carved[0], carved[1], s=60, color="#1f77b4", zorder=5,
                              label="carved point: at the jamb"))
    for origin, name in ((oi, "sensor, reading i"), (oj, "sensor, reading j (later)")):
        artists.append(ax.scatter(origin[0], origin[1], s=40, color="k", zorder=5))
        artists.append(ax.annotate(name, (origin[0], origin[1]), textcoords="offset points",
                                   xytext=(6, -12), fontsize="small"))
    artists.append(ax.annotate("0.9 m door", (0.95, wall_y), textcoords="offset points",
                               xytext=(-25, -22), fontsize="small", color="0.3"))
    ax.set_xlim(-0.7, 2.6)
    ax.set_ylim(-0.4, 3.3)
    ax.set_title("Arc carving: newer free space cuts older arcs")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper left", fontsize="small", framealpha=0.95)
    return artists


def write_carving_explainer(path: str | Path) -> None:
    """Write :func:`plot_carving_explainer` to ``path`` (the README's figure; .png, .svg or
    .pdf) with :func:`save_figure`: atomically, the figure closed after.

    Raises
    ------
    OutputError
        Another suffix, or a file that cannot be written.
    """
    ax = new_axes(7.0, 5.5)
    plot_carving_explainer(ax)
    save_figure(ax, path, dpi=110)


# -- a user's own map (``sonarcarve plot``) -------------------------------------------------------

#: Samples per arc drawn by :func:`plot_map_arcs` (a 22.5° arc of 5 m: 7 cm chords).
_ARC_SAMPLES = 24
#: Largest difference, seconds, between a map point's time and its reading's for the two to
#: be the same reading (:func:`map_origins`).
_SAME_TIME = 1e-6


class GridImage(NamedTuple):
    """A ROS map_server map as an image (design, "Grids").

    Attributes
    ----------
    image : ndarray of uint8, shape (h, w)
        Pixel values as a map_server image stores them (0 occupied, 205 unknown, 254 free in a
        trinary map), row 0 at the top (largest y).
    resolution : float
        Metres per pixel.
    origin : tuple of float
        World position (x, y) of the lower-left corner of the lower-left pixel, metres.
    """

    image: npt.NDArray[np.uint8]
    resolution: float
    origin: tuple[float, float]

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """Left, right, bottom, top in metres (matplotlib's ``extent``)."""
        h, w = self.image.shape
        x0, y0 = self.origin
        return x0, x0 + w * self.resolution, y0, y0 + h * self.resolution


def read_grid_image(path: str | Path) -> GridImage:
    """Read a ROS map_server map (``NAME.yaml`` beside its image) for drawing.

    Minimal on purpose: ``image`` (relative to the YAML's folder), ``resolution`` and
    ``origin`` ``[x, y, yaw]`` are read; ``negate: 1`` is undone so that dark is occupied in
    every map; a rotated map (yaw ≠ 0) is refused.

    Raises
    ------
    InputError
        One line naming the file and the problem (missing file or key, bad value, an image
        that cannot be read).
    """
    yaml_path = Path(path)
    data = load_yaml(yaml_path)
    if not isinstance(data, dict):
        msg = f"{yaml_path}: expected a map_server YAML mapping (image, resolution, origin)"
        raise InputError(msg)
    missing = [key for key in ("image", "resolution", "origin") if key not in data]
    if missing:
        msg = f"{yaml_path}: missing {', '.join(missing)} (a map_server map needs all three)"
        raise InputError(msg)
    resolution = finite_number(data["resolution"])
    if resolution is None or resolution <= 0:
        msg = f"{yaml_path}: resolution must be a number > 0 (metres per pixel)"
        raise InputError(msg)
    origin = data["origin"]
    values = ([finite_number(v) for v in origin] if isinstance(origin, list) else [])
    if len(values) != 3 or any(v is None for v in values):
        msg = f"{yaml_path}: origin must be [x, y, yaw], three numbers"
        raise InputError(msg)
    x0, y0, yaw = (float(v) for v in values if v is not None)
    if yaw != 0.0:
        msg = f"{yaml_path}: a rotated map (origin yaw {yaw:g}) is not supported"
        raise InputError(msg)
    image_path = yaml_path.parent / str(data["image"])
    pil = require("PIL.Image", "plot", "Image maps")
    try:
        with pil.open(image_path) as picture:
            image = np.asarray(picture.convert("L"), dtype=np.uint8)
    except FileNotFoundError:
        msg = f"{yaml_path}: image {image_path} does not exist"
        raise InputError(msg) from None
    except (OSError, ValueError) as err:
        msg = f"{yaml_path}: cannot read image {image_path} ({err})"
        raise InputError(msg) from None
    if data.get("negate") in (1, True):
        image = np.asarray(255 - image, dtype=np.uint8)
    return GridImage(image, resolution, (x0, y0))


#: Opacity of a map_server map drawn under a map (:func:`plot_grid`).
_GRID_ALPHA = 0.6


def plot_grid(grid: GridImage, ax: Axes | None = None, **style: Any) -> list[Any]:
    """Draw a map_server map in grey underneath everything else (occupied dark, free light)."""
    ax = ax or new_axes()
    options: dict[str, Any] = {"cmap": "gray", "vmin": 0, "vmax": 255, "origin": "upper",
                               "interpolation": "nearest", "zorder": 0,
                               "alpha": _GRID_ALPHA} | style
    return [ax.imshow(grid.image, extent=grid.extent, **options)]


#: Colours of a trinary map's cells, in the order free, unknown, occupied.
TRINARY_COLORS = ("#ffffff", "#c0c0c0", "#000000")


def plot_trinary(cells: npt.ArrayLike, extent: tuple[float, float, float, float],
                 ax: Axes | None = None, **style: Any) -> list[Any]:
    """Draw a trinary occupancy map: free white, unknown grey, occupied black
    (:data:`TRINARY_COLORS`).

    Parameters
    ----------
    cells : array-like of int, shape (rows, columns)
        ``nav_msgs/OccupancyGrid`` values (100 occupied, 0 free, -1 unknown; anything else is
        drawn as unknown), row 0 at the bottom (smallest y), as
        :func:`sonarcarve.grids.trinary` gives them.
    extent : tuple of float
        ``(xmin, ymin, xmax, ymax)`` covered by the cells, metres (a grid's ``extent``).
    """
    from matplotlib.colors import ListedColormap

    ax = ax or new_axes()
    values = np.asarray(cells)
    shade = np.select([values == 0, values == 100], [0, 2], 1)
    x0, y0, x1, y1 = extent
    options: dict[str, Any] = {"cmap": ListedColormap(TRINARY_COLORS), "vmin": 0, "vmax": 2,
                               "origin": "lower", "interpolation": "nearest"} | style
    return [ax.imshow(shade, extent=(x0, x1, y0, y1), **options)]


class MapOrigins(NamedTuple):
    """Where each map point's reading was heard from (see :func:`map_origins`).

    Attributes
    ----------
    xy : ndarray, shape (n, 2)
        Sensor origin of each point's reading, world frame, metres.
    range : ndarray, shape (n,)
        The reading's range r, metres.
    """

    xy: npt.NDArray[np.float64]
    range: npt.NDArray[np.float64]


def map_origins(points: LocalMap | GlobalMap, readings: ReadingBatch,
                source: str = "readings", map_file: str | None = None) -> MapOrigins:
    """Look up each map point's reading (``id`` = row of the readings it was made from).

    ``map_file``: the map CSV ``points`` were read from whole (:func:`read_map_csv`, point k on
    line k + 2); the errors then name its file and line instead of the point's index.

    Raises
    ------
    InputError
        An ``id`` beyond the readings, or a point whose ``t`` or ``sensor`` differs from its
        reading's: the map was not made from these readings (``source`` names them).
    """
    ids = points.reading_id
    n = len(readings)

    def point(k: int) -> str:
        return f"map point {k}" if map_file is None else f"{map_file}: line {k + 2}, map point"

    if len(ids) and int(ids.max()) >= n:
        bad = int(np.argmax(ids >= n))
        msg = (f"{point(bad)} has id {int(ids[bad])} but {source} has {n} rows: "
               "not the readings this map was made from")
        raise InputError(msg)
    # Times are compared loosely: a tool that rewrote one of the files may round them.
    same = (np.abs(readings.t[ids] - points.t) <= _SAME_TIME) & (
        readings.sensor[ids] == points.sensor)
    if not np.all(same):
        bad = int(np.argmin(same))
        rid = int(ids[bad])
        msg = (f"{point(bad)} (id {rid}, t {float(points.t[bad])!r}, sensor "
               f"{int(points.sensor[bad])}) does not match row {rid} of {source} (t "
               f"{float(readings.t[rid])!r}, sensor {int(readings.sensor[rid])}): not the "
               "readings this map was made from")
        raise InputError(msg)
    return MapOrigins(np.column_stack((readings.x[ids], readings.y[ids])), readings.range[ids])


def _source_colors(source: npt.NDArray[np.int8]) -> list[str]:
    return [SOURCE_COLORS[PointSource(int(code))] for code in source]


def plot_error_bounds(points: LocalMap | GlobalMap, ax: Axes | None = None,
                      **style: Any) -> list[Any]:
    """Draw each point's ``max_error`` as a circle of that radius about it, coloured by source.

    The bound (eq. 5.3 for arcs) says the true reflection lies within the circle. Points with
    an infinite bound (ATM with ψ = 0) get no circle.
    """
    from matplotlib.collections import EllipseCollection

    ax = ax or new_axes()
    keep = np.isfinite(points.max_error)
    if not np.any(keep):
        return []
    diameters = 2.0 * points.max_error[keep]
    options: dict[str, Any] = {"facecolors": "none", "linewidths": 0.6, "alpha": 0.6,
                               "zorder": 2} | style
    circles = EllipseCollection(diameters, diameters, np.zeros(len(diameters)), units="xy",
                                offsets=points.xy[keep], offset_transform=ax.transData,
                                edgecolors=_source_colors(points.source[keep]), **options)
    ax.add_collection(circles)
    ax.autoscale_view()
    return [circles]


def plot_map_arcs(points: LocalMap | GlobalMap, origins: MapOrigins, ax: Axes | None = None,
                  **style: Any) -> list[Any]:
    """Draw each point's final arc, coloured by source.

    The arc of a point is the circle of its reading's range about the sensor origin, over the
    point's final angular width ``width`` centred on the point's bearing from the origin (the
    carved interval of eq. 3.6 for carved points, the whole beam for centerline ones).
    """
    from matplotlib.collections import LineCollection

    ax = ax or new_axes()
    keep = np.isfinite(origins.range)
    if not np.any(keep):
        return []
    o, r = origins.xy[keep], origins.range[keep]
    delta = points.xy[keep] - o
    bearing = np.arctan2(delta[:, 1], delta[:, 0])
    half = 0.5 * points.width[keep]
    tau = bearing[:, None] + half[:, None] * np.linspace(-1.0, 1.0, _ARC_SAMPLES)[None, :]
    strips = np.stack((o[:, :1] + r[:, None] * np.cos(tau), o[:, 1:] + r[:, None] * np.sin(tau)),
                      axis=-1)
    options: dict[str, Any] = {"linewidths": 0.8, "alpha": 0.7, "zorder": 2} | style
    lines = LineCollection(list(strips), colors=_source_colors(points.source[keep]), **options)
    ax.add_collection(lines)
    ax.autoscale_view()
    return [lines]


def plot_path(readings: ReadingBatch, ax: Axes | None = None, **style: Any) -> list[Any]:
    """Draw the robot's path: the origins of each sensor's readings in time order, one line
    per sensor (a ring of sonars draws a band of parallel lines)."""
    from matplotlib.collections import LineCollection

    ax = ax or new_axes()
    lines = [np.column_stack((readings.x[mask], readings.y[mask]))
             for mask in (readings.sensor == s for s in np.unique(readings.sensor))]
    options: dict[str, Any] = {"colors": "0.3", "linewidths": 0.7, "zorder": 1,
                               "label": "sensor paths"} | style
    collection = LineCollection([line for line in lines if len(line) > 1], **options)
    ax.add_collection(collection)
    ax.autoscale_view()
    return [collection]


def plot_user_map(
    points: LocalMap | GlobalMap,
    ax: Axes | None = None,
    *,
    readings: ReadingBatch | None = None,
    grid: GridImage | None = None,
    error_bounds: bool = False,
    arcs: bool = False,
    title: str | None = None,
) -> list[Any]:
    """A map made from one's own data: points by source, optionally over a grid map, with the
    sensor paths, error circles and final arcs.

    Parameters
    ----------
    points : LocalMap or GlobalMap
        The map (e.g. :func:`~sonarcarve.io.read_map_csv` of ``sonarcarve process`` output).
    readings : ReadingBatch, optional
        The readings the map was made from (needed for ``arcs``); draws the sensor paths.
    grid : GridImage, optional
        Drawn underneath (:func:`read_grid_image`).
    error_bounds : bool
        Draw each point's ``max_error`` circle (:func:`plot_error_bounds`).
    arcs : bool
        Draw each point's final arc (:func:`plot_map_arcs`); needs ``readings``.
    title : str, optional
        Default: the counts of points by source (and of readings).

    Raises
    ------
    ConfigError
        ``arcs`` without ``readings``.
    InputError
        The map was not made from ``readings`` (:func:`map_origins`).
    """
    if arcs and readings is None:
        msg = "arcs needs readings, the log the map was made from"
        raise ConfigError(msg)
    origins = map_origins(points, readings) if readings is not None else None
    ax = ax or new_axes(8.0, 7.0)
    ax.set_aspect("equal")
    artists: list[Any] = []
    if grid is not None:
        artists += plot_grid(grid, ax)
    if readings is not None:
        artists += plot_path(readings, ax)
    if arcs and origins is not None:
        artists += plot_map_arcs(points, origins, ax)
    if error_bounds:
        artists += plot_error_bounds(points, ax)
    artists += plot_map(points, ax, size=6.0, legend=False)
    handles = ax.get_legend_handles_labels()[0] + _overlay_keys(
        grid=grid is not None, arcs=arcs and origins is not None, error_bounds=error_bounds)
    if handles:
        ax.legend(handles=handles, loc="best", fontsize="small", markerscale=2)
    if title is None:
        counts = ", ".join(f"{points.count(source):,} {source.label}" for source in PointSource)
        title = f"{len(points):,} points ({counts})"
        if readings is not None:
            title += f" from {len(readings):,} readings"
    ax.set_title(title, fontsize="medium")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return artists


#: The pixels of a trinary map_server map (map_saver's, and ``sonarcarve grid``'s): legend
#: label -> pixel value.
_GRID_PIXELS = {"grid: occupied": 0, "grid: unknown": 205, "grid: free": 254}


def _overlay_keys(*, grid: bool, arcs: bool, error_bounds: bool) -> list[Any]:
    """Legend keys of what :func:`plot_user_map` draws without a label of its own: the grid's
    shades, the arcs and the error circles (each drawn in its point's source colour, so the
    key is grey)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    keys: list[Any] = []
    if grid:
        # As plot_grid shows the pixel: grey level value/255 at _GRID_ALPHA over white.
        keys += [Patch(facecolor=str(1.0 - _GRID_ALPHA * (1.0 - value / 255.0)),
                       edgecolor="0.5", label=label) for label, value in _GRID_PIXELS.items()]
    if arcs:
        keys.append(Line2D([], [], color="0.45", lw=0.8, label="final arc of each point"))
    if error_bounds:
        keys.append(Line2D([], [], ls="none", marker="o", markersize=7, mfc="none", mec="0.45",
                           label="error bound (circle of radius max_error)"))
    return keys


#: Figure formats :func:`save_figure` writes, by file suffix.
FIGURE_FORMATS = ("png", "svg", "pdf")


def check_figure_path(path: str | Path, *, label: str | None = None) -> str:
    """The format of the figure file ``path`` from its suffix, one of :data:`FIGURE_FORMATS`.

    ``label`` names the path in the message (e.g. ``"--out map.jpg"``); default: the path.

    Raises
    ------
    OutputError
        Another suffix.

    Examples
    --------
    >>> check_figure_path("map.PNG")
    'png'
    """
    kind = Path(path).suffix.lower().removeprefix(".")
    if kind not in FIGURE_FORMATS:
        msg = f"{label if label is not None else path}: expected a .png, .svg or .pdf file name"
        raise OutputError(msg)
    return kind


def save_figure(ax: Axes, path: str | Path, *, dpi: int = 150) -> None:
    """Write the figure of ``ax`` atomically (format from the suffix: .png, .svg or .pdf) and
    close it.

    Raises
    ------
    OutputError
        Another suffix (:func:`check_figure_path`), or a file that cannot be written (the
        message names it and the reason).
    """
    import matplotlib.pyplot as plt

    target = Path(path)
    figure = ax.get_figure(root=True)
    try:
        kind = check_figure_path(target)
        if figure is None:  # an axes always has a figure; mypy does not know
            msg = "the axes belong to no figure"
            raise ValueError(msg)
        with atomic_path(target, suffix=f".{kind}") as tmp:
            figure.savefig(tmp, format=kind, dpi=dpi)
    finally:
        if figure is not None:
            plt.close(figure)
