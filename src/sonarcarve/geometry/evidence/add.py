"""Adding an echo to evidence carving: the new arc's profile, then its weight on every older arc.

A new reading ``j`` that heard an echo at range ``r_j`` gives, at each bin centre ``p`` of an
older live arc inside its beam (``d = |p - o_j|``):

* freespace evidence ``w = -log(1 - P_detect)`` where ``d < r_j - ε`` (eq. 3.2; times
  ``protect`` where the bin is established), the bin carved once its evidence reaches ``T``;
* support ``+ P_detect`` where ``|d - r_j| ≤ ε_s``, to the older bin and, mutually, to the new
  arc's bin at ``p``'s bearing;
* occlusion of the new arc's bins behind established surfaces
  (:mod:`~sonarcarve.geometry.evidence.occlusion`), transmission evidence
  (:mod:`~sonarcarve.geometry.evidence.transmission`) and ATM crossings
  (:mod:`~sonarcarve.geometry.evidence.crossings`).

:func:`evidence_add` takes the model's arrays and its work arrays as two bundles
(:class:`~sonarcarve.geometry.evidence.arrays.EvidenceState`,
:class:`~sonarcarve.geometry.evidence.arrays.AddScratch`: what each array holds is documented
there) and runs a sequence of passes, each an inlined helper taking a few bundles:

1. the new arc's profile (:func:`_init_new_arc`);
2. the cull of the older rows (:func:`_cull_older`,
   :func:`~sonarcarve.geometry.evidence.beam.mark_near`);
3. per group of older arcs (:func:`_weigh_older`), pass 1: the bins to weigh and ATM's
   crossings (:func:`_gather_group`: :func:`_mark_bins`, :func:`_gather_entries`); pass 2:
   their ``P_detect`` (:func:`_detect_entries`,
   :func:`~sonarcarve.geometry.evidence.model.detect_probability` inlined); pass 3: their
   evidence (:func:`_weigh_group`: :func:`_weigh_arc`, whose steps are
   :func:`_weigh_free_entry` with :func:`_pass_established` and :func:`_weigh_support_entry`;
   then :func:`_add_arc_sums`);
4. what the new arc learns, the transmission included (:func:`_finish_new_arc`).

Laid out for the processor, it gives bit for bit the values of one loop over every arc and
bin: ``docs/evidence-carving.md``, "Evidence, support and the threshold", "Per-arc sums" and
"Speed: the weighing kernel's layout".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sonarcarve.geometry._compiled import compiled_borrowing, compiled_inline
from sonarcarve.geometry.bounds import arc_bounding_circle
from sonarcarve.geometry.evidence.arrays import (
    AddScratch,
    ArcEvidence,
    ArcShapes,
    BinEvidence,
    EvidenceState,
    GroupScratch,
    NewArcScratch,
    NewArcTally,
    PlainBundle,
    ReadingRows,
    named_scratch,
    named_state,
)
from sonarcarve.geometry.evidence.beam import (
    Beam,
    clear_of_beam,
    draw_live_circle,
    mark_near,
    meets_echo_circle,
    new_beam,
)
from sonarcarve.geometry.evidence.behind import NEWER_ARCS, depth_behind_newer
from sonarcarve.geometry.evidence.bins import bin_from_guess, sine_guess
from sonarcarve.geometry.evidence.crossings import transversal_crossings
from sonarcarve.geometry.evidence.model import (
    EVIDENCE_ALIVE,
    EVIDENCE_CARVED,
    EvidenceParams,
    incidence_gain,
)
from sonarcarve.geometry.evidence.occlusion import occlude_behind
from sonarcarve.geometry.evidence.transmission import weigh_transmission
from sonarcarve.typing import BoolArray, FloatArray

__all__ = ["evidence_add", "evidence_add_many"]


#: The rows of :class:`~sonarcarve.geometry.evidence.arrays.GroupScratch`'s ``entries``:
#: an entry's offset from the new reading, its bin centre's direction (pass 1), then its
#: distance, the sine of its angle to j's axis, ``P_beam``, ``cos γ``, ``P_detect`` and
#: localised support (pass 2).
_VX, _VY, _D2, _EX, _EY, _D, _SINE, _P_BEAM, _COS_GAMMA, _P_DETECT, _LOCATED = range(11)


class _OlderArc(NamedTuple):
    """An older arc as pass 3 weighs it."""

    row: int
    first_entry: int  # its entries in the group: first_entry .. end_entry - 1, in bin order
    end_entry: int
    alive_outside: int  # its live bins outside the new beam's reach or beam (pass 1)
    other: bool  # another sensor's than the new reading
    distinct: bool  # another sensor's, or from an origin at least viewpoint_spacing away
    half_bin_arc: float  # Δ_i r_i / 2: half a bin's length along the arc, metres


@compiled_inline
def _shape_new_arc(slot: int, readings: ReadingRows, shapes: ArcShapes,
                   evidence: BinEvidence) -> None:
    """The new arc's shape: bin centres p_k on C_j (eq. 2.1) at τ_k = θ1 + (k + ½) Δ, their
    directions, the axis and the bounding circle; and its bins' empty evidence."""
    bx, by, ex, ey = shapes.bx, shapes.by, shapes.ex, shapes.ey
    bins = bx.shape[1]
    xj = readings.x[slot]
    yj = readings.y[slot]
    rj = readings.r[slot]
    theta_j = readings.theta[slot]
    half_j = 0.5 * readings.beam_width[slot]
    step_j = readings.beam_width[slot] / bins
    shapes.cos_axis[slot] = math.cos(theta_j)
    shapes.sin_axis[slot] = math.sin(theta_j)
    shapes.cos_half[slot] = math.cos(half_j)
    for k in range(bins):
        tau = theta_j - half_j + (k + 0.5) * step_j
        ex[slot, k] = math.cos(tau)
        ey[slot, k] = math.sin(tau)
        bx[slot, k] = xj + rj * ex[slot, k]
        by[slot, k] = yj + rj * ey[slot, k]
        evidence.free[slot, k] = 0.0
        evidence.support[slot, k] = 0.0
        evidence.located[slot, k] = 0.0
    c0, c1, c2 = arc_bounding_circle(xj, yj, rj, theta_j - half_j, theta_j + half_j)
    shapes.circle[0, slot] = c0
    shapes.circle[1, slot] = c1
    shapes.circle[2, slot] = c2


@compiled_inline
def _reset_new_arc_scratch(phi_j: float, bins: int, trans: FloatArray) -> None:
    """``trans`` (:class:`~sonarcarve.geometry.evidence.arrays.AddScratch`'s) for a new arc of
    beam width ``phi_j`` and ``bins`` bins: its support from other sensors zeroed; the sines
    of its bin edges and the guess's scale depend on the beam width only, so they are
    recomputed only when it changes (a ring of like sensors: never after the first
    reading)."""
    if trans[2 * bins + 1] != phi_j:  # the edges' beam width (NaN: none yet)
        half_j = 0.5 * phi_j
        step_j = phi_j / bins
        for k in range(bins + 1):
            trans[bins + k] = math.sin(-half_j + k * step_j)
        trans[2 * bins + 1] = phi_j
        trans[2 * bins + 2] = bins / (trans[2 * bins] - trans[bins])
    for k in range(bins):
        trans[k] = 0.0


@compiled_inline
def _init_new_arc(slot: int, state: EvidenceState, trans: FloatArray) -> None:
    """The new arc's row before it is weighed: its shape and empty evidence
    (:func:`_shape_new_arc`), its per-arc records (alive, untouched, zero sums and
    crossings) and the scratch ``trans`` (:func:`_reset_new_arc_scratch`)."""
    _shape_new_arc(slot, state.readings, state.shapes, state.evidence)
    arcs = state.arcs
    arcs.status[slot] = EVIDENCE_ALIVE
    arcs.touched[slot] = False
    arcs.occluded[slot] = 0.0
    arcs.viewpoints[slot] = 0.0
    arcs.looked[slot] = 0.0
    arcs.others[slot] = 0.0
    bins = state.evidence.free.shape[1]
    _reset_new_arc_scratch(state.readings.beam_width[slot], bins, trans)
    state.crossings.counts[slot] = 0


@compiled_inline
def _mark_bins(i: int, beam: Beam, threshold: float, shapes: ArcShapes, free: FloatArray,
               in_beam: BoolArray) -> tuple[int, int]:
    """Pass 1 for older arc ``i``: ``in_beam[k]`` where bin ``k`` is left to weigh (free
    evidence below T) and lies in j's reach and beam. Returns the live bins outside them and
    the bins marked. No branch, so the compiler runs it on several bins at once."""
    bx = shapes.bx
    by = shapes.by
    xj = beam.x
    yj = beam.y
    cj = beam.cos_axis
    sj = beam.sin_axis
    reach2 = beam.reach2
    cos_half2 = beam.cos_half2
    alive_bins = 0
    n_in = 0
    for k in range(bx.shape[1]):
        vx = bx[i, k] - xj
        vy = by[i, k] - yj
        d2 = vx * vx + vy * vy
        along = vx * cj + vy * sj
        weigh = not free[i, k] >= threshold
        # Outside j's reach or beam (along ≥ d cos(φ/2), squared: no root).
        outside = (d2 >= reach2) | (along <= 0.0) | (along * along < d2 * cos_half2)
        in_beam[k] = weigh & (not outside)
        alive_bins += weigh & outside
        n_in += weigh & (not outside)
    return alive_bins, n_in


@compiled_inline
def _gather_entries(i: int, first: int, n_in: int, beam: Beam, shapes: ArcShapes,
                    group: GroupScratch) -> None:
    """The ``n_in`` bins of arc ``i`` marked by pass 1 (``group.in_beam``), in order, as the
    group's entries from ``first`` on: each bin (``entry_bin``), its offset from the new
    reading and the bin centre's direction (``entries`` rows 0-4)."""
    bx = shapes.bx
    by = shapes.by
    ex = shapes.ex
    ey = shapes.ey
    in_beam = group.in_beam
    e_bin = group.entry_bin
    xj = beam.x
    yj = beam.y
    e_vx = group.entries[_VX]
    e_vy = group.entries[_VY]
    e_d2 = group.entries[_D2]
    e_ex = group.entries[_EX]
    e_ey = group.entries[_EY]
    e = first
    for k in range(bx.shape[1]):
        e_bin[e] = k
        e += in_beam[k]
    for e in range(first, first + n_in):
        k = e_bin[e]
        vx = bx[i, k] - xj
        vy = by[i, k] - yj
        e_vx[e] = vx
        e_vy[e] = vy
        e_d2[e] = vx * vx + vy * vy
        e_ex[e] = ex[i, k]
        e_ey[e] = ey[i, k]


@compiled_inline
def _detect_entries(n_entries: int, beam: Beam, params: EvidenceParams, new_arc: NewArcScratch,
                    group: GroupScratch) -> None:
    """Pass 2: :func:`~sonarcarve.geometry.evidence.model.detect_probability`, inlined, for
    the first ``n_entries`` entries of the group (``entries`` rows 0-4 in, rows 5-10 out:
    distance, sine of the angle to j's axis, ``P_beam``, ``cos γ``, ``P_detect``, localised
    support), and the guess of the bin of j behind each (``entry_guess``).

    One loop over all of them: the compiler runs it on several entries at once when they are
    many, 20 or more, and the entries are only the bins to weigh, 7 of an older arc's 24 at
    history 1,000. np.divide is ``/`` (the same rounding) without numba's zero-divisor test,
    whose branch would keep the loop scalar; bins in the beam have d > 0 (along > 0) unless
    d² underflows (a range near 1e-300: then inv_d = inf and the values stay finite where
    ``/`` raised ZeroDivisionError).
    """
    edges = new_arc.edges
    edge_scale = new_arc.edge_scale
    bins = edges.shape[0] - 1
    first_edge = edges[0]
    max_detect = params.max_detect
    rough = params.rough
    cj = beam.cos_axis
    sj = beam.sin_axis
    sin_half = beam.sin_half
    edge_loss = beam.edge_loss
    inv_scale = beam.inv_scale
    cos_full = beam.cos_full
    cos_zero = beam.cos_zero
    scratch = group.entries
    e_guess = group.entry_guess
    e_vx = scratch[_VX]
    e_vy = scratch[_VY]
    e_d2 = scratch[_D2]
    e_ex = scratch[_EX]
    e_ey = scratch[_EY]
    e_d = scratch[_D]
    e_sine = scratch[_SINE]
    e_beam = scratch[_P_BEAM]
    e_cos = scratch[_COS_GAMMA]
    e_p = scratch[_P_DETECT]
    e_loc = scratch[_LOCATED]
    for e in range(n_entries):
        vx = e_vx[e]
        vy = e_vy[e]
        d = math.sqrt(e_d2[e])
        inv_d = np.divide(1.0, d)
        sine = (cj * vy - sj * vx) * inv_d  # of the bin's angle to j's axis
        u = min(np.divide(abs(sine), sin_half), 1.0)
        p_beam = np.divide(max_detect * (1.0 - edge_loss * u * u), 1.0 + d * inv_scale)
        cos_gamma = abs(e_ex[e] * vx + e_ey[e] * vy) * inv_d
        e_d[e] = d
        e_sine[e] = sine
        e_beam[e] = p_beam
        e_cos[e] = cos_gamma
        p = p_beam * incidence_gain(cos_gamma, cos_full, cos_zero, rough)
        e_p[e] = p
        # What the support path needs: the localised support, the bin of j behind.
        e_loc[e] = p * abs(e_ex[e] * vy - e_ey[e] * vx) * inv_d
        e_guess[e] = sine_guess(sine, first_edge, bins, edge_scale)


@compiled_inline
def _occlude_past(slot: int, vx: float, vy: float, d: float, half_bin_arc: float, beam: Beam,
                  free: FloatArray, threshold: float) -> int:
    """Carve the bins of j behind an established bin of an older arc that j looked past, at
    offset ``(vx, vy)`` and distance ``d`` from j, half a bin (``half_bin_arc``) wide: j's echo
    cannot come from behind a surface (sound does not pass through walls; at any angle:
    ``docs/evidence-carving.md``, "Occlusion"). Returns the bins of j carved."""
    cj = beam.cos_axis
    sj = beam.sin_axis
    along = vx * cj + vy * sj
    return occlude_behind(slot, math.atan2(cj * vy - sj * vx, along), half_bin_arc / d, beam,
                          free, threshold)


@compiled_inline
def _keep_for_transmission(passed: FloatArray, n_passed: int, i: int, k: int, kb: int,
                           blocked: float, factor: float, w: float) -> int:
    """Row ``n_passed`` of ``passed``: older bin ``(i, k)`` that j's sound passed, j's bin
    ``kb`` behind it, the ``P_beam cos γ`` it would have blocked, the ``protect`` factor and the
    evidence ``w`` it got. Kept for the transmission pass, which needs j's support from other
    sensors, known only once every older arc is weighed. Returns the rows now used."""
    passed[n_passed, 0] = i
    passed[n_passed, 1] = k
    passed[n_passed, 2] = kb
    passed[n_passed, 3] = blocked
    passed[n_passed, 4] = factor
    passed[n_passed, 5] = w
    return n_passed + 1


@compiled_inline
def _add_support(slot: int, i: int, k: int, kb: int, p: float, loc: float, other: bool,
                 evidence: BinEvidence, other_support: FloatArray) -> None:
    """An older bin ``(i, k)`` on j's echo circle: ``P_detect`` of support to it and, mutually,
    to j's bin ``kb`` at its bearing; the localised support ``loc`` (``P_detect`` times the sine
    of the angle between the two circles there: tangent circles, one sensor stepping along its
    axis, say nothing of *where* on the arc the echo came from) to both; and to j's support
    from other sensors (the transmission's) when ``i`` is another sensor's."""
    evidence.support[i, k] += p
    evidence.support[slot, kb] += p
    evidence.located[i, k] += loc
    evidence.located[slot, kb] += loc
    if other:
        other_support[kb] += p


@compiled_inline
def _pass_established(slot: int, e: int, arc: _OlderArc, beam: Beam, params: EvidenceParams,
                      group: GroupScratch, state: EvidenceState,
                      tally: NewArcTally) -> tuple[bool, NewArcTally]:
    """Whether the older bin of entry ``e``, in j's freespace, is *established* (support at
    least ``establish``, free evidence below ``T / 2``), and what j learns passing it, only
    where it is nearer than ``r_j - 2ε`` (a margin clear of j's own echo): the support of the
    surface its sound passed (``top_through``) and, past an established bin, the bins of j
    behind it carved by occlusion (:func:`_occlude_past`). Returns the verdict and the new
    arc's tally updated."""
    i = arc.row
    k = group.entry_bin[e]
    support = state.evidence.support
    d = group.entries[_D, e]
    n_passed, occluding, top_through = tally
    established = (support[i, k] >= params.establish
                   and state.evidence.free[i, k] < 0.5 * params.threshold)
    if d < beam.free_r - params.tolerance:
        top_through = max(top_through, support[i, k])
        if established:
            occluding += _occlude_past(slot, group.entries[_VX, e], group.entries[_VY, e], d,
                                       arc.half_bin_arc, beam, state.evidence.free,
                                       params.threshold)
            state.arcs.touched[slot] = True
    return established, NewArcTally(n_passed=n_passed, occluding=occluding,
                                    top_through=top_through)


@compiled_inline
def _weigh_free_entry(slot: int, e: int, arc: _OlderArc, beam: Beam, params: EvidenceParams,
                      group: GroupScratch, state: EvidenceState, new_arc: NewArcScratch,
                      tally: NewArcTally) -> tuple[bool, NewArcTally]:
    """Entry ``e`` of an older arc, nearer than ``r_j - ε``: j heard nothing there, so the bin
    gains ``w = -log(1 - P_detect)`` of free evidence (eq. 3.2), times ``protect`` where it is
    established (:func:`_pass_established`). A bin still alive that j's sound passed
    obliquely (``P_detect < P_beam``) is kept for the transmission pass
    (:func:`_keep_for_transmission`). Returns whether the bin is still alive (below ``T``)
    and the new arc's tally updated."""
    i = arc.row
    k = group.entry_bin[e]
    free = state.evidence.free
    p = group.entries[_P_DETECT, e]
    p_beam = group.entries[_P_BEAM, e]
    f = free[i, k]
    state.arcs.touched[i] = True
    established, tally = _pass_established(slot, e, arc, beam, params, group, state, tally)
    factor = params.protect if established else 1.0
    w = -math.log1p(-p) * factor
    f += w
    free[i, k] = f
    alive = f < params.threshold
    passed = new_arc.passed
    n_passed = tally.n_passed
    if alive and params.transmit > 0.0 and p < p_beam and n_passed < passed.shape[0]:
        kb = bin_from_guess(group.entry_guess[e], group.entries[_SINE, e], new_arc.edges,
                            free.shape[1])
        n_passed = _keep_for_transmission(passed, n_passed, i, k, kb,
                                          p_beam * group.entries[_COS_GAMMA, e], factor, w)
    return alive, NewArcTally(n_passed=n_passed, occluding=tally.occluding,
                              top_through=tally.top_through)


@compiled_inline
def _weigh_support_entry(slot: int, e: int, arc: _OlderArc, group: GroupScratch,
                         state: EvidenceState, new_arc: NewArcScratch) -> float:
    """Entry ``e`` of an older arc, on j's echo circle (``|d - r_j| <= ε_s``): support, not
    freespace, to it and to j's bin at its bearing (:func:`_add_support`). Returns its
    ``P_detect``."""
    i = arc.row
    p: float = group.entries[_P_DETECT, e]
    state.arcs.touched[i] = True
    state.arcs.touched[slot] = True
    kb = bin_from_guess(group.entry_guess[e], group.entries[_SINE, e], new_arc.edges,
                        state.evidence.free.shape[1])
    _add_support(slot, i, group.entry_bin[e], kb, p, group.entries[_LOCATED, e], arc.other,
                 state.evidence, new_arc.other_support)
    return p


@compiled_inline
def _weigh_arc(slot: int, arc: _OlderArc, beam: Beam, params: EvidenceParams,
               group: GroupScratch, state: EvidenceState, new_arc: NewArcScratch,
               tally: NewArcTally) -> tuple[int, float, float, NewArcTally]:
    """Pass 3 for an older arc: the evidence of its entries (its marked bins, in bin order):
    freespace evidence where nearer than ``r_j - ε`` (:func:`_weigh_free_entry`: the rows
    kept for transmission among them, and occlusion of j's bins behind established ones and
    the support j looked through only where nearer than ``r_j - 2ε``, a margin clear of j's
    own echo); support where on j's echo circle (:func:`_weigh_support_entry`).

    Returns its live bins (those outside j's reach or beam included), its largest support and
    "looked" ``P_beam`` (from a distinct viewpoint only), and the new arc's tally updated.
    """
    distances = group.entries[_D]
    alive_bins = arc.alive_outside
    top_support = 0.0
    top_looked = 0.0
    for e in range(arc.first_entry, arc.end_entry):
        d = distances[e]
        if d >= beam.free_r and abs(d - beam.r) > params.support_tolerance:
            alive_bins += 1  # neither in j's freespace nor on its echo circle
        elif d < beam.free_r:
            if arc.distinct:
                top_looked = max(top_looked, group.entries[_P_BEAM, e])
            alive, tally = _weigh_free_entry(slot, e, arc, beam, params, group, state,
                                             new_arc, tally)
            alive_bins += alive
        else:
            alive_bins += 1
            top_support = max(top_support,
                              _weigh_support_entry(slot, e, arc, group, state, new_arc))
    return alive_bins, top_support, top_looked, tally


@compiled_inline
def _cull_older(first_older: int, n_older: int, beam: Beam, state: EvidenceState,
                group: GroupScratch) -> int:
    """The cull of the ``n_older`` rows from ``first_older`` on (ring order: two runs of rows
    where the ring wraps) by :func:`~sonarcarve.geometry.evidence.beam.mark_near`, all rows of
    a run at once (a loop without branches); the rows that pass, oldest first, into
    ``group.near``. Returns how many pass."""
    circle = state.shapes.circle
    status = state.arcs.status
    near = group.near
    near_flags = group.near_flags
    storage = status.shape[0]
    n_older = min(n_older, storage)  # no window past the rows (no bounds checks here)
    n_near = 0
    end = first_older + n_older
    for lo, hi in ((first_older, min(end, storage)), (0, max(end - storage, 0))):
        mark_near(circle[0, lo:hi], circle[1, lo:hi], circle[2, lo:hi], status[lo:hi], beam,
                  near_flags[lo:hi])
        for i in range(lo, hi):
            near[n_near] = i
            n_near += near_flags[i]
    return n_near


@compiled_inline
def _add_arc_sums(slot: int, arc: _OlderArc, top_support: float, top_looked: float,
                  arcs: ArcEvidence) -> None:
    """The per-arc sums of an older arc and j, mutual: support from distinct viewpoints and
    from other sensors (the arc's largest support from j, not every bin's, so that one reading
    counts once), and j's evidence of having looked at it from a distinct viewpoint."""
    i = arc.row
    if arc.distinct:
        arcs.viewpoints[i] += top_support
        arcs.viewpoints[slot] += top_support
        if top_looked > 0.0:
            arcs.looked[i] += -math.log1p(-top_looked)
    if arc.other:
        arcs.others[i] += top_support
        arcs.others[slot] += top_support


@compiled_inline
def _finish_new_arc(slot: int, tally: NewArcTally, new_arc: NewArcScratch,
                    state: EvidenceState, params: EvidenceParams) -> int:
    """What j learns once every older arc is weighed: its share of bins occluded, the support
    its free sector passed, the transmission evidence (needs all of j's support) and its own
    status. Returns the arcs this carved fully (j among them when occlusion took every bin)."""
    free = state.evidence.free
    arcs = state.arcs
    bins = free.shape[1]
    arcs.occluded[slot] = tally.occluding / bins
    arcs.through[slot] = tally.top_through
    arcs.behind[slot] = 0.0  # judged when the arc leaves (evidence_add_many), not on arrival
    fully = weigh_transmission(slot, new_arc.passed, tally.n_passed, new_arc.other_support,
                               free, arcs.status, params)
    if tally.occluding >= bins:
        arcs.status[slot] = EVIDENCE_CARVED
        fully += 1
    return fully


@compiled_inline
def _gather_group(slot: int, q: int, n_near: int, group_size: int, beam: Beam,
                  params: EvidenceParams, with_atm: bool, state: EvidenceState,
                  group: GroupScratch, spilled: int) -> tuple[int, int, int, int, int, int]:
    """Pass 1 and the crossings for the culled rows ``group.near[q:]``, until ``group_size`` of
    them have bins to weigh: those rows moved to ``near[q:group_end]``, their marked bins the
    group's entries (:func:`_mark_bins`, :func:`_gather_entries`); an arc with no bin to weigh
    is done here (pass 3 would add nothing: its sums would add 0.0 to sums of non-negative
    terms), as is one the cull found no live bin of within reach (pass 1 would mark none).
    ``spilled``: the rows of ``state.crossings.spill`` used so far.

    Returns the next row to read, ``group_end``, the entries, the crossings kept, the rows of
    ``spill`` used and the arcs carved fully.
    """
    near = group.near
    status = state.arcs.status
    circle = state.shapes.circle
    live = state.arcs.live_circle
    first = q
    group_end = q
    n_entries = 0
    crossings = 0
    fully = 0
    while q < n_near and group_end - first < group_size:
        i = near[q]
        q += 1
        if with_atm and meets_echo_circle(circle[0, i], circle[1, i], circle[2, i], beam):
            kept, spilled = transversal_crossings(slot, i, state.readings, state.shapes,
                                                  params.cos_psi, state.crossings, spilled)
            crossings += kept
        if clear_of_beam(live[0, i], live[1, i], live[2, i], beam):
            continue  # its live bins out of reach: none to weigh, and one left (alive)
        alive_bins, n_in = _mark_bins(i, beam, params.threshold, state.shapes,
                                      state.evidence.free, group.in_beam)
        if n_in == 0:
            if alive_bins == 0:
                status[i] = EVIDENCE_CARVED
                fully += 1
            continue
        near[group_end] = i  # q > group_end: a row already read
        group.arc_marked[group_end - first] = n_in
        group.arc_alive[group_end - first] = alive_bins
        group_end += 1
        _gather_entries(i, n_entries, n_in, beam, state.shapes, group)
        n_entries += n_in
    return q, group_end, n_entries, crossings, spilled, fully


@compiled_inline
def _weigh_group(slot: int, first: int, group_end: int, beam: Beam, params: EvidenceParams,
                 state: EvidenceState, group: GroupScratch, new_arc: NewArcScratch,
                 tally: NewArcTally) -> tuple[int, NewArcTally]:
    """Pass 3 for the group's arcs ``group.near[first:group_end]``, in the cull's order: each
    arc's evidence (:func:`_weigh_arc`) and per-arc sums (:func:`_add_arc_sums`), and its
    status, and the circle of its live bins redrawn when it lost some. Returns the arcs carved
    fully and the new arc's tally updated."""
    readings = state.readings
    status = state.arcs.status
    bins = state.evidence.free.shape[1]
    fully = 0
    start = 0
    for g in range(first, group_end):
        i = group.near[g]
        ox = readings.x[i] - beam.x
        oy = readings.y[i] - beam.y
        other = readings.sensor[i] != readings.sensor[slot]
        stop = start + group.arc_marked[g - first]
        arc = _OlderArc(
            row=i, first_entry=start, end_entry=stop, alive_outside=group.arc_alive[g - first],
            other=other, distinct=other or ox * ox + oy * oy >= beam.spacing2,
            half_bin_arc=0.5 * (readings.beam_width[i] / bins) * readings.r[i],  # Δ_i r_i / 2
        )
        alive_bins, top_support, top_looked, tally = _weigh_arc(slot, arc, beam, params, group,
                                                                state, new_arc, tally)
        start = stop
        _add_arc_sums(slot, arc, top_support, top_looked, state.arcs)
        if alive_bins == 0:
            status[i] = EVIDENCE_CARVED
            fully += 1
        elif alive_bins < state.arcs.live_circle[3, i]:  # it lost bins: a smaller circle
            draw_live_circle(i, readings, state.evidence.free, params.threshold,
                             state.arcs.live_circle)
    return fully, tally


@compiled_inline
def _group_scratch(scratch: AddScratch) -> GroupScratch:
    """The work arrays of the bin passes, by the names the passes use."""
    return GroupScratch(
        entries=scratch.entries, entry_bin=scratch.bin_index[0],
        entry_guess=scratch.bin_index[1], arc_marked=scratch.bin_index[2],
        arc_alive=scratch.bin_index[3], in_beam=scratch.in_beam, near=scratch.near,
        near_flags=scratch.near_flags,
    )


@compiled_inline
def _new_arc_scratch(scratch: AddScratch, bins: int) -> NewArcScratch:
    """The new arc's side of the weighing, once :func:`_init_new_arc` has set the sines of its
    bin edges in ``scratch.trans`` (``edge_scale`` is read from there)."""
    trans = scratch.trans
    return NewArcScratch(other_support=trans[:bins], edges=trans[bins : 2 * bins + 1],
                         edge_scale=trans[2 * bins + 2], passed=scratch.passed)


@compiled_inline
def _weigh_older(slot: int, n_near: int, beam: Beam, params: EvidenceParams, with_atm: bool,
                 state: EvidenceState, group: GroupScratch,
                 new_arc: NewArcScratch) -> tuple[int, int, int, NewArcTally]:
    """The new arc against the ``n_near`` older rows that passed the cull
    (``group.near[:n_near]``, oldest first), a group of them at a time: pass 1 and the
    crossings (:func:`_gather_group`), pass 2 (:func:`_detect_entries`: ``P_detect`` of every
    entry of the group at once, one loop the compiler vectorises when the entries are many),
    pass 3 (:func:`_weigh_group`: the evidence, arc after arc, in bin order, then the arc's
    sums). Returns the arcs carved fully, the crossings kept, the rows of ``spill`` used and
    the new arc's tally.

    Marking every row up front (the cull) gives the one loop's result because nothing here
    changes another older arc's status or bounding circle, nor the free evidence of a row
    other than the arc in hand and the new one (``slot``, never an older row): the new arc's
    status and the transmission come after it. For the same reason pass 1 can read every
    arc's free evidence of a group before pass 3 writes any of them, and pass 2 reads only
    geometry: the passes run over a group's arcs in turn, and pass 3 in the arcs' order, so
    every value is the one loop's.
    """
    bins = state.evidence.free.shape[1]
    group_size = max(1, group.entries.shape[1] // bins)  # arcs a group's entries always hold
    tally = NewArcTally(n_passed=0, occluding=0, top_through=0.0)
    fully = 0
    crossings = 0
    spilled = 0
    q = 0
    while q < n_near:
        first = q  # the group's rows end up in near[first:group_end]
        q, group_end, n_entries, kept, spilled, carved = _gather_group(
            slot, q, n_near, group_size, beam, params, with_atm, state, group, spilled)
        crossings += kept
        fully += carved
        _detect_entries(n_entries, beam, params, new_arc, group)
        carved, tally = _weigh_group(slot, first, group_end, beam, params, state, group,
                                     new_arc, tally)
        fully += carved
    return fully, crossings, spilled, tally


@compiled_inline
def _add_reading(slot: int, first_older: int, n_older: int, state: EvidenceState,
                 scratch: AddScratch, params: EvidenceParams,
                 with_atm: bool) -> tuple[int, int, int, int]:
    """:func:`evidence_add`, inlined into :func:`evidence_add_many`: as a call there (the
    bundles flattened into some 300 arguments) the kernel was 7 % slower per reading at
    history 250 (measured on numba 0.68, CPU time of the kernel, the best of 7 runs)."""
    # The passes are inlined helpers (compiled_inline), as this is, into kernels that count
    # no references (compiled_borrowing), so they compile to the code of one body: the same
    # bits, and the same speed where numba can compile without reference counting (measured
    # on numba 0.68; docs/evidence-carving.md, "Speed: the weighing kernel's layout").
    bins = state.evidence.free.shape[1]
    group = _group_scratch(scratch)
    _init_new_arc(slot, state, scratch.trans)
    beam = new_beam(slot, state.readings, state.shapes, params)
    new_arc = _new_arc_scratch(scratch, bins)
    n_near = _cull_older(first_older, n_older, beam, state, group)
    fully, crossings, spilled, tally = _weigh_older(slot, n_near, beam, params, with_atm,
                                                    state, group, new_arc)
    fully += _finish_new_arc(slot, tally, new_arc, state, params)
    draw_live_circle(slot, state.readings, state.evidence.free, params.threshold,
                     state.arcs.live_circle)
    return fully, crossings, tally.occluding, spilled


@compiled_borrowing
def evidence_add(slot: int, first_older: int, n_older: int,
                 state: EvidenceState | PlainBundle, scratch: AddScratch | PlainBundle,
                 params: EvidenceParams, with_atm: bool) -> tuple[int, int, int, int]:
    """Add reading ``slot``: initialise its profile, then weigh it against every older arc.

    Parameters
    ----------
    slot : int
        The new arc's row.
    first_older, n_older : int
        The older rows: ``n_older`` rows from ``first_older`` on, oldest first, wrapping
        from the last row to row 0 (the history's ring); the arcs not alive among them are
        skipped. ``0 <= first_older < n`` and ``n_older < n``, ``slot`` not among them (the
        history's storage is twice its capacity); a longer window is cut to ``n`` rows, since
        the kernel runs without bounds checks.
    state : EvidenceState
        The model's arrays (:class:`~sonarcarve.geometry.evidence.arrays.EvidenceState`:
        each array's meaning and shape there): the new arc's row filled, the older arcs'
        evidence updated in place. Named, or :func:`~sonarcarve.geometry.evidence.arrays.plain`
        (faster to call: the module docstring of
        :mod:`~sonarcarve.geometry.evidence.arrays`).
    scratch : AddScratch
        The work arrays (:class:`~sonarcarve.geometry.evidence.arrays.AddScratch`), named or
        plain.
    params : EvidenceParams
        The sensor model.
    with_atm : bool
        Find ATM crossings too.

    Returns
    -------
    fully_carved, crossings, occluded_bins, spilled : int
        Arcs whose last bin was carved by this reading; ATM crossings kept; bins of the new arc
        carved by occlusion; rows of ``state.crossings.spill`` used (0: every crossing
        fitted).
    """
    return _add_reading(slot, first_older, n_older, named_state(state), named_scratch(scratch),
                        params, with_atm)


@compiled_inline
def judge_leaving(start: int, n_live: int, state: EvidenceState, params: EvidenceParams,
                  scratch: FloatArray) -> None:
    """The arc leaving the history, ``start - 1`` (the row before the live ones from ``start``
    on, ring order): its ``behind`` set to its depth behind the ``n_live`` first of them
    (:func:`~sonarcarve.geometry.evidence.behind.depth_behind_newer`, the margin ``2ε``);
    left 0 for an arc already carved (it has no point to judge)."""
    readings, shapes, arcs = state.readings, state.shapes, state.arcs
    storage = arcs.status.shape[0]
    leaving = start - 1 if start > 0 else storage - 1
    if arcs.status[leaving] != EVIDENCE_ALIVE:
        return
    arcs.behind[leaving] = depth_behind_newer(
        leaving, start, n_live, readings.x, readings.y, readings.r, shapes.cos_axis,
        shapes.sin_axis, shapes.cos_half, arcs.status, arcs.viewpoints, params.establish,
        2.0 * params.tolerance, scratch)


@compiled_borrowing
def evidence_add_many(first: int, count: int, capacity: int,
                      state: EvidenceState | PlainBundle, scratch: AddScratch | PlainBundle,
                      params: EvidenceParams, with_atm: bool) -> tuple[int, int, int, int, int]:
    """:func:`evidence_add` for the arcs of sequence numbers ``first .. first + count - 1``,
    in order, each against the ``capacity - 1`` (or fewer) arcs before it: one compiled call
    per block of readings (no Python between arcs), the same result as one call per arc.

    The bundles are those of :func:`evidence_add`. Before arc ``s`` is added, the arc it
    pushes out of the history (``s - capacity``) gets its ``behind``: the depth behind the
    :data:`~sonarcarve.geometry.evidence.behind.NEWER_ARCS` arcs after it
    (:func:`~sonarcarve.geometry.evidence.behind.depth_behind_newer`, in ``scratch.depth``),
    judged on the state it leaves with, so the same whatever the blocks. Arcs still in the
    history keep 0.

    It stops after the first arc whose crossings did not all fit the store (they are in
    ``spill``; every other part of that arc is done): the caller widens the store, moves the
    spilled crossings to the ends of their rows and calls again for the arcs after it. The
    crossings are then stored as a store wide enough from the start would hold them.

    Returns
    -------
    fully_carved, crossings, occluded_bins : int
        The sums of :func:`evidence_add`'s counts over the arcs done.
    done : int
        Sequence number after the last arc done (``first + count`` when all are).
    spilled : int
        Rows of ``spill`` the last arc done used: 0 when no arc spilled. It can be > 0 with
        ``done == first + count`` (the block's last arc spilled, as every single ``add()``
        that spills), so the caller moves the spill whenever it is > 0, whatever ``done``.
    """
    state = named_state(state)
    scratch = named_scratch(scratch)
    storage = state.arcs.status.shape[0]
    fully = 0
    crossings = 0
    occluding = 0
    for sequence in range(first, first + count):
        live = min(sequence + 1, capacity)
        start = (sequence + 1 - live) % storage
        if sequence >= capacity:
            judge_leaving(start, min(capacity - 1, NEWER_ARCS), state, params, scratch.depth)
        a, b, c, spilled = _add_reading(sequence % storage, start, live - 1, state, scratch,
                                        params, with_atm)
        fully += a
        crossings += b
        occluding += c
        if spilled:
            return fully, crossings, occluding, sequence + 1, spilled
    return fully, crossings, occluding, first + count, 0
