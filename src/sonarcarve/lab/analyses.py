"""What the experiments measure in one method run: the analyses of a recorded run.

Each ``analyse_*`` function takes the simulation (readings and their ground truth), the
:class:`~sonarcarve.lab.instrument.RunRecord` of one method over it and the job that made
it, and returns a small JSON-ready dict; :mod:`sonarcarve.lab.experiments` plans the runs
and summarises these dicts over seeds. :data:`ANALYSES` names them for the jobs.

*Unprocessed* shares here are over every history row (:func:`~sonarcarve.lab.instrument.
unprocessed_percent`): an arc carving removed counts as processed, as the library's
``processed`` flag has it; ``unprocessed_alive`` leaves removed arcs out, as the paper's
history, which drops them, would.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from sonarcarve.lab import metrics
from sonarcarve.lab.instrument import (
    ArcTable,
    RunRecord,
    full_history_samples,
    sample_points,
    unprocessed_percent,
)
from sonarcarve.maps import PointSource
from sonarcarve.methods import MethodConfig
from sonarcarve.methods.atm import atm_error_bound
from sonarcarve.methods.base import ArcFate
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import EchoKind
from sonarcarve.typing import FloatArray, JsonDict

if TYPE_CHECKING:
    from sonarcarve.lab.plan import Job

__all__ = [
    "ANALYSES",
    "CLEARANCE_MARGIN",
    "GAP_DEPTH",
    "LATENCY_GRID_M",
    "LATENCY_GRID_S",
    "METHOD_LABELS",
    "OPENING_DISTANCES",
    "PATCH_LENGTH",
    "PATCH_TOLERANCES",
    "RANGE_EDGES",
    "WALL_POINTS",
    "WALL_RADIUS",
    "analyse_office",
    "analyse_opening",
    "analyse_sweep",
    "analyse_t_junction",
    "fig13_keep",
    "fig13_threshold",
    "first_reading_within",
    "latency_accuracy",
    "passage_clearance",
    "removal_summary",
    "truth_breakdown",
]


#: Method CLI name -> the label used in results (the paper's names).
METHOD_LABELS = {"centerline": "centerline", "carve": "carving", "atm": "atm",
                 "combined": "combined", "evidence": "evidence"}
#: Range bins of Fig. 10-12, metres: 0.5 m wide up to the Scout2's 6.477 m maximum range.
RANGE_EDGES = tuple(np.round(np.arange(0.0, 7.0 + 1e-9, 0.5), 3).tolist())
#: Fig. 4: the facing wall "shows" once this many local-map points lie within the radius of it.
WALL_POINTS = 3
WALL_RADIUS = 0.10
#: Fig. 2 and 9: clearance the robot needs (Scout2 diameter 0.41 m + 5 cm margin) and how far
#: either side of the gap line a map point blocks the gap, metres.
CLEARANCE_MARGIN = 0.05
GAP_DEPTH = 0.25
#: Fig. 2 and 9: distances before an opening at which its passability is judged, metres.
OPENING_DISTANCES = (1.0, 2.0, 3.0)
#: Latency against accuracy: wall patches of this length, and the error tolerances, metres.
PATCH_LENGTH = 0.5
PATCH_TOLERANCES = (0.05, 0.10)
#: Latency against accuracy: the delays (seconds) and distances driven (metres) the
#: resolved-share curves are sampled at.
LATENCY_GRID_S = tuple(np.round(np.linspace(0.0, 60.0, 121), 3).tolist())
LATENCY_GRID_M = tuple(np.round(np.linspace(0.0, 20.0, 101), 3).tolist())


def passage_clearance(robot_radius: float) -> float:
    """Free width a robot of ``robot_radius`` metres needs to pass an opening: its diameter
    plus :data:`CLEARANCE_MARGIN`, metres (Fig. 2 and 9)."""
    return 2.0 * robot_radius + CLEARANCE_MARGIN


def analyse_office(sim: Simulation, record: RunRecord, job: Job,
                   detail: bool = False) -> JsonDict:
    """Table I, Fig. 10-12, fully carved, true error, latency-vs-accuracy for one run.

    ``unprocessed`` (Table I) and ``unprocessed_by_range`` (Fig. 10) count every history row,
    so arcs carving removed count as processed; ``unprocessed_alive`` leaves them out, as the
    paper's history, which drops removed arcs, would. Both over the snapshots taken once the
    history is full (:func:`~sonarcarve.lab.instrument.full_history_samples`).
    """
    edges = np.asarray(RANGE_EDGES)
    full = full_history_samples(record, job.config.history_size)
    out: JsonDict = {
        "unprocessed": unprocessed_percent(full),
        "unprocessed_alive": unprocessed_percent(full, live_only=True),
        "unprocessed_by_range": metrics.binned(
            (~full.processed).astype(float) * 100.0, full.range, edges).as_dict(),
    }
    final = record.final
    live = final.select(final.alive)
    carved = live.select(live.source == PointSource.CARVED)
    out["width_by_range"] = metrics.binned(np.degrees(live.width), live.range, edges).as_dict()
    out["carved_width_by_range"] = metrics.binned(
        np.degrees(carved.width), carved.range, edges).as_dict()
    out["max_error_by_range"] = metrics.binned(live.max_error, live.range, edges).as_dict()
    out["removal"] = removal_summary(final, sim.truth.kind)
    # True error of every local-map point at every snapshot (what the robot navigated on).
    points = sample_points(record)
    err = metrics.segment_distance(points.xy, sim.world.segments)[0]
    out["true_error"] = metrics.error_summary(err).as_dict()
    out["true_error_by_range"] = metrics.binned(err, points.range, edges).as_dict()
    gmap = record.global_map
    gerr = metrics.segment_distance(gmap.xy, sim.world.segments)[0]
    kept = fig13_keep(gmap.source, gmap.max_error, job.method, fig13_threshold(job.config))
    out["global_error"] = metrics.error_summary(gerr).as_dict()
    out["global_points"] = len(gmap)
    out["thresholded_points"] = int(np.count_nonzero(kept))
    out["thresholded_error"] = metrics.error_summary(gerr[kept]).as_dict()
    out["latency_accuracy"] = latency_accuracy(sim, record, points, err)
    out["truth_breakdown"] = truth_breakdown(sim, final, gmap.reading_id, gerr)
    out["duration"] = sim.trajectory.duration
    if detail:
        out["global_map"] = {"xy": gmap.xy[kept], "source": gmap.source[kept],
                             "world": sim.world.segments}
    return out


def truth_breakdown(sim: Simulation, final: ArcTable, map_reading: npt.NDArray[np.int64],
                    map_error: FloatArray) -> JsonDict:
    """Why a map's error is what it is: what it kept and lost, judged by the simulator's truth.

    Returns the global map's share of spurious points (percent) and the true error of its
    points from direct readings only (so maps that keep different readings can be compared);
    the median range and centerline error (metres) of the direct readings the method removed
    and of those it kept; and, for arcs placed by carving, the share (percent) whose final
    interval still contains the bearing of the true reflection.
    """
    kind = sim.truth.kind
    direct_map = kind[map_reading] == EchoKind.DIRECT
    b = sim.readings
    axis = np.column_stack((b.x + b.range * np.cos(b.theta), b.y + b.range * np.sin(b.theta)))
    rid = final.reading_id
    direct = kind[rid] == EchoKind.DIRECT
    lost = direct & ~final.alive
    kept = direct & final.alive
    centerline_err = metrics.segment_distance(axis[rid[lost | kept]], sim.world.segments)[0]
    err_of = dict(zip(rid[lost | kept].tolist(), centerline_err.tolist(), strict=True))
    carved = kept & (final.source == PointSource.CARVED)
    truth = sim.truth.reflection[rid[carved]]
    origin = np.column_stack((b.x[rid[carved]], b.y[rid[carved]]))
    true_bearing = np.arctan2(truth[:, 1] - origin[:, 1], truth[:, 0] - origin[:, 0])
    point = final.xy[carved]
    centre = np.arctan2(point[:, 1] - origin[:, 1], point[:, 0] - origin[:, 0])
    off = np.abs(np.angle(np.exp(1j * (true_bearing - centre))))
    return {
        "spurious_share": metrics.percent(~direct_map),
        "direct_error": metrics.error_summary(map_error[direct_map]).as_dict(),
        "lost_direct_median_range": _median_or_none(final.range[lost]),
        "kept_direct_median_range": _median_or_none(final.range[kept]),
        "lost_direct_centerline_error": _median_or_none(
            np.array([err_of[i] for i in rid[lost].tolist()])),
        "kept_direct_centerline_error": _median_or_none(
            np.array([err_of[i] for i in rid[kept].tolist()])),
        "carved_contains_truth": metrics.percent(off <= 0.5 * final.width[carved] + 1e-9),
    }


def fig13_threshold(config: MethodConfig) -> float:
    """Fig. 13's max-error threshold, metres: ATM's own guaranteed bound (eq. 5.4 times δ).

    A carved point is kept when its bound (eq. 5.3) is no worse than what ATM guarantees for
    its crossings, so the two maps promise the same accuracy.
    """
    return atm_error_bound(config.min_transversal, config.range_resolution)


def fig13_keep(source: npt.NDArray[np.int8], max_error: FloatArray, method: str,
               threshold: float) -> npt.NDArray[np.bool_]:
    """Points of a global map shown in Fig. 13.

    ATM's map (a) shows the medians of transversal intersections only (no centerline
    fallbacks); every other map (b) keeps the points whose bound is within ``threshold``.
    """
    if method == "atm":
        return np.asarray(source == PointSource.ATM)
    return np.asarray(max_error <= threshold)


def removal_summary(final: ArcTable, kind: npt.NDArray[np.int64]) -> JsonDict:
    """Shares (percent) of arcs removed by carving, split by what produced the reading.

    ``share`` is the fully carved share of all arcs (paper, section 5-C: "over 20 percent");
    ``spurious_removed`` the share of spurious readings (any kind but direct) that were fully
    carved; ``true_lost`` the share of direct readings that were; ``spurious_of_removed`` the
    share of fully carved arcs that were spurious.
    """
    k = kind[final.reading_id]
    fully = final.removal == ArcFate.FULLY_CARVED
    split = final.removal == ArcFate.SPLIT
    direct = k == EchoKind.DIRECT
    return {
        "share": metrics.percent(fully),
        "split_share": metrics.percent(split),
        "spurious_removed": metrics.percent(fully[~direct]),
        "true_lost": metrics.percent(fully[direct]),
        "spurious_of_removed": metrics.percent(~direct[fully]),
        "spurious_removed_or_split": metrics.percent((fully | split)[~direct]),
        "true_lost_or_split": metrics.percent((fully | split)[direct]),
        "spurious_readings": metrics.percent(~direct),
        "unknown_removal": int(np.count_nonzero(final.removal < 0)),
    }


def latency_accuracy(sim: Simulation, record: RunRecord, points: ArcTable,
                     err: FloatArray) -> JsonDict:
    """Per 0.5 m wall patch: delay from first view to a local map within 5 and 10 cm.

    A patch is seen at the first direct reading whose true reflection lies on it; it is right
    at the first snapshot where at least half of its local-map points (points of readings that
    reflected off it) are within the tolerance of the true walls (see
    :func:`~sonarcarve.lab.metrics.patch_latency`). Delays are in seconds and in metres
    travelled; patches never right count as never (inf) and keep the curves below 100 %.
    """
    segments = sim.world.segments
    patches = metrics.patch_index(segments, PATCH_LENGTH)
    reflection = np.where((sim.truth.kind == EchoKind.DIRECT)[:, None], sim.truth.reflection,
                          np.nan)
    reading_patch = metrics.patch_of_points(reflection, segments, patches)
    sample_t = record.sample_times(sim.readings)
    grid_s = np.asarray(LATENCY_GRID_S)
    grid_m = np.asarray(LATENCY_GRID_M)
    out: JsonDict = {"patches_seen": 0}
    for tol in PATCH_TOLERANCES:
        seen, resolved = metrics.patch_latency(
            reading_patch=reading_patch, reading_t=sim.readings.t, sample_t=sample_t,
            row_sample=points.sample, row_reading=points.reading_id, row_error=err,
            n_patches=len(patches), tolerance=tol)
        mask = np.isfinite(seen)
        ok = np.isfinite(resolved[mask])
        delay_s = np.full(ok.shape, np.inf)
        delay_s[ok] = resolved[mask][ok] - seen[mask][ok]
        dist = sim.trajectory.distance_at
        delay_m = np.full(delay_s.shape, np.inf)
        delay_m[ok] = dist(resolved[mask][ok]) - dist(seen[mask][ok])
        out["patches_seen"] = int(mask.sum())
        out[f"{tol:g}"] = {
            "resolved_share": metrics.percent(ok),
            "median_s": _median_or_none(delay_s[ok]),
            "median_m": _median_or_none(delay_m[ok]),
            "curve_s": metrics.resolved_share_curve(delay_s, grid_s).tolist(),
            "curve_m": metrics.resolved_share_curve(delay_m, grid_m).tolist(),
        }
    return out


def analyse_t_junction(sim: Simulation, record: RunRecord, job: Job,
                       detail: bool = False) -> JsonDict:
    """Fig. 4: robot-to-facing-wall distance when the local map first shows the wall.

    The facing wall is the wall hit by a ray from the start of the drive along its heading. The
    wall *shows* once at least :data:`WALL_POINTS` local-map points lie within
    :data:`WALL_RADIUS` of it; counted over all the method's points, and over its *refined*
    points only (not ``centerline``: carved or ATM), which is what the paper's Fig. 4(a) shows.
    """
    traj = sim.trajectory
    start = np.array([traj.x[0], traj.y[0]])
    _, wall_index = sim.world.cast_rays(start, [traj.heading[0]])
    facing = sim.world.segments[int(wall_index[0])]
    points = sample_points(record)
    near = metrics.segment_distance(points.xy, facing[None, :])[0] <= WALL_RADIUS
    k = len(record.sample_readings)
    all_counts = np.bincount(points.sample[near], minlength=k)
    refined = near & (points.source != PointSource.CENTERLINE)
    refined_counts = np.bincount(points.sample[refined], minlength=k)
    sample_t = record.sample_times(sim.readings)
    x, y, _ = traj.pose_at(sample_t)
    wall_distance = metrics.segment_distance(np.column_stack((x, y)), facing[None, :])[0]
    out: JsonDict = {"end_distance": float(wall_distance[-1]) if k else None}
    for name, counts in (("all", all_counts), ("refined", refined_counts)):
        first = metrics.first_at_least(counts, WALL_POINTS)
        out[name] = None if first < 0 else float(wall_distance[first])
    if detail:
        # The local maps when the robot is about 4 m from the wall (the paper's Fig. 4 moment).
        moment = int(np.argmin(np.abs(wall_distance - 4.0)))
        snap = points.select(points.sample == moment)
        out["snapshot"] = {"xy": snap.xy, "source": snap.source,
                           "robot": [float(x[moment]), float(y[moment])],
                           "wall_distance": float(wall_distance[moment]),
                           "world": sim.world.segments}
    return out


def first_reading_within(sim: Simulation, opening: Sequence[Sequence[float]],
                          distance: float) -> int:
    """Readings added when the robot is first within ``distance`` of being level with the gap.

    The distance is measured along the robot's heading: ``(c - p) · (cos h, sin h)`` for gap
    centre ``c``, robot position ``p`` and heading ``h``, i.e. how far it still has to drive to
    reach the door (head-on) or to come abreast of a side opening. 0 when it never gets there.
    """
    centre = 0.5 * (np.asarray(opening[0]) + np.asarray(opening[1]))
    x, y, heading = sim.trajectory.pose_at(sim.readings.t)
    ahead = (centre[0] - x) * np.cos(heading) + (centre[1] - y) * np.sin(heading)
    within = np.flatnonzero(ahead <= distance)
    return int(within[0]) + 1 if within.size else 0


def analyse_opening(sim: Simulation, record: RunRecord, job: Job,
                    opening: Sequence[Sequence[float]] = (), detail: bool = False) -> JsonDict:
    """Fig. 2 and 9: is the opening passable in the local map 1, 2 and 3 m before it?

    Distances are along the drive (see :func:`first_reading_within`).

    Passable: some stretch of the gap at least :func:`passage_clearance` wide has no map
    point within :data:`GAP_DEPTH` of the gap line (see
    :func:`~sonarcarve.lab.metrics.free_width`). ``None`` where the drive never comes
    that close.
    """
    region = metrics.gap_region(opening[0], opening[1], GAP_DEPTH)
    clearance = passage_clearance(sim.robot.robot_radius)
    out: JsonDict = {"width": region.width}
    for d in OPENING_DISTANCES:
        stop = first_reading_within(sim, opening, d)
        if stop <= 0:
            out[f"{d:g}"] = None
            continue
        snap = record.local_map(int(np.searchsorted(record.sample_readings, stop)))
        out[f"{d:g}"] = bool(metrics.is_passable(snap.xy, region, clearance))
        if detail and d == 2.0:
            x, y, _ = sim.trajectory.pose_at(sim.readings.t[stop - 1])
            out["snapshot"] = {"xy": snap.xy, "source": snap.source,
                               "robot": [float(x), float(y)], "world": sim.world.segments,
                               "opening": np.asarray(opening)}
    return out


def analyse_sweep(sim: Simulation, record: RunRecord, job: Job) -> JsonDict:
    """One point of a sensitivity curve: true error, unprocessed share, fully carved share.

    The unprocessed share is :func:`analyse_office`'s (every history row: removed arcs count
    as processed). The local map's points are also split by source: ``refined_share`` is the
    share (percent) placed by carving or ATM, ``error_median_refined`` their median true error
    and ``error_median_fallback`` / ``fallback_median_range`` the median true error and range
    (metres) of the centerline points (None where there are none).
    """
    full = full_history_samples(record, job.config.history_size)
    points = sample_points(record)
    err = metrics.segment_distance(points.xy, sim.world.segments)[0]
    summary = metrics.error_summary(err)
    fully = record.final.removal == ArcFate.FULLY_CARVED
    refined = points.source != PointSource.CENTERLINE
    return {"error_median": summary.median, "error_p90": summary.p90,
            "unprocessed": unprocessed_percent(full), "fully_carved": metrics.percent(fully),
            "refined_share": metrics.percent(refined),
            "error_median_refined": _median_or_none(err[refined]),
            "error_median_fallback": _median_or_none(err[~refined]),
            "fallback_median_range": _median_or_none(points.range[~refined])}


ANALYSES: dict[str, Callable[..., JsonDict]] = {
    "office": analyse_office,
    "t-junction": analyse_t_junction,
    "opening": analyse_opening,
    "sweep": analyse_sweep,
}


def _median_or_none(a: FloatArray) -> float | None:
    """Median of ``a``; None for an empty array (strict JSON has no NaN)."""
    return float(np.median(a)) if a.size else None
