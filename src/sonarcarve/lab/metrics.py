"""Measures of sonar maps on plain arrays: binning by range, true error, passable gaps, latency.

Every function here takes numpy arrays (points, segments, times) and no simulator or method
objects, so each can be checked by hand on constructed inputs. The experiments in
:mod:`sonarcarve.lab.experiments` feed them from recorded runs.

Conventions: metres, seconds, radians; points are arrays of shape (n, 2); wall segments are
arrays of shape (m, 4) holding ``(x1, y1, x2, y2)``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numba
import numpy as np
import numpy.typing as npt

from sonarcarve.typing import FloatArray, IntArray

__all__ = [
    "OFF_BEAM_TOLERANCE",
    "BinnedStats",
    "ErrorSummary",
    "GapRegion",
    "PatchIndex",
    "binned",
    "combine_binned",
    "count_near_segment",
    "error_summary",
    "first_at_least",
    "free_width",
    "gap_region",
    "is_passable",
    "off_beam",
    "patch_index",
    "patch_latency",
    "patch_of_points",
    "percent",
    "range_bin_index",
    "resolved_share_curve",
    "segment_distance",
]



# -- ratios and binning ------------------------------------------------------------------------

def percent(mask: npt.ArrayLike) -> float:
    """Share of true values in ``mask`` in percent; NaN for an empty mask.

    Examples
    --------
    >>> percent([True, False, False, False])
    25.0
    """
    m = np.asarray(mask, dtype=bool)
    return float(100.0 * np.count_nonzero(m) / m.size) if m.size else math.nan


def range_bin_index(values: npt.ArrayLike, edges: npt.ArrayLike) -> IntArray:
    """Bin of each value for bins ``[edges[k], edges[k+1])``; -1 outside ``[edges[0], edges[-1])``.

    Examples
    --------
    >>> range_bin_index([0.0, 0.49, 0.5, 2.0, -1.0], [0.0, 0.5, 1.0]).tolist()
    [0, 0, 1, -1, -1]
    """
    v = np.asarray(values, dtype=np.float64)
    e = np.asarray(edges, dtype=np.float64)
    k = np.searchsorted(e, v, side="right") - 1
    inside = (v >= e[0]) & (v < e[-1])
    return np.where(inside, k, -1).astype(np.int64)


class BinnedStats(NamedTuple):
    """Statistics of a quantity per bin of another, arrays of shape (bins,).

    Attributes
    ----------
    edges : ndarray, shape (bins + 1,)
        Bin edges.
    counts : ndarray of int64
        Values per bin.
    mean, median, p90 : ndarray
        Statistics per bin; NaN in empty bins.
    """

    edges: FloatArray
    counts: IntArray
    mean: FloatArray
    median: FloatArray
    p90: FloatArray

    @property
    def centers(self) -> FloatArray:
        """Bin centres."""
        return np.asarray(0.5 * (self.edges[1:] + self.edges[:-1]))

    def as_dict(self) -> dict[str, list[float | None] | list[int]]:
        """JSON-ready lists (NaN becomes None)."""
        return {
            "edges": _json_list(self.edges),
            "count": [int(c) for c in self.counts],
            "mean": _json_list(self.mean),
            "median": _json_list(self.median),
            "p90": _json_list(self.p90),
        }


def binned(values: npt.ArrayLike, keys: npt.ArrayLike, edges: npt.ArrayLike) -> BinnedStats:
    """Mean, median and 90th percentile of ``values`` grouped by the bin of ``keys``.

    Parameters
    ----------
    values : array-like, shape (n,)
        The measured quantity (for example 1.0 for unprocessed, 0.0 for processed).
    keys : array-like, shape (n,)
        What to bin by (for example the range of each arc, metres).
    edges : array-like, shape (bins + 1,)
        Increasing bin edges; bins are ``[edges[k], edges[k+1])``.
    """
    v = np.asarray(values, dtype=np.float64).reshape(-1)
    e = np.asarray(edges, dtype=np.float64)
    k = range_bin_index(keys, e)
    bins = e.size - 1
    counts = np.zeros(bins, dtype=np.int64)
    mean = np.full(bins, np.nan)
    median = np.full(bins, np.nan)
    p90 = np.full(bins, np.nan)
    for b in range(bins):
        sel = v[k == b]
        counts[b] = sel.size
        if sel.size:
            mean[b] = float(np.mean(sel))
            median[b] = float(np.median(sel))
            p90[b] = float(np.percentile(sel, 90.0))
    return BinnedStats(e, counts, mean, median, p90)


def combine_binned(entries: Sequence[Mapping[str, Any]], stat: str = "mean") -> dict[str, Any]:
    """Several runs' binned curves as one (for example one curve per simulation seed).

    Parameters
    ----------
    entries : sequence of dict
        :meth:`BinnedStats.as_dict` outputs over the same edges (None marks an empty bin).
    stat : str
        Which statistic to combine: ``mean``, ``median`` or ``p90``.

    Returns
    -------
    dict
        ``edges``; per bin ``value`` (mean over the runs whose bin is not empty), ``min`` and
        ``max`` over those runs (None where every run's bin is empty); ``count`` summed.

    Examples
    --------
    >>> a = {"edges": [0.0, 1.0, 2.0], "median": [1.0, None], "count": [2, 0]}
    >>> b = {"edges": [0.0, 1.0, 2.0], "median": [3.0, None], "count": [1, 0]}
    >>> combine_binned([a, b], "median")
    {'edges': [0.0, 1.0, 2.0], 'value': [2.0, None], 'min': [1.0, None], 'max': [3.0, None], \
'count': [3, 0]}
    """
    rows = np.array([[np.nan if x is None else x for x in e[stat]] for e in entries],
                    dtype=np.float64)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: empty bins
        mean = np.nanmean(rows, axis=0)
        lo = np.nanmin(rows, axis=0)
        hi = np.nanmax(rows, axis=0)
    counts = np.sum([e["count"] for e in entries], axis=0)
    return {"edges": list(entries[0]["edges"]), "value": _json_list(mean),
            "min": _json_list(lo), "max": _json_list(hi), "count": [int(c) for c in counts]}


# -- error bounds and true error ---------------------------------------------------------------

class ErrorSummary(NamedTuple):
    """Median, 90th percentile and mean of distances, metres, and how many there were."""

    median: float
    p90: float
    mean: float
    n: int

    def as_dict(self) -> dict[str, float | int | None]:
        """JSON-ready (NaN becomes None)."""
        return {"median": _json_float(self.median), "p90": _json_float(self.p90),
                "mean": _json_float(self.mean), "n": self.n}


def error_summary(distances: npt.ArrayLike) -> ErrorSummary:
    """Summary of non-negative distances (NaN entries are ignored)."""
    d = np.asarray(distances, dtype=np.float64).reshape(-1)
    d = d[np.isfinite(d)]
    if not d.size:
        return ErrorSummary(math.nan, math.nan, math.nan, 0)
    return ErrorSummary(float(np.median(d)), float(np.percentile(d, 90.0)), float(np.mean(d)),
                        int(d.size))


def segment_distance(points: npt.ArrayLike, segments: npt.ArrayLike) -> tuple[FloatArray, IntArray]:
    """Distance from each point to the nearest of ``segments`` and that segment's index.

    Parameters
    ----------
    points : array-like, shape (n, 2)
    segments : array-like, shape (m, 4), m >= 1

    Returns
    -------
    distance : ndarray, shape (n,)
        Euclidean distance to the closest point of the closest segment, metres.
    nearest : ndarray of int64, shape (n,)
        Index of that segment.

    Examples
    --------
    >>> d, i = segment_distance([[0.0, 1.0], [3.0, 4.0]], [[-1.0, 0.0, 1.0, 0.0]])
    >>> d.tolist(), i.tolist()
    ([1.0, 4.47213595499958], [0, 0])
    """
    p = np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 2))
    seg = np.ascontiguousarray(np.asarray(segments, dtype=np.float64).reshape(-1, 4))
    if not seg.shape[0]:
        return np.full(p.shape[0], np.inf), np.full(p.shape[0], -1, dtype=np.int64)
    return _segment_distance(p, seg)


@numba.njit(cache=True)
def _segment_distance(p: FloatArray, seg: FloatArray) -> tuple[FloatArray, IntArray]:
    # Brute force over every (point, wall) pair, compiled: exact and fast enough for a few
    # hundred thousand map points against a few hundred walls (no spatial index to get wrong).
    n, m = p.shape[0], seg.shape[0]
    distance = np.empty(n)
    nearest = np.empty(n, dtype=np.int64)
    for i in range(n):
        best, arg = np.inf, -1
        px, py = p[i, 0], p[i, 1]
        for j in range(m):
            ax, ay = seg[j, 0], seg[j, 1]
            ex, ey = seg[j, 2] - ax, seg[j, 3] - ay
            length2 = ex * ex + ey * ey
            u = 0.0
            if length2 > 0.0:
                u = min(1.0, max(0.0, ((px - ax) * ex + (py - ay) * ey) / length2))
            dx, dy = px - (ax + u * ex), py - (ay + u * ey)
            d2 = dx * dx + dy * dy
            if d2 < best:
                best, arg = d2, j
        distance[i] = math.sqrt(best)
        nearest[i] = arg
    return distance, nearest


#: How far outside its beam, measured along the arc, a reflector may lie and still count as
#: heard inside it (:func:`off_beam`): the default range tolerance ε of the methods, so that
#: rays at the beam's edge, rounded bearings and a pose stamped a sample late stay inside.
OFF_BEAM_TOLERANCE = 0.05


def off_beam(sensor_xy: npt.ArrayLike, theta: npt.ArrayLike, beam_width: npt.ArrayLike,
             reflection: npt.ArrayLike,
             tolerance: float = OFF_BEAM_TOLERANCE) -> npt.NDArray[np.bool_]:
    """Which echoes came from outside the beam the methods were told: side lobes, or a sonar
    that hears wider than its declared width.

    Every method draws an echo as the arc of its range over ``theta ± beam_width / 2`` (the
    paper's section 2). An echo whose true reflector lies off that arc (its bearing from the
    sensor more than ``tolerance`` metres of arc beyond either edge) can give no point on the
    surface that returned it, so a measure of "true echoes kept" should count it apart
    (``docs/RESULTS.md``, *Other sonars*: at a 45° amplitude beam 39 % of the direct echoes are
    such, mean of four worlds and three seeds).

    Parameters
    ----------
    sensor_xy : array-like, shape (n, 2)
        Sensor positions, metres.
    theta, beam_width : array-like, shape (n,)
        Sensor axes and the beam widths the methods were told, radians.
    reflection : array-like, shape (n, 2)
        True reflection points; NaN rows (no reflector, as for floor echoes) are never off-beam.
    tolerance : float
        Metres of arc beyond an edge still counted inside.

    Returns
    -------
    ndarray of bool, shape (n,)

    Examples
    --------
    >>> off_beam([[0.0, 0.0]] * 3, [0.0] * 3, [math.radians(22.5)] * 3,
    ...          [[1.0, 0.1], [0.0, 1.0], [np.nan, np.nan]]).tolist()
    [False, True, False]
    """
    xy = np.asarray(sensor_xy, dtype=np.float64).reshape(-1, 2)
    hit = np.asarray(reflection, dtype=np.float64).reshape(-1, 2)
    dx, dy = hit[:, 0] - xy[:, 0], hit[:, 1] - xy[:, 1]
    bearing = np.angle(np.exp(1j * (np.arctan2(dy, dx) - np.asarray(theta, dtype=np.float64))))
    outside = np.abs(bearing) - 0.5 * np.asarray(beam_width, dtype=np.float64)
    return np.asarray(np.hypot(dx, dy) * outside > tolerance)  # NaN (no reflector): False


def count_near_segment(points: npt.ArrayLike, segment: npt.ArrayLike, radius: float) -> int:
    """Number of ``points`` within ``radius`` metres of one segment ``(x1, y1, x2, y2)``."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if not p.shape[0]:
        return 0
    d, _ = segment_distance(p, np.asarray(segment, dtype=np.float64).reshape(1, 4))
    return int(np.count_nonzero(d <= radius))


def first_at_least(counts: npt.ArrayLike, threshold: int) -> int:
    """Index of the first entry of ``counts`` that is ``>= threshold``, or -1 if none is.

    Examples
    --------
    >>> first_at_least([0, 1, 3, 2, 5], 3)
    2
    >>> first_at_least([0, 1], 3)
    -1
    """
    c = np.asarray(counts)
    hit = np.flatnonzero(c >= threshold)
    return int(hit[0]) if hit.size else -1


# -- passable openings (Fig. 2 and 9) ----------------------------------------------------------

class GapRegion(NamedTuple):
    """The region of an opening that map points must leave free for the robot to pass.

    The opening runs from jamb ``a`` to jamb ``b`` (the wall ends, metres). The region is the
    rectangle ``{a + s u + h n : 0 <= s <= width, |h| <= depth}`` with ``u`` the unit vector from
    ``a`` to ``b`` and ``n`` its normal: the gap itself, thickened by ``depth`` on both sides.
    """

    a: FloatArray
    u: FloatArray
    n: FloatArray
    width: float
    depth: float


def gap_region(jamb_a: npt.ArrayLike, jamb_b: npt.ArrayLike, depth: float) -> GapRegion:
    """The :class:`GapRegion` between two jamb points, thickened ``depth`` metres each side."""
    a = np.asarray(jamb_a, dtype=np.float64).reshape(2)
    b = np.asarray(jamb_b, dtype=np.float64).reshape(2)
    width = float(np.hypot(*(b - a)))
    if width <= 0.0:
        msg = "the two jambs of an opening must differ"
        raise ValueError(msg)
    u = (b - a) / width
    return GapRegion(a, u, np.array([-u[1], u[0]]), width, float(depth))


def free_width(points: npt.ArrayLike, region: GapRegion) -> float:
    """Widest stretch of the opening with no map point in the region across it, metres.

    Each map point inside ``region`` blocks the opening at its position ``s`` along the gap
    (its projection on the jamb-to-jamb line); the free width is the largest distance between
    neighbouring blocked positions, the two jambs (``s = 0`` and ``s = width``) included.
    Points outside the region (beyond the jambs along the wall, or farther than ``depth`` from
    the gap line) do not narrow it.

    Examples
    --------
    >>> g = gap_region([0.0, 0.0], [1.0, 0.0], depth=0.2)
    >>> free_width(np.zeros((0, 2)), g)
    1.0
    >>> free_width([[0.3, 0.1], [0.5, 0.5]], g)  # the second point is too far from the gap
    0.7
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2) - region.a
    s = p @ region.u
    h = p @ region.n
    inside = (s >= 0.0) & (s <= region.width) & (np.abs(h) <= region.depth)
    blocked = np.sort(np.concatenate(([0.0], s[inside], [region.width])))
    return float(np.max(np.diff(blocked)))


def is_passable(points: npt.ArrayLike, region: GapRegion, clearance: float) -> bool:
    """Whether the map leaves a stretch at least ``clearance`` metres wide (robot + margin)."""
    return free_width(points, region) >= clearance


# -- surface patches and latency-vs-accuracy ---------------------------------------------------

class PatchIndex(NamedTuple):
    """Walls cut into pieces of at most ``length`` metres; patch ``k`` is piece
    ``piece[k]`` of wall ``segment[k]``, starting ``piece[k] * length`` metres from its first end.
    """

    segment: IntArray
    piece: IntArray
    first: IntArray  #: first patch id of each wall, shape (walls,)
    length: float

    def __len__(self) -> int:
        return int(self.segment.shape[0])


def patch_index(segments: npt.ArrayLike, length: float) -> PatchIndex:
    """Cut every wall of ``segments`` (shape (m, 4)) into ``ceil(L / length)`` patches."""
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    lengths = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    pieces = np.maximum(1, np.ceil(lengths / length - 1e-9)).astype(np.int64)
    first = np.concatenate(([0], np.cumsum(pieces)[:-1])).astype(np.int64)
    segment = np.repeat(np.arange(seg.shape[0], dtype=np.int64), pieces)
    piece = np.arange(int(pieces.sum()), dtype=np.int64) - np.repeat(first, pieces)
    return PatchIndex(segment, piece, first, float(length))


def patch_of_points(
    points: npt.ArrayLike, segments: npt.ArrayLike, patches: PatchIndex, tolerance: float = 1e-3
) -> IntArray:
    """The patch each point lies on, or -1 for NaN points and points off every wall.

    Parameters
    ----------
    points : array-like, shape (n, 2)
        Points on walls (for example true reflection points), NaN where there is none.
    segments : array-like, shape (m, 4)
        The walls the patches were cut from.
    patches : PatchIndex
        From :func:`patch_index` on the same ``segments``.
    tolerance : float
        Points farther than this from every wall get -1, metres.
    """
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    out = np.full(p.shape[0], -1, dtype=np.int64)
    ok = np.all(np.isfinite(p), axis=1)
    if not np.any(ok) or not seg.shape[0]:
        return out
    d, k = segment_distance(p[ok], seg)
    along = np.hypot(p[ok, 0] - seg[k, 0], p[ok, 1] - seg[k, 1])
    pieces = np.diff(np.concatenate((patches.first, [len(patches)])))
    piece = np.minimum((along / patches.length).astype(np.int64), pieces[k] - 1)
    out[ok] = np.where(d <= tolerance, patches.first[k] + piece, -1)
    return out


def patch_latency(
    *,
    reading_patch: npt.ArrayLike,
    reading_t: npt.ArrayLike,
    sample_t: npt.ArrayLike,
    row_sample: npt.ArrayLike,
    row_reading: npt.ArrayLike,
    row_error: npt.ArrayLike,
    n_patches: int,
    tolerance: float,
    quorum: float = 0.5,
) -> tuple[FloatArray, FloatArray]:
    """When each surface patch was first seen, and when the local map first had it right.

    A patch is *seen* at the time of the first reading whose true reflection lies on it. At a
    sample time, the patch's map points are the local-map points of readings whose reflection
    lies on it; the patch is *resolved* at the first sample time (not before it was seen) at
    which it has at least one such point and at least ``quorum`` of them (0.5: the median point)
    are within ``tolerance`` metres of the true walls.

    Parameters
    ----------
    reading_patch : array-like of int, shape (readings,)
        Patch of each reading's true reflection, -1 for none (indexed by reading id).
    reading_t : array-like, shape (readings,)
        Time of each reading, seconds.
    sample_t : array-like, shape (samples,)
        Times at which the local map was sampled, increasing.
    row_sample, row_reading : array-like of int, shape (rows,)
        For every local-map point of every sample: the sample index and the reading id.
    row_error : array-like, shape (rows,)
        That point's distance to the true walls, metres.
    n_patches : int
        Number of patches.
    tolerance : float
        Error bound for "right", metres.
    quorum : float
        Share of the patch's points that must be within ``tolerance``.

    Returns
    -------
    seen : ndarray, shape (n_patches,)
        Time first seen, seconds; inf if never.
    resolved : ndarray, shape (n_patches,)
        Time first resolved, seconds; inf if never.
    """
    rp = np.asarray(reading_patch, dtype=np.int64)
    seen = _first_seen(rp, np.asarray(reading_t, dtype=np.float64), n_patches)
    ok_sample, ok_patch = _right_pairs(
        rp, np.asarray(row_sample, dtype=np.int64), np.asarray(row_reading, dtype=np.int64),
        np.asarray(row_error, dtype=np.float64) <= tolerance, n_patches, quorum,
    )
    ok_t = np.asarray(sample_t, dtype=np.float64)[ok_sample]
    # A patch cannot be resolved before it was seen: earlier right samples do not count.
    after = ok_t >= seen[ok_patch]
    resolved = np.full(n_patches, np.inf)
    np.minimum.at(resolved, ok_patch[after], ok_t[after])
    return seen, resolved


def _first_seen(reading_patch: IntArray, reading_t: FloatArray, n_patches: int) -> FloatArray:
    """Time of the first reading on each patch (see :func:`patch_latency`).

    Parameters
    ----------
    reading_patch : ndarray of int64, shape (readings,)
        Patch of each reading's true reflection, -1 for none.
    reading_t : ndarray, shape (readings,)
        Time of each reading, seconds.
    n_patches : int
        Number of patches.

    Returns
    -------
    ndarray, shape (n_patches,)
        Earliest reading time per patch, seconds; inf for a patch no reading hit.
    """
    seen = np.full(n_patches, np.inf)
    has = reading_patch >= 0
    np.minimum.at(seen, reading_patch[has], reading_t[has])
    return seen


def _right_pairs(
    reading_patch: IntArray,
    row_sample: IntArray,
    row_reading: IntArray,
    row_good: npt.NDArray[np.bool_],
    n_patches: int,
    quorum: float,
) -> tuple[IntArray, IntArray]:
    """The (sample, patch) pairs at which the local map had the patch right.

    Parameters
    ----------
    reading_patch : ndarray of int64, shape (readings,)
        Patch of each reading's true reflection, -1 for none.
    row_sample, row_reading : ndarray of int64, shape (rows,)
        Sample index and reading id of every local-map point of every sample.
    row_good : ndarray of bool, shape (rows,)
        Whether that point is within tolerance of the true walls.
    n_patches : int
        Number of patches.
    quorum : float
        Share of a pair's points that must be good.

    Returns
    -------
    sample, patch : ndarray of int64, shape (pairs,)
        The pairs with at least one point, at least ``quorum`` of them good, ordered by sample
        then patch.
    """
    patch = reading_patch[row_reading]
    keep = patch >= 0
    rs, patch, good = row_sample[keep], patch[keep], row_good[keep]
    # Count points and good points per (sample, patch) pair present, via one joint key.
    key = rs * n_patches + patch
    pairs, inverse = np.unique(key, return_inverse=True)
    total = np.bincount(inverse, minlength=pairs.size)
    within = np.bincount(inverse, weights=good.astype(np.float64), minlength=pairs.size)
    ok = (within >= quorum * total) & (total > 0)
    return pairs[ok] // n_patches, pairs[ok] % n_patches


def resolved_share_curve(delays: npt.ArrayLike, grid: npt.ArrayLike) -> FloatArray:
    """Percentage of patches whose delay is ``<= grid[k]``, for every ``k`` (inf never counts).

    Examples
    --------
    >>> resolved_share_curve([0.0, 1.0, np.inf, 3.0], [0.5, 1.0, 10.0]).tolist()
    [25.0, 50.0, 75.0]
    """
    d = np.asarray(delays, dtype=np.float64).reshape(-1)
    g = np.asarray(grid, dtype=np.float64)
    if not d.size:
        return np.full(g.shape, np.nan)
    return np.asarray(100.0 * np.mean(d[:, None] <= g[None, :], axis=0))


def _json_float(x: float) -> float | None:
    return None if not math.isfinite(x) else float(x)


def _json_list(a: npt.ArrayLike) -> list[float | None]:
    return [_json_float(float(x)) for x in np.asarray(a, dtype=np.float64).reshape(-1)]
