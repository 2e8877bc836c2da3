"""Evidence carving: free-space *evidence* on arcs instead of a veto (beyond the paper).

The paper's carving (eq. 3.5) removes every point of an older arc ``C_i`` that lies in the
freespace sector ``F_j`` of *one* newer reading. Real beams miss surfaces: a smooth wall met at a
glancing angle returns nothing, the beam's edges are weak and far surfaces are quiet, so one
reading's "freespace" is only evidence, of a strength that depends on where the point is. Here
each arc carries an *evidence profile* over its bearing: ``K`` equal bins across its full beam
``[θ_i - φ_i/2, θ_i + φ_i/2]``, bin ``k`` represented by its centre point ``p_k`` (bearing
``τ_k = θ1_i + (k + ½) Δ_i``, ``Δ_i = φ_i / K``).

The model of a newer reading ``j`` at a point ``p`` (``v = p - o_j``, ``d = |v|``):

* ``p`` in ``j``'s beam: ``v · a_j ≥ d cos(φ_j/2)`` (``a_j`` the unit axis; exact);
* beam directivity: ``B(p) = 1 - (1 - g) u²`` with ``u = sin δ / sin(φ_j/2)``, ``δ`` the
  off-axis angle of ``p`` and ``g`` the relative sensitivity at the beam edge (``edge_gain``);
* incidence: the echo of ``i`` at ``p`` implies a surface through ``p`` whose normal points at
  ``o_i``; ``j`` meets it at ``γ`` with ``cos γ = |e_i(τ_k) · v| / d`` (the angle of
  :mod:`~sonarcarve.geometry.specular`). ``I(γ) = 1`` for ``γ ≤ γ0``, the floor ``ρ`` (rough
  surfaces, corners) for ``γ ≥ γ1``, linear in ``cos γ`` between;
* spreading and absorption: ``A(d) = 1 / (1 + d / L)``;
* ``P_detect(j, p) = P_max · B · I · A``: the probability that ``j`` would have heard a surface
  at ``p``.

Evidence that ``p`` is empty from ``j`` is ``w = -log(1 - P_detect)`` when ``d < r_j - ε`` (eq.
3.2 with the range tolerance ε); the log-odds of independent misses add. Bin ``k`` is *carved*
once its evidence reaches ``T = -log(1 - P_carve)``: one strong reading or several weak ones.
A reading whose echo circle passes through ``p`` (``|d - r_j| ≤ ε_s``) *supports* it instead
(``+ P_detect``), and the same crossing supports the new arc's bin at ``p``'s bearing (the
support is mutual: each arc heard something at ``p``).

Occlusion (multipath): sound does not pass through walls. A bin of an older arc that is
*established* (support at least ``S_est``, free evidence below ``T/2``) and lies in ``F_j``
while ``j`` could easily have missed it (``P_detect < ½``, a glancing look) means ``j``'s echo did
not come from behind it: the bins of the new arc ``j`` behind that point (within the point's
angular half-bin seen from ``o_j``) are carved. A multipath echo reads too long, behind a wall
that its beam met at a glancing angle, and is carved this way; a head-on look through an
established point (``P_detect ≥ ½``) instead carves the point (the newer reading is
authoritative, as in the paper).

What is exact and what is binned: membership of a bin centre in a beam, a disk and the support
annulus, and the incidence angle, are exact; the profile is piecewise constant over bins, so a
carved interval's ends are known to half a bin: :func:`evidence_estimates` widens every error
bound by ``Δ_i / 2`` on each side (``E_s = 2 r sin((w + Δ)/4)`` for a width ``w``, eq. 5.3).

A no-echo reading (it heard nothing up to its ``max_range``, :func:`evidence_free`) adds the same
free-space evidence with ``r_j = max_range``: ``w`` at every bin centre ``d < max_range - ε`` in
its beam, and nothing else (no support, no occlusion, no crossing, no arc of its own).

Transmission (the other half of a look): a surface at ``p`` that ``j`` met at a glancing angle
returns no echo, but it still stands in the way of the sound. When ``j``'s own echo, at the
bearing of ``p`` and beyond it, is confirmed by *other sensors'* older echoes (support ``S``
from readings of another transducer; a sensor's own repeated echoes can repeat one systematic
error, crosstalk off the same wall or one multipath path), the sound went through ``p``: the
bin gains ``-log(1 - P_t)`` with ``P_t = transmit · P_beam · cos γ · min(1, S / S_conf)``
instead of the incidence evidence when that is larger (one reading, one event: the larger
counts). ``cos γ`` is the share of the beam a patch at ``p`` with the older echo's normal
would block: a wall the beam runs along (γ near 90°) does not block it, so grazing looks do
not carve true walls. Bins of ``j`` carved by occlusion take no part (a multipath echo behind
a wall confirms nothing). This is what lets another sensor remove a crosstalk or floor
phantom it can only look at obliquely, and it is exact in the same sense as the rest (bin
centres).

Two per-arc sums serve the confidence of :mod:`sonarcarve.methods.evidence`: ``others``, the
support from other sensors (as ``viewpoints`` but never from the arc's own sensor), and
``through``, the largest support of an older live bin a new beam passed on its way to its
echo (the graded form of the occlusion rule).

ATM (section 6, integration): transversal crossings (eq. 2.1, ψ) are found in the same pass for
the pairs the evidence pass does not cull, stored per arc as bearings relative to its axis, and
*counted only inside the surviving bins*; a crossing inside a surviving piece confirms it. The
store has as many columns as the caller gave it: crossings that do not fit wait in a spill
buffer, and :func:`evidence_add_many` stops after that arc so that the caller can widen the
store and move them to their rows (the store grows on demand, as ATM's does).

The weighing kernels (:func:`evidence_add`, :func:`evidence_add_many`, :func:`evidence_free`)
only borrow the arrays their caller owns and allocate nothing, so they are compiled without
numba's reference counting (``compiled_borrowing``): the same arithmetic, and 13-18 % less
kernel CPU per reading at a history of 250 (the atomic counts of the arrays their inlined
helpers bind).

The weighing pass of :func:`evidence_add` is laid out for the processor; each value is the
same IEEE operation in the same order as in one loop that tests every arc and every bin in
turn, so the maps are bit for bit those of that loop. The cull tests every older row's
bounding circle in one loop without branches (the compiler tests several rows at once), and only
the rows that pass are visited, oldest first, in groups. For each arc of a group, a loop without
branches over its K bins marks the bins to weigh (free evidence below T, inside the reach and
the beam); an arc with none is done there (pass 3 would add nothing to it), the others' marked
bins are gathered as the group's entries. A second loop computes ``P_detect`` for every entry of
the group at once (``np.divide`` instead of ``/``: the same division without numba's
zero-divisor test, whose branch kept the loop scalar; it also guesses the bin of ``j`` behind
each bin, which the third pass steps to the exact one); a third adds the evidence, arc after
arc in the cull's order, each in bin order. Against the one loop, ``benchmarks/throughput.py``
(history 250 / 1,000, the same run) went from 172k / 66k to 246k / 96k readings/s (1.43x /
1.45x) with one group per arc (``P_detect`` of all K bins of an arc with any marked); the groups
(issue 9, 64 arcs) weigh only the marked bins, 7 of an older arc's 24 at history 1,000, in one
vector loop long enough for the compiler's vector path (it takes the scalar one below 20
iterations: the runtime tests that the arrays do not overlap cost too much for fewer), and skip
the arcs with nothing to weigh, 36 of the 65 a reading that pass the cull at history 1,000:
the kernel 10.5 → 9.8 µs a reading at history 1,000, 4.3 → 4.25 at 250 (CPU time, best of 3,
alternating runs); ``benchmarks/evidence_speed.py --commits 24474ed 6282d54 --rounds 5``:
evidence 80.7k → 85.4k readings/s at 1,000 (medians), 185k → 187k at 250, against carving
0.26 → 0.28 and 0.31 → 0.32; maps bit for bit the same (``benchmarks/same_outputs.py``: 638 of
638 fields; ``tests/geometry/test_evidence_passes.py`` runs the one loop as the oracle, with
groups of 1, 3 and 64 arcs). Still short of the 0.5x issue 9 asks for: the time is spread over
the cull (0.44 ns a history row), about 0.1 µs per arc that passes it (crossings, the marking
pass, the weighing of its ~7 bins) and the new arc's 24 ``sincos``; the divisions and square
root of pass 2, the target of cheaper arithmetic, are now a few per cent of it.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_borrowing, compiled_inline
from sonarcarve.geometry.bounds import arc_bounding_circle
from sonarcarve.geometry.circles import common_chord
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = [
    "EVIDENCE_ALIVE",
    "EVIDENCE_CARVED",
    "EvidenceParams",
    "detect_probability",
    "evidence_add",
    "evidence_add_many",
    "evidence_estimates",
    "evidence_free",
    "evidence_threshold",
]

#: Status codes of an arc in the evidence model.
EVIDENCE_ALIVE = 0
EVIDENCE_CARVED = 1  # every bin carved


class EvidenceParams(NamedTuple):
    """The sensor model of evidence carving (module docstring), SI units, radians.

    Attributes
    ----------
    tolerance : float
        ε, metres: the freespace of a reading of range r ends at ``r - ε``.
    support_tolerance : float
        ε_s, metres: a reading whose range is within ε_s of ``|p - o_j|`` supports ``p``.
    edge_gain : float
        g in (0, 1]: sensitivity at the beam edge relative to the axis.
    incidence_full : float
        γ0, radians: below it a surface is heard fully.
    incidence_zero : float
        γ1 > γ0, radians: above it only the floor ``rough`` is left.
    rough : float
        ρ in [0, 1]: detection at glancing incidence (rough walls, edges, corners).
    max_detect : float
        P_max in (0, 1): detection on the axis, head-on, at zero range.
    range_scale : float
        L, metres: detection halves at ``d = L`` (spreading and absorption).
    threshold : float
        T > 0: evidence (log-odds of misses) that carves a bin.
    establish : float
        S_est: support that makes a bin established (occludes what lies behind it).
    cos_psi : float
        cos ψ of ATM's minimum transversal angle (crossings kept when ``|cos γ| ≤ cos ψ``).
    protect : float
        Factor in [0, 1] on a newer reading's evidence against an established bin.
    viewpoint_spacing : float
        Metres: a reading of the same sensor counts as a distinct viewpoint of an arc only when
        its origin is at least this far from the arc's (repeated looks from one place at one
        phantom do not confirm it).
    transmit : float
        Factor in [0, 1] on transmission evidence (0: off): a newer echo confirmed by other
        sensors behind a point says that the sound passed through the point (module
        docstring).
    confirm : float
        Other-sensor support at which a bin of a new arc counts as fully confirmed for
        transmission.
    """

    tolerance: float
    support_tolerance: float
    edge_gain: float
    incidence_full: float
    incidence_zero: float
    rough: float
    max_detect: float
    range_scale: float
    threshold: float
    establish: float
    cos_psi: float
    protect: float
    viewpoint_spacing: float
    transmit: float
    confirm: float


def evidence_threshold(carve_probability: float) -> float:
    """``T = -log(1 - P_carve)``: the evidence of one reading with ``P_detect = P_carve``.

    Examples
    --------
    >>> round(evidence_threshold(0.9), 4)
    2.3026
    """
    return -math.log1p(-carve_probability)


@compiled_inline
def _incidence_gain(cos_gamma: float, cos_full: float, cos_zero: float, rough: float) -> float:
    """``I(γ)`` (module docstring) from ``cos γ``; ``cos_full > cos_zero``. np.divide is
    ``/`` without numba's zero-divisor test (a branch that keeps a loop scalar)."""
    if cos_gamma >= cos_full:
        return 1.0
    if cos_gamma <= cos_zero:
        return rough
    return rough + float(np.divide((1.0 - rough) * (cos_gamma - cos_zero), cos_full - cos_zero))


@compiled_inline
def _bin_of_sine(sine: float, edges: FloatArray, bins: int, scale: float) -> int:
    """Bin index of a direction inside a beam (``along > 0``) from the sine of its angle to the
    axis, ``edges[k]`` the sines of the bin edges (increasing; the beam is narrower than π):
    the same bin as :func:`_bin_of` of the angle, without an arc tangent (clamped).

    The largest ``k`` in ``1 .. K - 1`` with ``edges[k] <= sine``, else 0. Found from a guess
    that treats the sines as evenly spaced (``scale = K / (edges[K] - edges[0])``; within a
    bin of the answer for a beam of 22.5°), then stepped to the exact bin by the comparisons
    themselves, so the guess changes only the speed: a binary search took 4-5 branches that
    the processor could not predict, for every supporting bin.
    """
    return _bin_from_guess(_sine_guess(sine, edges[0], bins, scale), sine, edges, bins)


@compiled_inline
def _sine_guess(sine: float, first_edge: float, bins: int, scale: float) -> int:
    """:func:`_bin_of_sine`'s guess (no branch: a loop of these runs on several sines at
    once)."""
    guess = (sine - first_edge) * scale
    # Clamped as a float before the conversion: for a very narrow beam the guess exceeds the
    # int64 range, and int() of that is undefined (it gave a huge negative index).
    return int(min(guess, bins - 1.0)) if guess > 0.0 else 0  # NaN: 0, as the search gave


@compiled_inline
def _bin_from_guess(k: int, sine: float, edges: FloatArray, bins: int) -> int:
    """:func:`_bin_of_sine` stepped from the guess ``k`` (in ``0 .. K - 1``)."""
    while k < bins - 1 and edges[k + 1] <= sine:
        k += 1
    while k > 0 and edges[k] > sine:
        k -= 1
    return k


@compiled
def detect_probability(vx: float, vy: float, ex: float, ey: float, axis_x: float, axis_y: float,
                       sin_half: float, edge_gain: float, cos_full: float, cos_zero: float,
                       rough: float, max_detect: float, range_scale: float) -> float:
    """``P_detect`` of a reading at a point ``p`` inside its beam (module docstring).

    ``v = p - o_j`` (metres), ``e`` the unit direction of ``p`` from the older arc's origin,
    ``axis`` the reading's unit axis, ``sin_half = sin(φ_j/2)``; ``cos_full = cos γ0``,
    ``cos_zero = cos γ1``.

    Examples
    --------
    Head-on on the axis at 1 m, with P_max = 0.95, L = 20 m:

    >>> p = detect_probability(1.0, 0.0, 1.0, 0.0, 1.0, 0.0, math.sin(0.2), 0.5,
    ...                        math.cos(0.2), math.cos(0.5), 0.05, 0.95, 20.0)
    >>> round(p, 4)  # 0.95 / (1 + 1/20)
    0.9048
    """
    d = math.sqrt(vx * vx + vy * vy)
    if d <= 0.0:
        return max_detect
    sin_off = abs(vx * axis_y - vy * axis_x) / d
    u = min(sin_off / sin_half, 1.0)
    beam = 1.0 - (1.0 - edge_gain) * u * u
    cos_gamma = abs(ex * vx + ey * vy) / d
    inc = _incidence_gain(cos_gamma, cos_full, cos_zero, rough)
    return max_detect * beam * inc / (1.0 + d / range_scale)


@compiled_inline
def _store_crossing(bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32],
                    spill: FloatArray, spilled: int, slot: int, value: float) -> int:
    """Append ``value`` to row ``slot`` of the crossing store; when the row is full, to
    ``spill`` instead (``(slot, value)`` at row ``spilled``). ``counts[slot]`` counts both, so
    the spilled crossings of a row are its last ones, in order. Returns the spilled rows."""
    if counts[slot] < bearings.shape[1]:
        bearings[slot, counts[slot]] = value
    else:
        spill[spilled, 0] = slot
        spill[spilled, 1] = value
        spilled += 1
    counts[slot] += 1
    return spilled


@compiled_inline
def _crossings(j: int, i: int, x: FloatArray, y: FloatArray, r: FloatArray,
               cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
               cos_psi: float, bearings: npt.NDArray[np.float32],
               counts: npt.NDArray[np.int32], spill: FloatArray, spilled: int,
               ) -> tuple[int, int]:
    """ATM's transversal crossings of arcs ``j`` and ``i`` (as ``methods/atm.py``), stored
    (:func:`_store_crossing`). Returns the crossings kept and the rows of ``spill`` used."""
    xj = x[j]
    yj = y[j]
    rj = r[j]
    ri = r[i]
    dx = x[i] - xj
    dy = y[i] - yj
    d2 = dx * dx + dy * dy
    if abs(rj * rj + ri * ri - d2) > 2.0 * rj * ri * cos_psi or d2 == 0.0:
        return 0, spilled
    a, h = common_chord(d2, rj, ri)
    d = math.sqrt(d2)
    ux = dx / d
    uy = dy / d
    kept = 0
    cj = cos_axis[j]
    sj = sin_axis[j]
    for sign in (1.0, -1.0):
        px = a * ux - sign * h * uy
        py = a * uy + sign * h * ux
        along_j = px * cj + py * sj
        if along_j < rj * cos_half[j]:
            continue
        qx = px - dx
        qy = py - dy
        along_i = qx * cos_axis[i] + qy * sin_axis[i]
        if along_i < ri * cos_half[i]:
            continue
        spilled = _store_crossing(bearings, counts, spill, spilled, j,
                                  math.atan2(cj * py - sj * px, along_j))
        spilled = _store_crossing(bearings, counts, spill, spilled, i,
                                  math.atan2(cos_axis[i] * qy - sin_axis[i] * qx, along_i))
        kept += 1
    return kept, spilled


@compiled_inline
def _bin_of(rel: float, half: float, width: float, bins: int) -> int:
    """Bin index of a bearing ``rel`` relative to the axis (clamped to the beam)."""
    k = math.floor((rel + half) / width)
    return min(max(k, 0), bins - 1)


@compiled_inline
def _transmission(slot: int, passed: FloatArray, n_passed: int, trans: FloatArray,
                  free: FloatArray, status: Int8Array, params: EvidenceParams) -> int:
    """Transmission evidence of the new reading ``slot`` (module docstring).

    For each older live bin it looked past (``passed`` rows: arc, bin, the new arc's bin
    behind it, ``P_beam cos γ``, ``protect`` factor, evidence already given), the chance that
    the sound went through is ``transmit · P_beam · cos γ · min(1, S / S_conf)``, ``S`` the
    new arc's support from other sensors in the bin behind; the bin gains what that exceeds
    the incidence evidence by (one reading, one event: the larger of the two counts). Returns
    the arcs this carved fully.
    """
    threshold = params.threshold
    bins = free.shape[1]
    fully = 0
    for m in range(n_passed):
        kj = int(passed[m, 2])
        s = trans[kj]
        if s <= 0.0 or free[slot, kj] >= threshold:
            continue  # nothing confirmed behind, or that bin of the new arc is occluded
        i = int(passed[m, 0])
        k = int(passed[m, 1])
        if status[i] != EVIDENCE_ALIVE or free[i, k] >= threshold:
            continue
        p_t = params.transmit * passed[m, 3] * min(1.0, s / params.confirm)
        w_t = -math.log1p(-p_t) * passed[m, 4]
        if w_t <= passed[m, 5]:
            continue
        free[i, k] += w_t - passed[m, 5]
        if free[i, k] >= threshold:
            alive = False
            for kk in range(bins):
                if free[i, kk] < threshold:
                    alive = True
                    break
            if not alive:
                status[i] = EVIDENCE_CARVED
                fully += 1
    return fully


class _Beam(NamedTuple):
    """The new reading ``j`` as the weighing pass sees it (metres, radians)."""

    x: float
    y: float
    r: float
    cos_axis: float
    sin_axis: float
    half: float  # φ_j / 2
    step: float  # Δ_j = φ_j / K
    sin_half: float
    cos_half2: float  # cos²(φ_j / 2): beam membership without a root
    free_r: float  # r_j - ε: the end of the freespace sector F_j (eq. 3.2)
    reach: float  # r_j + ε_s: beyond it a point is neither free nor supported
    reach2: float
    edge1_x: float  # unit vectors of the beam's lower and upper edges
    edge1_y: float
    edge2_x: float
    edge2_y: float
    # The sensor model's derived constants, computed once per reading, not per older arc.
    edge_loss: float  # 1 - g
    inv_scale: float  # 1 / L
    cos_full: float  # cos γ0
    cos_zero: float  # cos γ1
    spacing2: float  # viewpoint_spacing²


@compiled_inline
def _new_beam(slot: int, x: FloatArray, y: FloatArray, r: FloatArray, beam_width: FloatArray,
              cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray, bins: int,
              params: EvidenceParams) -> _Beam:
    """The new reading's :class:`_Beam`, from its row (once :func:`evidence_add` has
    initialised it)."""
    rj = r[slot]
    half_j = 0.5 * beam_width[slot]
    cj = cos_axis[slot]
    sj = sin_axis[slot]
    sin_half_j = math.sin(half_j)
    cos_half_j = cos_half[slot]
    reach = rj + params.support_tolerance
    return _Beam(
        x[slot], y[slot], rj, cj, sj, half_j, beam_width[slot] / bins, sin_half_j,
        cos_half_j * cos_half_j, rj - params.tolerance, reach, reach * reach,
        cj * cos_half_j + sj * sin_half_j, sj * cos_half_j - cj * sin_half_j,
        cj * cos_half_j - sj * sin_half_j, sj * cos_half_j + cj * sin_half_j,
        1.0 - params.edge_gain, 1.0 / params.range_scale, math.cos(params.incidence_full),
        math.cos(params.incidence_zero), params.viewpoint_spacing * params.viewpoint_spacing,
    )


@compiled_inline
def _mark_near(cx: FloatArray, cy: FloatArray, rho: FloatArray, status: Int8Array,
               beam: _Beam, near_flags: BoolArray) -> None:
    """The cull, for each row ``i`` of the arrays (slices of the history's rows): ``near_flags[i]``
    is False where arc ``i`` is no longer alive or its bounding circle (centre ``(cx[i],
    cy[i])``, radius ``rho[i]``) lies beyond the reach of ``j``'s echo circle, or clear of one
    of the two half-planes whose intersection is ``j``'s beam (φ < π; as
    ``geometry/bounds.py``). No branch, and indices from 0 (no test for negative ones): the
    compiler tests several rows at once."""
    bx = beam.x
    by = beam.y
    reach = beam.reach
    e1x = beam.edge1_x
    e1y = beam.edge1_y
    e2x = beam.edge2_x
    e2y = beam.edge2_y
    for i in range(near_flags.shape[0]):
        dcx = cx[i] - bx
        dcy = cy[i] - by
        r = rho[i]
        far = dcx * dcx + dcy * dcy >= (reach + r) * (reach + r)
        below_lower_edge = e1x * dcy - e1y * dcx < -r
        above_upper_edge = dcx * e2y - dcy * e2x < -r
        near_flags[i] = (status[i] == EVIDENCE_ALIVE) & (not far) & (not below_lower_edge) & (
            not above_upper_edge)


@compiled_inline
def _occlude_behind(slot: int, rel: float, spread: float, beam: _Beam, free: FloatArray,
                    threshold: float) -> int:
    """Carve the bins of the new arc within ``rel ± spread`` (bearings relative to its axis):
    they lie behind an established surface it looked past at a glancing angle, and sound does
    not pass through walls. Returns the bins this carved."""
    bins = free.shape[1]
    k0 = _bin_of(rel - spread, beam.half, beam.step, bins)
    k1 = _bin_of(rel + spread, beam.half, beam.step, bins)
    carved = 0
    for kk in range(k0, k1 + 1):
        if free[slot, kk] < threshold:
            free[slot, kk] = threshold
            carved += 1
    return carved


@compiled_borrowing
def evidence_add(
    slot: int, first_older: int, n_older: int,
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    sensor: npt.NDArray[np.int64], viewpoints: FloatArray, looked: FloatArray,
    others: FloatArray, through: FloatArray, passed: FloatArray, trans: FloatArray,
    scratch: FloatArray, in_beam: BoolArray, bin_index: SlotArray, near: SlotArray,
    near_flags: BoolArray,
    bx: FloatArray, by: FloatArray, ex: FloatArray, ey: FloatArray,
    free: FloatArray, support: FloatArray, located: FloatArray, circle: FloatArray,
    cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
    status: Int8Array, touched: BoolArray, occluded: FloatArray,
    bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], spill: FloatArray,
    params: EvidenceParams, with_atm: bool,
) -> tuple[int, int, int, int]:
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
    x, y, r, theta, beam_width : ndarray, shape (n,)
        The history's rows (metres, radians).
    sensor : ndarray of int64, shape (n,)
        The history's sensor index per row.
    viewpoints : ndarray, shape (n,)
        Support from distinct viewpoints per arc: the sum, over newer or older readings of
        another sensor or from an origin at least ``viewpoint_spacing`` away whose echo circle
        passes through the arc, of the largest ``P_detect`` of that support (updated in place).
    looked : ndarray, shape (n,)
        "Looked through" evidence per arc: ``-log(1 - P)`` summed over distinct viewpoints
        whose free sector covers a bin still alive, ``P`` the largest detection over those bins
        *without* the incidence factor (a phantom in open space has no surface to be glancing
        at; how much this says about a real surface is left to the confidence fit).
    others : ndarray, shape (n,)
        Support from *other sensors* per arc: as ``viewpoints``, but only over readings of
        another sensor. A systematic phantom (crosstalk off the same wall, a multipath path)
        repeats for one sensor as the robot moves, so one sensor's repeated echoes confirm
        each other without being independent; another transducer at another mounting angle
        is closer to independent (updated in place).
    through : ndarray, shape (n,)
        Per new arc, the largest support of an older live bin its free sector passed
        (nearer than ``r_j - 2ε``): how well heard the surface is that its echo would have had
        to cross; the graded form of the occlusion rule (filled for ``slot``).
    passed : ndarray, shape (m, 6)
        Scratch for the transmission pass: one row per older live bin in the new beam's free
        sector (``m`` at least the older arcs' bins); overwritten.
    trans : ndarray, shape (2 K + 3,)
        Scratch: the new arc's support per bin from other sensors' older echoes (overwritten),
        then the sines of its bin edges, the beam width they are for (NaN before the first
        reading) and the scale of :func:`_bin_of_sine`'s guess (kept between readings of the
        same beam width).
    scratch : ndarray, shape (11, G K)
        Scratch of the bin passes (overwritten), ``G >= 1`` older arcs' bins: one entry per
        bin to weigh of a group of up to ``G`` arcs, its offset from the new reading and the
        bin centre's direction (rows 0-4), and what :func:`detect_probability` computes of it
        (rows 5-10).
    in_beam : ndarray of bool, shape (K,)
        Scratch (overwritten): the older arc's bins to weigh.
    bin_index : ndarray of int64, shape (4, G K)
        Scratch (overwritten): per entry its bin and the guess of :func:`_bin_of_sine`; per
        arc of the group its entries and its live bins outside the new beam.
    near, near_flags : ndarray of int64 and bool, shape (n,)
        Scratch (overwritten): the rows that pass the cull (then the group's rows with bins
        to weigh), and the cull's verdict per row.
    bx, by, ex, ey : ndarray, shape (n, K)
        Bin centre points and their unit directions from the arc's origin (filled for ``slot``).
    free, support : ndarray, shape (n, K)
        Evidence of empty space and support per bin (updated in place).
    located : ndarray, shape (n, K)
        Support per bin times the sine of the angle at which the two echo circles meet there:
        how much the support says about where on the arc the echo came from (updated in
        place; it picks the kept run of a split arc).
    circle : ndarray, shape (3, n)
        A circle containing each full arc (a cheap first test): rows centre x, centre y,
        radius (a row each, so that the cull reads them contiguously).
    cos_axis, sin_axis, cos_half : ndarray, shape (n,)
        Axis direction and ``cos(φ/2)`` per row (filled for ``slot``).
    status : ndarray of int8, shape (n,)
        ``EVIDENCE_ALIVE`` or ``EVIDENCE_CARVED``.
    touched : ndarray of bool, shape (n,)
        The arc has received evidence (processed, Table I).
    occluded : ndarray, shape (n,)
        Share of the arc's bins carved by occlusion when it arrived (the multipath flag).
    bearings, counts : ndarray
        ATM's crossing store (bearings relative to the axis), as in ``methods/atm.py``:
        ``bearings`` has a column per crossing the busiest arc has kept so far, ``counts`` the
        crossings of each row, spilled ones included.
    spill : ndarray, shape (m, 2)
        Where crossings go that do not fit their row: ``(row, bearing)`` in the order found;
        ``m`` at least ``4 (older + 1)`` (an arc meets each older arc at most twice, and each
        crossing goes to two rows). The caller widens the store and moves them there.
    params : EvidenceParams
        The sensor model.
    with_atm : bool
        Find ATM crossings too.

    Returns
    -------
    fully_carved, crossings, occluded_bins, spilled : int
        Arcs whose last bin was carved by this reading; ATM crossings kept; bins of the new arc
        carved by occlusion; rows of ``spill`` used (0: every crossing fitted).
    """
    bins = bx.shape[1]
    # The new arc's profile: bin centres p_k on C_j (eq. 2.1) at τ_k = θ1 + (k + ½) Δ, empty
    # evidence, the bounding circle, and the scratch ``trans``. Written here, not in a helper:
    # a compiled helper taking these twenty arrays, inlined or not, cost 4-8 % per reading.
    xj = x[slot]
    yj = y[slot]
    rj = r[slot]
    half_j = 0.5 * beam_width[slot]
    step_j = beam_width[slot] / bins
    cos_axis[slot] = math.cos(theta[slot])
    sin_axis[slot] = math.sin(theta[slot])
    cos_half[slot] = math.cos(half_j)
    for k in range(bins):
        tau = theta[slot] - half_j + (k + 0.5) * step_j
        ex[slot, k] = math.cos(tau)
        ey[slot, k] = math.sin(tau)
        bx[slot, k] = xj + rj * ex[slot, k]
        by[slot, k] = yj + rj * ey[slot, k]
        free[slot, k] = 0.0
        support[slot, k] = 0.0
        located[slot, k] = 0.0
    c0, c1, c2 = arc_bounding_circle(xj, yj, rj, theta[slot] - half_j, theta[slot] + half_j)
    circle[0, slot] = c0
    circle[1, slot] = c1
    circle[2, slot] = c2
    status[slot] = EVIDENCE_ALIVE
    touched[slot] = False
    occluded[slot] = 0.0
    viewpoints[slot] = 0.0
    looked[slot] = 0.0
    others[slot] = 0.0
    if trans[2 * bins + 1] != beam_width[slot]:  # the edges' beam width (NaN: none yet)
        # The scratch's second part: sines of j's bin edges; they depend on the beam width
        # only, so they are kept while it stays the same (a ring of like sensors: always).
        for k in range(bins + 1):
            trans[bins + k] = math.sin(-half_j + k * step_j)
        trans[2 * bins + 1] = beam_width[slot]
        trans[2 * bins + 2] = bins / (trans[2 * bins] - trans[bins])
    for k in range(bins):  # its first part: j's support from other sensors
        trans[k] = 0.0
    counts[slot] = 0
    beam = _new_beam(slot, x, y, r, beam_width, cos_axis, sin_axis, cos_half, bins, params)
    edges = trans[bins : 2 * bins + 1]
    edge_scale = trans[2 * bins + 2]  # the guess of _bin_of_sine
    # Weigh every older live arc against j (one loop here, not a compiled helper: a helper
    # taking these arrays, per arc or per reading, inlined or not, measured 3-20 % slower).
    threshold = params.threshold
    cj = beam.cos_axis
    sj = beam.sin_axis
    free_r = beam.free_r
    reach2 = beam.reach2
    cos_half2 = beam.cos_half2
    sin_half = beam.sin_half
    edge_loss = beam.edge_loss
    inv_scale = beam.inv_scale
    cos_full = beam.cos_full
    cos_zero = beam.cos_zero
    max_detect = params.max_detect
    rough = params.rough
    # The bins to weigh of a group of older arcs, one entry each, in arc and bin order:
    # inputs (rows 0-4) and what pass 2 computes of them (rows 5-10).
    e_vx = scratch[0]
    e_vy = scratch[1]
    e_d2 = scratch[2]
    e_ex = scratch[3]
    e_ey = scratch[4]
    e_d = scratch[5]
    e_sine = scratch[6]
    e_beam = scratch[7]
    e_cos = scratch[8]
    e_p = scratch[9]
    e_loc = scratch[10]
    e_bin = bin_index[0]  # the entry's bin of its older arc
    e_guess = bin_index[1]  # the guess of the bin of j behind it
    arc_marked = bin_index[2]  # per arc of the group: its entries
    arc_alive = bin_index[3]  # per arc of the group: live bins outside j's reach or beam
    group_size = max(1, scratch.shape[1] // bins)  # arcs a group's entries always hold
    first_edge = edges[0]
    fully = 0
    crossings = 0
    occluding = 0
    n_passed = 0
    spilled = 0
    top_through = 0.0
    # The cull, for all older rows at once (two runs of rows: the ring wraps), then the
    # rows that pass it, oldest first, a group at a time.
    # Marking every row up front gives the one loop's result because nothing in the loop
    # below changes another older arc's status or bounding circle, nor the free evidence
    # of a row other than the arc in hand and the new one (``slot``, never an older row):
    # status[slot] and the transmission come after the loop. For the same reason pass 1 can
    # read every arc's free evidence of a group before pass 3 writes any of them, and pass 2
    # reads only geometry: the passes run over a group's arcs in turn, and pass 3 in the arcs'
    # order, so every value is the one loop's.
    storage = x.shape[0]
    n_older = min(n_older, storage)  # no window past the rows (no bounds checks here)
    n_near = 0
    end = first_older + n_older
    for lo, hi in ((first_older, min(end, storage)), (0, max(end - storage, 0))):
        _mark_near(circle[0, lo:hi], circle[1, lo:hi], circle[2, lo:hi], status[lo:hi], beam,
                   near_flags[lo:hi])
        for i in range(lo, hi):
            near[n_near] = i
            n_near += near_flags[i]
    q = 0
    while q < n_near:
        # Pass 1 and the crossings for the next older arcs, until group_size of them have
        # bins to weigh (their rows in ``near[group:group_end]``, their bins the entries).
        group = q
        group_end = q
        n_entries = 0
        while q < n_near and group_end - group < group_size:
            i = near[q]
            q += 1
            if with_atm:
                kept, spilled = _crossings(slot, i, x, y, r, cos_axis, sin_axis, cos_half,
                                           params.cos_psi, bearings, counts, spill, spilled)
                crossings += kept
            # Pass 1: which bins are left to weigh (free evidence below T) and lie in j's
            # reach and beam; no branch, so the compiler runs it on several bins at once.
            alive_bins = 0
            n_in = 0
            for k in range(bins):
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
            if n_in == 0:
                # Nothing to weigh: pass 3 would add nothing (its sums would add 0.0 to sums
                # of non-negative terms, which leaves them as they are).
                if alive_bins == 0:
                    status[i] = EVIDENCE_CARVED
                    fully += 1
                continue
            near[group_end] = i  # q > group_end: a row already read
            arc_marked[group_end - group] = n_in
            arc_alive[group_end - group] = alive_bins
            group_end += 1
            e = n_entries
            for k in range(bins):  # the bins to weigh, in order, as the group's entries
                e_bin[e] = k
                e += in_beam[k]
            for e in range(n_entries, n_entries + n_in):
                k = e_bin[e]
                vx = bx[i, k] - xj
                vy = by[i, k] - yj
                e_vx[e] = vx
                e_vy[e] = vy
                e_d2[e] = vx * vx + vy * vy
                e_ex[e] = ex[i, k]
                e_ey[e] = ey[i, k]
            n_entries += n_in
        # Pass 2: detect_probability, inlined, for every entry of the group at once (one
        # loop over all of them: the compiler runs it on several entries at once when they
        # are many, 20 or more, and the entries are only the bins to weigh, 7 of an older
        # arc's 24 at history 1,000). np.divide is ``/`` (the same rounding) without numba's
        # zero-divisor test, whose branch would keep the loop scalar; bins in the beam have
        # d > 0 (along > 0) unless d² underflows (a range near 1e-300: then inv_d = inf and
        # the values stay finite where ``/`` raised ZeroDivisionError).
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
            p = p_beam * _incidence_gain(cos_gamma, cos_full, cos_zero, rough)
            e_p[e] = p
            # What the support path needs: the localised support, the bin of j behind.
            e_loc[e] = p * abs(e_ex[e] * vy - e_ey[e] * vx) * inv_d
            e_guess[e] = _sine_guess(sine, first_edge, bins, edge_scale)
        # Pass 3: the evidence, arc after arc, in bin order.
        start = 0
        for g in range(group, group_end):
            i = near[g]
            ox = x[i] - xj
            oy = y[i] - yj
            other = sensor[i] != sensor[slot]
            distinct = other or ox * ox + oy * oy >= beam.spacing2
            half_bin_arc = 0.5 * (beam_width[i] / bins) * r[i]  # Δ_i r_i / 2
            alive_bins = arc_alive[g - group]
            top_support = 0.0
            top_looked = 0.0
            stop = start + arc_marked[g - group]
            for e in range(start, stop):
                k = e_bin[e]
                d = e_d[e]
                if d >= free_r and abs(d - beam.r) > params.support_tolerance:
                    alive_bins += 1
                    continue
                vx = e_vx[e]
                vy = e_vy[e]
                sine = e_sine[e]
                p_beam = e_beam[e]
                p = e_p[e]
                if d < free_r:
                    f = free[i, k]
                    touched[i] = True
                    if distinct:
                        top_looked = max(top_looked, p_beam)
                    established = (support[i, k] >= params.establish and f < 0.5 * threshold)
                    if d < free_r - params.tolerance:
                        top_through = max(top_through, support[i, k])
                    if established and d < free_r - params.tolerance:
                        # An established surface j looked past at a glancing angle: the bins
                        # of j behind it cannot hold j's echo (sound does not pass through
                        # walls).
                        along = vx * cj + vy * sj
                        occluding += _occlude_behind(slot, math.atan2(cj * vy - sj * vx, along),
                                                     half_bin_arc / d, beam, free, threshold)
                        touched[slot] = True
                    factor = params.protect if established else 1.0
                    w = -math.log1p(-p) * factor
                    f += w
                    free[i, k] = f
                    if f < threshold:
                        alive_bins += 1
                        if params.transmit > 0.0 and p < p_beam and n_passed < passed.shape[0]:
                            # Kept for the transmission pass (after j's support is known).
                            passed[n_passed, 0] = i
                            passed[n_passed, 1] = k
                            passed[n_passed, 2] = _bin_from_guess(e_guess[e], sine, edges, bins)
                            passed[n_passed, 3] = p_beam * e_cos[e]  # blocked, not echoed
                            passed[n_passed, 4] = factor
                            passed[n_passed, 5] = w
                            n_passed += 1
                else:  # on j's echo circle: support, not freespace
                    alive_bins += 1
                    touched[i] = True
                    touched[slot] = True
                    top_support = max(top_support, p)
                    # Localised support: times the sine of the angle between the two circles
                    # there (tangent circles, one sensor stepping along its axis, say nothing
                    # of *where* on the arc the echo came from).
                    support[i, k] += p
                    kb = _bin_from_guess(e_guess[e], sine, edges, bins)
                    support[slot, kb] += p
                    loc = e_loc[e]
                    located[i, k] += loc
                    located[slot, kb] += loc
                    if other:
                        trans[kb] += p
            start = stop
            # The per-arc sums, mutual: support from distinct viewpoints and other sensors.
            if distinct:
                viewpoints[i] += top_support
                viewpoints[slot] += top_support
                if top_looked > 0.0:
                    looked[i] += -math.log1p(-top_looked)
            if other:
                others[i] += top_support
                others[slot] += top_support
            if alive_bins == 0:
                status[i] = EVIDENCE_CARVED
                fully += 1
    occluded[slot] = occluding / bins
    through[slot] = top_through
    fully += _transmission(slot, passed, n_passed, trans, free, status, params)
    if occluding >= bins:
        status[slot] = EVIDENCE_CARVED
        fully += 1
    return fully, crossings, occluding, spilled


@compiled_borrowing
def evidence_add_many(
    first: int, count: int, capacity: int,
    x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray, beam_width: FloatArray,
    sensor: npt.NDArray[np.int64], viewpoints: FloatArray, looked: FloatArray,
    others: FloatArray, through: FloatArray, passed: FloatArray, trans: FloatArray,
    scratch: FloatArray, in_beam: BoolArray, bin_index: SlotArray, near: SlotArray,
    near_flags: BoolArray,
    bx: FloatArray, by: FloatArray, ex: FloatArray, ey: FloatArray,
    free: FloatArray, support: FloatArray, located: FloatArray, circle: FloatArray,
    cos_axis: FloatArray, sin_axis: FloatArray, cos_half: FloatArray,
    status: Int8Array, touched: BoolArray, occluded: FloatArray,
    bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], spill: FloatArray,
    params: EvidenceParams, with_atm: bool,
) -> tuple[int, int, int, int, int]:
    """:func:`evidence_add` for the arcs of sequence numbers ``first .. first + count - 1``,
    in order, each against the ``capacity - 1`` (or fewer) arcs before it: one compiled call
    per block of readings (no Python between arcs), the same result as one call per arc.

    The arrays are those of :func:`evidence_add`.

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
    storage = x.shape[0]
    fully = 0
    crossings = 0
    occluding = 0
    for sequence in range(first, first + count):
        live = min(sequence + 1, capacity)
        start = (sequence + 1 - live) % storage
        a, b, c, spilled = evidence_add(
            sequence % storage, start, live - 1, x, y, r, theta, beam_width,
            sensor, viewpoints, looked, others, through, passed, trans, scratch, in_beam,
            bin_index, near, near_flags, bx, by, ex, ey, free,
            support, located, circle, cos_axis, sin_axis, cos_half, status, touched, occluded,
            bearings, counts, spill, params, with_atm)
        fully += a
        crossings += b
        occluding += c
        if spilled:
            return fully, crossings, occluding, sequence + 1, spilled
    return fully, crossings, occluding, first + count, 0


@compiled_borrowing
def evidence_free(
    xj: float, yj: float, max_range: float, theta_j: float, phi_j: float, sensor_j: int,
    older: SlotArray, x: FloatArray, y: FloatArray, beam_width: FloatArray,
    sensor: npt.NDArray[np.int64], looked: FloatArray, bx: FloatArray, by: FloatArray,
    ex: FloatArray, ey: FloatArray, free: FloatArray, support: FloatArray, circle: FloatArray,
    status: Int8Array, touched: BoolArray, params: EvidenceParams,
) -> int:
    """Add the free-space evidence of a no-echo reading against every ``older`` arc.

    The reading is at ``(xj, yj)`` (metres) along ``theta_j`` with beam width ``phi_j``
    (radians), from sensor ``sensor_j``, and heard nothing up to ``max_range`` metres: every
    bin centre of a live arc inside its beam nearer than ``max_range - ε`` gains
    ``-log(1 - P_detect)`` (times ``protect`` where the bin is established), as in
    :func:`evidence_add`; ``touched`` and ``looked`` are updated the same way. The arrays are
    those of :func:`evidence_add`.

    Returns
    -------
    int
        Arcs whose last bin this reading carved.
    """
    bins = bx.shape[1]
    threshold = params.threshold
    free_r = max_range - params.tolerance
    if free_r <= 0.0:
        return 0
    half_j = 0.5 * phi_j
    cj = math.cos(theta_j)
    sj = math.sin(theta_j)
    sin_half_j = math.sin(half_j)
    cos_half_j = math.cos(half_j)
    cos_half_j2 = cos_half_j * cos_half_j
    reach2 = free_r * free_r
    edge_loss = 1.0 - params.edge_gain
    inv_scale = 1.0 / params.range_scale
    u1x = cj * cos_half_j + sj * sin_half_j
    u1y = sj * cos_half_j - cj * sin_half_j
    u2x = cj * cos_half_j - sj * sin_half_j
    u2y = sj * cos_half_j + cj * sin_half_j
    cos_full = math.cos(params.incidence_full)
    cos_zero = math.cos(params.incidence_zero)
    spacing2 = params.viewpoint_spacing * params.viewpoint_spacing
    fully = 0
    for i in older:
        if status[i] != EVIDENCE_ALIVE:
            continue
        dcx = circle[0, i] - xj
        dcy = circle[1, i] - yj
        rho = circle[2, i]
        if dcx * dcx + dcy * dcy >= (free_r + rho) * (free_r + rho):
            continue
        if u1x * dcy - u1y * dcx < -rho or dcx * u2y - dcy * u2x < -rho:
            continue
        ox = x[i] - xj
        oy = y[i] - yj
        distinct = sensor[i] != sensor_j or ox * ox + oy * oy >= spacing2
        alive_bins = 0
        top_looked = 0.0
        for k in range(bins):
            f = free[i, k]
            if f >= threshold:
                continue
            vx = bx[i, k] - xj
            vy = by[i, k] - yj
            d2 = vx * vx + vy * vy
            along = vx * cj + vy * sj
            if d2 >= reach2 or along <= 0.0 or along * along < d2 * cos_half_j2:
                alive_bins += 1
                continue
            d = math.sqrt(d2)
            u = min(abs(vx * sj - vy * cj) / (d * sin_half_j), 1.0)
            p_beam = params.max_detect * (1.0 - edge_loss * u * u) / (1.0 + d * inv_scale)
            cos_gamma = abs(ex[i, k] * vx + ey[i, k] * vy) / d
            p = p_beam * _incidence_gain(cos_gamma, cos_full, cos_zero, params.rough)
            touched[i] = True
            if distinct:
                top_looked = max(top_looked, p_beam)
            established = support[i, k] >= params.establish and f < 0.5 * threshold
            f += -math.log1p(-p) * (params.protect if established else 1.0)
            free[i, k] = f
            if f < threshold:
                alive_bins += 1
        if distinct and top_looked > 0.0:
            looked[i] += -math.log1p(-top_looked)
        if alive_bins == 0:
            status[i] = EVIDENCE_CARVED
            fully += 1
    return fully


@compiled_inline
def _located_median(located: FloatArray, s: int, start: int, end: int, lo_axis: float,
                    step: float, mid: float) -> float:
    """Bearing of the median of the localised support over bins ``start .. end - 1`` of arc
    ``s`` (``mid`` where there is none)."""
    total = 0.0
    for k in range(start, end):
        total += located[s, k]
    if total <= 0.0:
        return mid
    acc = 0.0
    for k in range(start, end):
        acc += located[s, k]
        if acc >= 0.5 * total:
            return lo_axis + (k + 0.5) * step
    return mid


@compiled_inline
def _posterior_weight(located: float, free: float, with_located: bool) -> float:
    """Unnormalised posterior that the echo came from a bin: ``exp(-F)``, the probability
    that every newer reading that looked there missed a surface there (``F = Σ -log(1 - P)``,
    the bin's free evidence; strictly, of the evidence left after the ``protect`` factor and
    with transmission's share added, so a likelihood in that model's sense), times the bin's
    localised support when the run has any."""
    w = math.exp(-free)
    return w * located if with_located else w


@compiled_inline
def _posterior_median(located: FloatArray, free: FloatArray, weights: FloatArray, s: int,
                      start: int, end: int, lo_axis: float, step: float, mid: float) -> float:
    """Bearing of the median of the posterior over bins ``start .. end - 1`` of arc ``s``
    (:func:`_posterior_weight`; uniform inside a bin, so the median is interpolated: a run
    with equal weights gives its middle, eq. 3.6, to rounding). ``mid`` where every weight is
    0. Where the weight reaches exactly half at the end of a bin followed by bins of weight 0,
    every point of those bins is a median: their middle is taken (the lower end would depend on
    the direction of the scan: a mirror-image profile would not give the mirror-image point).
    ``weights`` (shape (K,), overwritten) keeps each bin's weight between the sum and the
    median: one ``exp`` a bin, not two."""
    with_located = False
    for k in range(start, end):
        if located[s, k] > 0.0:
            with_located = True
    total = 0.0
    for k in range(start, end):
        weights[k] = _posterior_weight(located[s, k], free[s, k], with_located)
        total += weights[k]
    if not total > 0.0:
        return mid
    half = 0.5 * total
    acc = 0.0
    for k in range(start, end):
        w = float(weights[k])
        if w > 0.0 and acc + w >= half:
            # At most the whole bin: a weight below an ulp of ``half`` can round acc + w up to
            # it while half - acc is still larger than the weight.
            point = k + min((half - acc) / w, 1.0)
            if acc + w == half:  # flat at one half over the zero-weight bins after k
                after = k + 1
                while after < end and not weights[after] > 0.0:
                    after += 1
                if after < end:
                    point = 0.5 * (k + 1 + after)
            return lo_axis + point * step
        acc += w
    return mid


@compiled_inline
def _whole_beam_bound(r: float, phi: float) -> float:
    """``E_s = 2 r sin(φ/4)`` (eq. 5.3): the bound of a point at the middle of the full beam."""
    return 2.0 * r * math.sin(0.25 * phi)


@compiled_inline
def _hull_bound(r: float, point: float, hull_lo: float, hull_hi: float, step: float) -> float:
    """``2 r sin(e/2)`` (eq. 5.3), ``e`` the largest angle from the point's bearing to an end of
    the surviving hull ``[hull_lo, hull_hi]`` plus half a bin (the binned ends), at most π."""
    e = max(point - hull_lo, hull_hi - point) + 0.5 * step
    return 2.0 * r * math.sin(0.5 * min(e, math.pi))


@compiled_inline
def _crossings_per_bin(in_bin: FloatArray, crossing_bin: SlotArray,
                       bearings: npt.NDArray[np.float32], s: int, c: int, half: float,
                       step: float) -> None:
    """Count arc ``s``'s first ``c`` ATM crossings into ``in_bin`` (shape (K,), overwritten),
    and keep each crossing's bin in ``crossing_bin`` (for :func:`_run_crossings`)."""
    bins = in_bin.shape[0]
    for k in range(bins):
        in_bin[k] = 0.0
    for m in range(c):
        kb = _bin_of(float(bearings[s, m]), half, step, bins)
        crossing_bin[m] = kb
        in_bin[kb] += 1.0


@compiled_inline
def _kept_run(free: FloatArray, located: FloatArray, in_bin: FloatArray, s: int,
              threshold: float) -> tuple[int, int, int, int, int]:
    """The surviving runs of arc ``s`` (bins with free evidence below ``T``), and the one kept:
    the most ATM crossings plus the largest localised support; ties, the longest, then the
    first.

    Returns
    -------
    start, end, first, last, runs
        Bins ``start .. end - 1`` of the kept run, ``first .. last - 1`` of the surviving hull
        (-1 when nothing survives), and the number of runs.
    """
    bins = free.shape[1]
    best_score = -1.0
    best_start = -1
    best_end = -1
    first = -1
    last = -1
    runs = 0
    k = 0
    while k < bins:
        if not free[s, k] < threshold:  # carved; a NaN counts as carved (else no progress)
            k += 1
            continue
        start = k
        score = 0.0
        top = 0.0
        while k < bins and free[s, k] < threshold:
            score += in_bin[k]
            top = max(top, located[s, k])
            k += 1
        score += top
        runs += 1
        if first < 0:
            first = start
        last = k
        better = score > best_score or (
            score == best_score and k - start > best_end - best_start)
        if better:
            best_score = score
            best_start = start
            best_end = k
    return best_start, best_end, first, last, runs


@compiled_inline
def _run_evidence(support: FloatArray, free: FloatArray, s: int, start: int, end: int,
                  threshold: float) -> tuple[float, float]:
    """Largest support of a bin in run ``start .. end - 1`` of arc ``s``, and the run's mean
    free evidence in units of ``T``."""
    top = 0.0
    mean_free = 0.0
    for k in range(start, end):
        top = max(top, support[s, k])
        mean_free += free[s, k]
    return top, mean_free / ((end - start) * threshold)


#: numba's sort (``numba/misc/quicksort.py``) sorts this many values or fewer by insertion.
_INSERTION_SORT_MAX = 15


@compiled_inline
def _sort_in_place(values: FloatArray, n: int) -> None:
    """Sort ``values[:n]`` in place, in exactly the order ``np.sort`` would leave them: up to
    :data:`_INSERTION_SORT_MAX` values by numba's own insertion sort, with its comparison
    (NaN last), written out here; more by ``ndarray.sort``. ``np.sort`` allocated a copy (and
    numba's sort a stack) for every arc with crossings, a third of the estimates' time."""
    if n > _INSERTION_SORT_MAX:
        values[:n].sort()
        return
    for i in range(1, n):
        v = values[i]
        j = i
        while j > 0 and (v < values[j - 1] or (
                math.isnan(values[j - 1]) and not math.isnan(v))):
            values[j] = values[j - 1]
            j -= 1
        values[j] = v


@compiled_inline
def _run_crossings(values: FloatArray, crossing_bin: SlotArray,
                   bearings: npt.NDArray[np.float32], s: int, c: int, start: int, end: int,
                   ) -> tuple[int, float]:
    """ATM's crossings of arc ``s`` inside bins ``start .. end - 1`` (copied into ``values``),
    and their median bearing relative to the axis (0 when there are none). ``crossing_bin``
    holds the bins of its first ``c`` crossings (:func:`_crossings_per_bin`: one division a
    crossing, not two)."""
    kept = 0
    for m in range(c):
        kb = crossing_bin[m]
        if start <= kb < end:
            values[kept] = float(bearings[s, m])
            kept += 1
    if kept == 0:
        return 0, 0.0
    _sort_in_place(values, kept)
    return kept, 0.5 * (values[(kept - 1) // 2] + values[kept // 2])


@compiled
def evidence_estimates(
    slots: SlotArray, x: FloatArray, y: FloatArray, r: FloatArray, theta: FloatArray,
    beam_width: FloatArray, free: FloatArray, support: FloatArray, located: FloatArray,
    status: Int8Array,
    bearings: npt.NDArray[np.float32], counts: npt.NDArray[np.int32], threshold: float,
    atm_bound: float, with_atm: bool, place_located: bool, posterior: bool = True,
    posterior_uncut: bool = False, min_crossings: int = 3,
) -> tuple[BoolArray, FloatArray, FloatArray, FloatArray, FloatArray, BoolArray,
           FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per slot: the surviving piece, its point, width and bound, and the evidence behind it.

    The surviving bins form runs; with several (a *split* arc), the run with the most
    localised support (``located``) plus ATM crossings is kept (ties: the longest, then the
    first). Where on the run the echo came from (eq. 3.3 knows only that it is somewhere in
    the beam, eq. 3.6 takes the middle of what carving left):

    * with ``place_located`` and ``posterior`` (the default), once evidence has cut the beam,
      at the median of a posterior over the run's bins: bin ``k`` weighs ``exp(-F_k)``, the
      probability that every newer reading that looked there missed a surface there
      (``F_k = Σ -log(1 - P_detect)``, its free evidence: the misses' likelihood), times its
      localised support ``L_k`` (echo circles crossing the arc there, each by its
      ``P_detect`` and the sine of the angle between the circles) when the run has any. The
      weight is taken as uniform inside a bin, so the median is interpolated and equal
      weights give the run's middle (eq. 3.6). A beam nothing has cut keeps its middle
      unless ``posterior_uncut``: there the misses say nothing, the localised support alone
      would place the point, and crossings on a whole beam may be ghosts (two jambs' echo
      circles meet in the doorway between them). Measured (issue 9): on the simulator's
      truth placing uncut beams by the posterior too is more accurate (t-junction median
      0.52 / 0.56 of the centreline's instead of 0.66 / 0.56, doorway p90 0.36 / 0.21 instead
      of 0.47 / 0.29, specular / amplitude physics), but the Fig. 2/9 openings lose doorway
      approaches (specular: 93.5 / 85.2 / 82.7 % passable at 1 / 2 / 3 m -> 92.0 / 83.0 /
      79.3 %): the ghosts are real. So it is an option, off;
    * with ``place_located`` alone (the rule before it), once evidence has cut the beam, the
      bin at the median of the run's localised support (the middle where it has none); an
      uncut beam keeps its middle;
    * without ``place_located``, the run's middle (eq. 3.6).

    The ATM median of the crossings inside the run replaces that point where the run holds at
    least ``min_crossings`` of them (the median of one or two crossings is those crossings:
    one ghost moves it anywhere; from three, one cannot move it outside the others) and its
    bound (eq. 5.4 times δ, ``atm_bound``, for a single run; else the hull's, below) is smaller
    than the point's (section 4: the estimate with the smaller bound). The bound covers every
    surviving run (the echo may be in any of them), widened by half a bin on each side:
    ``2 r sin(e/2)`` with ``e`` the largest angle from the point to the far end of the surviving
    hull plus ``Δ/2`` (eq. 5.3).

    Returns
    -------
    has_piece : bool
        At least one bin survives.
    bearing : float
        Bearing of the point, radians (unwrapped near the axis).
    width : float
        Width of the kept run, radians.
    max_error : float
        Bound, metres.
    piece_support : float
        Largest support of a bin in the kept run.
    is_atm : bool
        The point is an ATM median.
    piece_crossings : float
        ATM crossings inside the kept run.
    piece_free : float
        Mean free evidence over the kept run, in units of ``T``.
    runs : float
        Number of surviving runs.
    hull_share : float
        Surviving hull width over the full beam.
    """
    n = slots.shape[0]
    bins = free.shape[1]
    has_piece = np.zeros(n, dtype=np.bool_)
    bearing = np.zeros(n)
    width = np.zeros(n)
    max_error = np.zeros(n)
    piece_support = np.zeros(n)
    is_atm = np.zeros(n, dtype=np.bool_)
    piece_crossings = np.zeros(n)
    piece_free = np.zeros(n)
    run_count = np.zeros(n)
    hull_share = np.zeros(n)
    in_bin = np.zeros(bins)
    values = np.zeros(bearings.shape[1])
    crossing_bin = np.zeros(bearings.shape[1], dtype=np.int64)
    weights = np.zeros(bins)
    for q in range(n):
        s = slots[q]
        phi = beam_width[s]
        half = 0.5 * phi
        step = phi / bins
        lo_axis = theta[s] - half
        c = counts[s] if with_atm else 0
        start = end = first = last = runs = 0
        if status[s] == EVIDENCE_ALIVE:
            _crossings_per_bin(in_bin, crossing_bin, bearings, s, c, half, step)
            start, end, first, last, runs = _kept_run(free, located, in_bin, s, threshold)
        if runs == 0:  # nothing survives: the whole beam's middle (eq. 3.3)
            bearing[q] = theta[s]
            width[q] = phi
            max_error[q] = _whole_beam_bound(r[s], phi)
            continue
        has_piece[q] = True
        lo = lo_axis + start * step
        hi = lo_axis + end * step
        hull_lo = lo_axis + first * step
        hull_hi = lo_axis + last * step
        mid = 0.5 * (lo + hi)  # eq. 3.6
        cut = end - start < bins
        if place_located and posterior and (cut or posterior_uncut):
            mid = _posterior_median(located, free, weights, s, start, end, lo_axis, step, mid)
        elif place_located and cut:
            mid = _located_median(located, s, start, end, lo_axis, step, mid)
        width[q] = hi - lo
        piece_support[q], piece_free[q] = _run_evidence(support, free, s, start, end, threshold)
        run_count[q] = runs
        hull_share[q] = (hull_hi - hull_lo) / phi
        carved_bound = _hull_bound(r[s], mid, hull_lo, hull_hi, step)
        bearing[q] = mid
        max_error[q] = carved_bound
        kept, median_rel = _run_crossings(values, crossing_bin, bearings, s, c, start, end)
        piece_crossings[q] = kept
        if kept > 0 and kept >= min_crossings:
            median = theta[s] + median_rel
            bound = (atm_bound if runs == 1
                     else _hull_bound(r[s], median, hull_lo, hull_hi, step))
            if bound < carved_bound:
                bearing[q] = median
                max_error[q] = bound
                is_atm[q] = True
    return (has_piece, bearing, width, max_error, piece_support, is_atm, piece_crossings,
            piece_free, run_count, hull_share)
