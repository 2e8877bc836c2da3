"""Exact arc carving (sonarcarve.geometry, paper eq. 3.1-3.5) against slow references.

The references never use the code under test:

* a *sampled* carving: each arc as 2,001 points tested one by one against the sector's own
  definition (eq. 3.2: distance < R and bearing within the beam, via atan2);
* a *shapely* carving: the sector as a 4,000-vertex polygon, the arc as a 4,000-vertex line.

Tolerances. A sample whose point lies farther than ``CLEAR`` (1e-9 m) from the sector's boundary
has an unambiguous membership, and the exact remainder must classify it the same way: no
tolerance in angle at all. (A boundary bearing the exact code gets wrong by δ would put samples
within ``r δ sin(crossing angle)`` of the boundary; near a tangency acos/asin lose up to ~1e-8 rad
but the crossing angle shrinks in proportion, so such samples are within ~1e-15 m of the boundary
and are skipped, never misjudged.) The outcome (unchanged / shrunk / fully carved / split) and the
carved interval are compared only when every sample is clear and every exact piece, carved or
remaining, is longer than two sampling steps, so that every piece holds a sample; then the
sampled interval must match the exact one to within one step. Cases that fail that condition are
measure-zero ties (a boundary through an end, a tangency) and get the pointwise check only; a
separate test makes sure that such skipping stays rare on generic cases.

Specular-aware carving (``max_incidence = β < π/2``) is checked against the same sampled
reference with one more per-sample test: the incidence ``γ``, the angle ``o_i``-``p``-``o_j``
computed with atan2 and folded into ``[0, π/2]``, must be at most ``β``. Its boundary, the two
circles of radius ``D / (2 sin β)`` through ``o_i`` and ``o_j`` (inscribed angle theorem, a
construction the code under test does not use), joins the sector's boundary in the ``CLEAR``
test, with the same reasoning: near a tangency of circle ``i`` with those circles the code's
acos/sqrt lose accuracy but the crossing angle shrinks in proportion.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from sonarcarve.geometry import (
    MIN_PIECE,
    NO_INCIDENCE_LIMIT,
    ArcFate,
    arc_bounding_circle,
    arc_remainder,
    carve_arc,
    carve_arcs,
)
from sonarcarve.geometry.bounds import arc_clear_of_disk, arc_clear_of_wedge
from sonarcarve.geometry.sector import make_sector

SAMPLES = 2001
CLEAR = 1e-9  # metres: samples nearer the sector's boundary are ties
TWO_PI = 2.0 * math.pi
OFF = NO_INCIDENCE_LIMIT  # β = π/2: the paper

Case = tuple[float, float, float, float, float, float, float, float, float, float, float]


# -- the sampled reference ---------------------------------------------------------------------


def _in_sector(px, py, fx, fy, radius, f_lo, f_hi):
    """Eq. 3.2 taken literally: distance < R, bearing within [f_lo, f_hi] (mod 2π)."""
    vx, vy = px - fx, py - fy
    offset = np.mod(np.arctan2(vy, vx) - f_lo, TWO_PI)
    return (np.hypot(vx, vy) < radius) & (offset <= f_hi - f_lo)


def _segment_distance(px, py, ax, ay, bx, by):
    ex, ey = bx - ax, by - ay
    length2 = max(ex * ex + ey * ey, 1e-300)
    u = np.clip(((px - ax) * ex + (py - ay) * ey) / length2, 0.0, 1.0)
    return np.hypot(px - ax - u * ex, py - ay - u * ey)


def _boundary_distance(px, py, fx, fy, radius, f_lo, f_hi):
    """Distance from each point to the sector's boundary (two edges and the far arc)."""
    if radius <= 0.0:
        return np.full(np.shape(px), np.inf)
    vx, vy = px - fx, py - fy
    in_wedge = np.mod(np.arctan2(vy, vx) - f_lo, TWO_PI) <= f_hi - f_lo
    far_arc = np.where(in_wedge, np.abs(np.hypot(vx, vy) - radius), np.inf)
    edges = [
        _segment_distance(px, py, fx, fy, fx + radius * math.cos(a), fy + radius * math.sin(a))
        for a in (f_lo, f_hi)
    ]
    return np.minimum(far_arc, np.minimum(*edges))


def _incidence(px, py, ox, oy, fx, fy):
    """The angle o-p-f at each p, folded into [0, π/2] (a wall reflects from both faces)."""
    wx, wy, vx, vy = px - ox, py - oy, px - fx, py - fy
    gamma = np.arctan2(np.abs(wx * vy - wy * vx), wx * vx + wy * vy)  # in [0, π]
    return np.minimum(gamma, math.pi - gamma)


def _locus_distance(px, py, ox, oy, fx, fy, beta):
    """Distance from each p to the locus γ = β: two circles through o and f of radius
    D / (2 sin β), centred on the perpendicular bisector (the line o f itself when β = 0)."""
    dx, dy = fx - ox, fy - oy
    dist = math.hypot(dx, dy)
    if beta >= OFF or dist == 0.0:
        return np.full(np.shape(px), np.inf)
    nx, ny = -dy / dist, dx / dist
    if beta == 0.0:
        return np.abs((px - ox) * nx + (py - oy) * ny)
    radius = dist / (2.0 * math.sin(beta))
    offset = 0.5 * dist / math.tan(beta)
    mx, my = 0.5 * (ox + fx), 0.5 * (oy + fy)
    return np.minimum(*(np.abs(np.hypot(px - mx - k * offset * nx, py - my - k * offset * ny)
                               - radius) for k in (1.0, -1.0)))


class Sampled:
    """The arc as SAMPLES bearings, each classified against the sector directly.

    With ``beta < π/2`` a sample is carved only if it is in the sector and its incidence seen
    from the sector's apex is at most ``beta`` (``Z_ij^β``).
    """

    def __init__(self, case: Case, beta: float = OFF) -> None:
        ox, oy, r, lo, hi, fx, fy, fr, f_lo, f_hi, eps = case
        self.tau = np.linspace(lo, hi, SAMPLES)
        self.step = (hi - lo) / (SAMPLES - 1)
        px, py = ox + r * np.cos(self.tau), oy + r * np.sin(self.tau)
        carved = _in_sector(px, py, fx, fy, fr - eps, f_lo, f_hi)
        boundary = _boundary_distance(px, py, fx, fy, fr - eps, f_lo, f_hi)
        if beta < OFF:
            carved &= _incidence(px, py, ox, oy, fx, fy) <= beta
            boundary = np.minimum(boundary, _locus_distance(px, py, ox, oy, fx, fy, beta))
        self.remaining = ~carved
        self.clear = boundary > CLEAR

    def runs(self) -> list[tuple[float, float]]:
        """First and last bearing of each run of remaining samples."""
        edges = np.diff(np.concatenate(([0], self.remaining.astype(np.int8), [0])))
        starts = np.flatnonzero(edges == 1)
        stops = np.flatnonzero(edges == -1) - 1
        return [(self.tau[a], self.tau[b]) for a, b in zip(starts, stops, strict=True)]


def _pieces(case: Case, beta: float = OFF) -> np.ndarray:
    return arc_remainder(*case, beta)


def _all_pieces(case: Case, pieces: np.ndarray) -> list[float]:
    """Lengths of every exact piece of the arc: the remaining ones and the carved gaps."""
    lo, hi = case[3], case[4]
    bounds = [lo, *pieces.reshape(-1).tolist(), hi]
    return [b - a for a, b in zip(bounds[::2], bounds[1::2], strict=True) if b - a > 0] + [
        float(b - a) for a, b in pieces
    ]


def _unambiguous(case: Case, sampled: Sampled, pieces: np.ndarray) -> bool:
    return bool(sampled.clear.all()) and all(
        length > 2.0 * sampled.step for length in _all_pieces(case, pieces)
    )


def _exact_remaining(tau: np.ndarray, pieces: np.ndarray) -> np.ndarray:
    inside = np.zeros(tau.shape, dtype=bool)
    for a, b in pieces:
        inside |= (tau >= a) & (tau <= b)
    return inside


# -- cases ---------------------------------------------------------------------------------------


def _generic(rng: np.random.Generator) -> Case:
    """A random arc and a random sector aimed roughly at it, angles in random 2π turns."""
    ox, oy = rng.uniform(-1.0, 1.0, 2)
    r = rng.uniform(0.2, 4.0)
    lo = rng.uniform(-3.5, 3.5)
    hi = lo + rng.uniform(0.05, 1.2)
    mid = 0.5 * (lo + hi)
    bearing, reach = rng.uniform(-math.pi, math.pi), rng.uniform(0.0, 5.0)
    fx, fy = ox + reach * math.cos(bearing), oy + reach * math.sin(bearing)
    aim = math.atan2(oy + r * math.sin(mid) - fy, ox + r * math.cos(mid) - fx)
    width = rng.uniform(0.02, 3.0)
    f_lo = aim + rng.uniform(-1.0, 1.0) - 0.5 * width + TWO_PI * rng.integers(-2, 3)
    return (ox, oy, r, lo, hi, fx, fy, rng.uniform(0.1, 7.0), f_lo, f_lo + width,
            rng.choice([0.0, rng.uniform(0.0, 0.3)]))


DEGENERATE = (
    "generic", "same_origin", "same_origin_same_range", "tangent_inside", "tangent_outside",
    "edge_through_end", "apex_on_arc", "zero_length", "end_on_range", "equal_beams",
)


@st.composite
def cases(draw: st.DrawFn) -> Case:
    """Generic cases and near-degenerate constructions (exact ties in the real numbers)."""
    seed = draw(st.integers(0, 2**32 - 1))
    kind = draw(st.sampled_from(DEGENERATE))
    ox, oy, r, lo, hi, fx, fy, fr, f_lo, f_hi, eps = _generic(np.random.default_rng(seed))
    dist = math.hypot(fx - ox, fy - oy)
    if kind == "same_origin":
        fx, fy = ox, oy
    elif kind == "same_origin_same_range":
        fx, fy, fr, eps = ox, oy, r, 0.0
    elif kind == "tangent_inside":  # the disk holds the circle, touching it
        fr = dist + r + eps
    elif kind == "tangent_outside":  # the disk touches the circle from outside or inside
        fr = abs(dist - r) + eps
    elif kind == "edge_through_end":
        end, width = draw(st.sampled_from([lo, hi])), f_hi - f_lo
        f_lo = math.atan2(oy + r * math.sin(end) - fy, ox + r * math.cos(end) - fx)
        f_hi = f_lo + width
    elif kind == "apex_on_arc":
        u = draw(st.floats(0.0, 1.0))
        fx, fy = ox + r * math.cos(lo + u * (hi - lo)), oy + r * math.sin(lo + u * (hi - lo))
    elif kind == "zero_length":
        hi = lo
    elif kind == "end_on_range":
        end = draw(st.sampled_from([lo, hi]))
        fr = math.hypot(ox + r * math.cos(end) - fx, oy + r * math.sin(end) - fy) + eps
    elif kind == "equal_beams":
        fx, fy, f_lo, f_hi = ox, oy, lo, lo + max(hi - lo, 0.01)
    return (ox, oy, r, lo, hi, fx, fy, fr, f_lo, f_hi, eps)


@st.composite
def specular_cases(draw: st.DrawFn) -> tuple[Case, float]:
    """A case of :func:`cases` and a critical angle β, with the incidence's own ties: β whose
    locus circles touch circle ``i`` (``D = r sin β``), and β = 0 and π/2."""
    case = draw(cases())
    ox, oy, r, fx, fy = case[0], case[1], case[2], case[5], case[6]
    dist = math.hypot(fx - ox, fy - oy)
    kind = draw(st.sampled_from(["any", "any", "any", "special", "tangent"]))
    if kind == "tangent" and 0.0 < dist < r:
        return case, math.asin(dist / r)
    if kind == "special":
        return case, draw(st.sampled_from([0.0, math.radians(17.5), OFF - 1e-6, OFF]))
    return case, draw(st.floats(0.01, OFF - 0.01))


# -- exact versus sampled ------------------------------------------------------------------------


def _check_against_samples(case: Case, beta: float = OFF) -> bool:
    """Assert the exact carving against the sampled one; return whether it was unambiguous."""
    sampled = Sampled(case, beta)
    pieces = _pieces(case, beta)
    # Pointwise: every clear sample is classified alike, with no angular tolerance.
    exact = _exact_remaining(sampled.tau, pieces)
    assert np.array_equal(exact[sampled.clear], sampled.remaining[sampled.clear])
    if not _unambiguous(case, sampled, pieces):
        return False
    status, new_lo, new_hi = carve_arc(*case, beta)
    runs = sampled.runs()
    if not runs:
        assert status == ArcFate.FULLY_CARVED
    elif len(runs) >= 2:
        assert status == ArcFate.SPLIT
    else:
        first, last = runs[0]
        expected = (ArcFate.UNCHANGED if sampled.remaining.all() else ArcFate.SHRUNK)
        assert status == expected
        assert abs(new_lo - first) <= sampled.step
        assert abs(new_hi - last) <= sampled.step
    return True


@settings(max_examples=300, deadline=None, derandomize=True)
@given(case=cases())
def test_exact_carving_agrees_with_the_sampled_reference(case: Case) -> None:
    _check_against_samples(case)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(spec=specular_cases())
def test_specular_carving_agrees_with_the_sampled_reference(spec: tuple[Case, float]) -> None:
    _check_against_samples(*spec)


def test_generic_cases_are_rarely_ties_and_cover_every_outcome() -> None:
    rng = np.random.default_rng(7)
    outcomes: set[int] = set()
    checked = 0
    for _ in range(400):
        case = _generic(rng)
        if _check_against_samples(case):
            checked += 1
            outcomes.add(carve_arc(*case)[0])
    assert checked >= 0.9 * 400  # the outcome check is not skipped away
    assert outcomes == set(ArcFate)


def test_specular_generic_cases_are_rarely_ties_and_the_angle_matters() -> None:
    rng = np.random.default_rng(11)
    outcomes: set[int] = set()
    checked = differs = 0
    for _ in range(400):
        case, beta = _generic(rng), rng.uniform(0.05, OFF - 0.05)
        if _check_against_samples(case, beta):
            checked += 1
            outcomes.add(carve_arc(*case, beta)[0])
        paper, specular = _pieces(case), _pieces(case, beta)
        differs += paper.shape != specular.shape or not np.array_equal(paper, specular)
    assert checked >= 0.9 * 400
    assert outcomes == set(ArcFate)
    assert differs >= 0.1 * 400  # the incidence condition does change the answer


@settings(max_examples=200, deadline=None, derandomize=True)
@given(case=cases())
def test_right_angle_limit_is_the_paper_exactly(case: Case) -> None:
    # β = π/2 admits every incidence: the result is bitwise the paper's, in every kernel.
    assert np.array_equal(_pieces(case, OFF), _pieces(case))
    assert carve_arc(*case, OFF) == carve_arc(*case)
    assert carve_arc(*case, 2.0) == carve_arc(*case)  # anything above π/2 is "off" too


@settings(max_examples=200, deadline=None, derandomize=True)
@given(spec=specular_cases())
def test_specular_carves_a_subset_of_the_paper(spec: tuple[Case, float]) -> None:
    # Z_ij^β ⊂ Z_ij, so the paper's remainder lies inside the specular one: every sample the
    # paper keeps, the specular mode keeps too (ties on the boundaries aside).
    case, beta = spec
    sampled = Sampled(case, beta)
    paper = _exact_remaining(sampled.tau, _pieces(case))
    specular = _exact_remaining(sampled.tau, _pieces(case, beta))
    assert not np.any(paper & ~specular & sampled.clear)


# -- consistency of the exact API ----------------------------------------------------------------


@settings(max_examples=300, deadline=None, derandomize=True)
@given(case=cases())
def test_outcome_interval_and_pieces_agree(case: Case) -> None:
    lo, hi = case[3], case[4]
    status, new_lo, new_hi = carve_arc(*case)
    pieces = _pieces(case)
    assert pieces.shape[1] == 2
    assert np.all(pieces[:, 0] >= lo)
    assert np.all(pieces[:, 1] <= hi)
    assert np.all(np.diff(pieces.reshape(-1)) >= 0.0)  # sorted, disjoint
    if hi - lo >= MIN_PIECE:
        assert np.all(pieces[:, 1] - pieces[:, 0] >= MIN_PIECE)
    if len(pieces) == 0:
        assert status == ArcFate.FULLY_CARVED
    elif len(pieces) >= 2:
        assert status == ArcFate.SPLIT
    elif (pieces[0, 0], pieces[0, 1]) == (lo, hi):
        assert (status, new_lo, new_hi) == (ArcFate.UNCHANGED, lo, hi)
    else:
        assert status == ArcFate.SHRUNK
        assert (new_lo, new_hi) == (pieces[0, 0], pieces[0, 1])
    if status != ArcFate.SHRUNK:
        assert (new_lo, new_hi) == (lo, hi)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(case=cases(), turns=st.integers(-3, 3))
def test_carving_does_not_depend_on_the_unwrapping(case: Case, turns: int) -> None:
    ox, oy, r, lo, hi, fx, fy, fr, f_lo, f_hi, eps = case
    shift = TWO_PI * turns
    moved = carve_arc(ox, oy, r, lo + shift, hi + shift, fx, fy, fr, f_lo, f_hi, eps)
    status, new_lo, new_hi = carve_arc(*case)
    assert moved[0] == status
    assert moved[1] == pytest.approx(new_lo + shift, abs=1e-9)
    assert moved[2] == pytest.approx(new_hi + shift, abs=1e-9)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(spec=specular_cases())
def test_batch_kernel_matches_the_scalar_one(spec: tuple[Case, float]) -> None:
    case, beta = spec
    _check_batch_against_scalar(case, beta)


def test_batch_kernel_shortcuts_match_the_scalar_one_in_specular_mode() -> None:
    # Small arcs well inside long sectors, from near and far origins: the cases where the
    # batch kernel's bounding-circle shortcut decides "fully carved" without the exact path.
    rng = np.random.default_rng(5)
    for _ in range(3000):
        fx, fy, aim = *rng.uniform(-1.0, 1.0, 2), rng.uniform(-math.pi, math.pi)
        reach = rng.uniform(0.5, 4.0)
        px, py = fx + reach * math.cos(aim), fy + reach * math.sin(aim)  # a point on arc i
        back, r = rng.uniform(-math.pi, math.pi), rng.uniform(0.2, 3.0)
        ox, oy = px - r * math.cos(back), py - r * math.sin(back)
        half = rng.uniform(0.0, 0.3)
        width = rng.uniform(0.3, 1.0)
        case = (ox, oy, r, back - half, back + half, fx, fy, reach + rng.uniform(0.0, 2.0),
                aim - width / 2, aim + width / 2, 0.0)
        _check_batch_against_scalar(case, rng.choice([OFF, rng.uniform(0.0, OFF)]))


def _check_batch_against_scalar(case: Case, beta: float) -> None:
    ox, oy, r, lo, hi, fx, fy, fr, f_lo, f_hi, eps = case
    n = 3  # the arc sits in row 1 of 3; rows 0 and 2 must stay untouched
    x, y, rr = np.full(n, ox), np.full(n, oy), np.full(n, r)
    lo_a, hi_a = np.full(n, lo), np.full(n, hi)
    bounds = np.array([arc_bounding_circle(ox, oy, r, lo, hi)] * n)
    status = np.zeros(n, dtype=np.int8)
    carved = np.zeros(n, dtype=bool)
    fully, split = carve_arcs(np.array([1]), x, y, rr, lo_a, hi_a, bounds, status, carved,
                              fx, fy, fr, f_lo, f_hi, eps, beta)
    expected, new_lo, new_hi = carve_arc(*case, beta)
    assert (fully, split) == (int(expected == ArcFate.FULLY_CARVED),
                              int(expected == ArcFate.SPLIT))
    assert carved[1] == (expected != ArcFate.UNCHANGED)
    if expected == ArcFate.SHRUNK:
        assert (lo_a[1], hi_a[1]) == (new_lo, new_hi)
        assert np.allclose(bounds[1], arc_bounding_circle(ox, oy, r, new_lo, new_hi))
    else:
        assert (lo_a[1], hi_a[1]) == (lo, hi)
    alive = expected in (ArcFate.UNCHANGED, ArcFate.SHRUNK)
    assert status[1] == (ArcFate.ALIVE if alive else expected)
    assert lo_a[[0, 2]].tolist() == [lo, lo]
    assert not carved[[0, 2]].any()
    assert status[[0, 2]].tolist() == [0, 0]


@settings(max_examples=200, deadline=None, derandomize=True)
@given(ox=st.floats(-5, 5), oy=st.floats(-5, 5), r=st.floats(0.01, 10), lo=st.floats(-10, 10),
       width=st.floats(0.0, 6.2))
def test_bounding_circle_contains_the_arc(ox: float, oy: float, r: float, lo: float,
                                          width: float) -> None:
    cx, cy, radius = arc_bounding_circle(ox, oy, r, lo, lo + width)
    tau = np.linspace(lo, lo + width, 1001)
    assert np.all(np.hypot(ox + r * np.cos(tau) - cx, oy + r * np.sin(tau) - cy) <= radius)


# -- hand-made cases: expectations from elementary geometry ---------------------------------------

PHI = math.radians(22.5)


def test_same_place_longer_range_fully_carves() -> None:
    assert carve_arc(0.0, 0.0, 1.0, -PHI / 2, PHI / 2, 0.0, 0.0, 1.5, -PHI / 2, PHI / 2)[0] == (
        ArcFate.FULLY_CARVED)


def test_same_place_same_range_survives_the_open_disk() -> None:
    status, lo, hi = carve_arc(1.0, 2.0, 3.0, 0.1, 0.5, 1.0, 2.0, 3.0, 0.1, 0.5)
    assert (status, lo, hi) == (ArcFate.UNCHANGED, 0.1, 0.5)


def test_range_tolerance_shortens_the_freespace() -> None:
    args = (0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 1.04, -0.2, 0.2)
    assert carve_arc(*args, 0.0)[0] == ArcFate.FULLY_CARVED
    assert carve_arc(*args, 0.05)[0] == ArcFate.UNCHANGED


def test_overlapping_beam_from_the_same_place_keeps_the_rest() -> None:
    # The beam [0.05, 0.5] covers the arc [-0.2, 0.2] from 0.05 on: [-0.2, 0.05] remains.
    status, lo, hi = carve_arc(0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 2.0, 0.05, 0.5)
    assert status == ArcFate.SHRUNK
    assert (lo, hi) == (-0.2, pytest.approx(0.05, abs=1e-12))


def test_disk_from_elsewhere_cuts_where_the_circles_cross() -> None:
    # Arc: the unit circle about the origin. Freespace: radius 0.7 about (1.5, 0), beam pointing
    # back along -x. |e(τ) - (1.5, 0)|² = 3.25 - 3 cos τ < 0.49 where |τ| < acos(0.92); those
    # points lie at bearings π ± 0.6 from (1.5, 0), inside the beam.
    cut = math.acos(0.92)
    full = (math.pi - 1.5, math.pi + 1.5)
    pieces = arc_remainder(0.0, 0.0, 1.0, -0.5, 0.5, 1.5, 0.0, 0.7, *full)
    assert pieces == pytest.approx(np.array([[-0.5, -cut], [cut, 0.5]]), abs=1e-12)
    assert carve_arc(0.0, 0.0, 1.0, -0.5, 0.5, 1.5, 0.0, 0.7, *full)[0] == ArcFate.SPLIT
    # An arc starting at τ = 0 loses only [0, cut).
    status, lo, hi = carve_arc(0.0, 0.0, 1.0, 0.0, 0.5, 1.5, 0.0, 0.7, *full)
    assert (status, lo, hi) == (ArcFate.SHRUNK, pytest.approx(cut, abs=1e-12), 0.5)
    # Half the beam, bounded by the ray along -x through (1, 0) = e(0): only (-cut, 0) goes.
    pieces = arc_remainder(0.0, 0.0, 1.0, -0.5, 0.5, 1.5, 0.0, 0.7, math.pi, math.pi + 1.5)
    assert pieces == pytest.approx(np.array([[-0.5, -cut], [0.0, 0.5]]), abs=1e-12)


def test_tangent_disks_carve_nothing() -> None:
    # Circle r=1 about the origin; disks about (3, 0) of radius 2 (outside) and about (0.5, 0)
    # of radius 0.5 (inside) touch it at one point.
    beam = (math.pi - 0.3, math.pi + 0.3)
    assert carve_arc(0.0, 0.0, 1.0, -0.3, 0.3, 3.0, 0.0, 2.0, *beam)[0] == ArcFate.UNCHANGED
    assert carve_arc(0.0, 0.0, 1.0, -0.3, 0.3, 0.5, 0.0, 0.5, -0.3, 0.3)[0] == (
        ArcFate.UNCHANGED)


def test_zero_length_arc_is_a_point() -> None:
    assert carve_arc(0.0, 0.0, 1.0, 0.1, 0.1, 0.0, 0.0, 2.0, 0.0, 0.3)[0] == (
        ArcFate.FULLY_CARVED)
    assert carve_arc(0.0, 0.0, 1.0, 0.4, 0.4, 0.0, 0.0, 2.0, 0.0, 0.3)[0] == (
        ArcFate.UNCHANGED)


def test_no_freespace_within_the_tolerance() -> None:
    assert carve_arc(0.0, 0.0, 0.5, -0.2, 0.2, 0.0, 0.0, 0.04, -0.2, 0.2, 0.05)[0] == (
        ArcFate.UNCHANGED)


# -- specular-aware carving: hand-made cases ------------------------------------------------------

# A wall along x = 1 heard head-on from the origin (arc i: r = 1, bearings ±0.1), then passed
# by reading j at (0, 0.9) whose beam [-0.9, -0.5] meets that wall 40° off its normal: on a
# specular wall j hears nothing, and reports a far echo at 3 m.
WALL = (0.0, 0.0, 1.0, -0.1, 0.1, 0.0, 0.9, 3.0, -0.9, -0.5, 0.0)


def _wall_incidence(tau: float) -> float:
    """Incidence at e(τ) seen from (0, 0.9), by elementary trigonometry: the angle between the
    radius (bearing τ) and the line of sight from (0, 0.9)."""
    sight = math.atan2(math.sin(tau) - 0.9, math.cos(tau))
    return abs(tau - sight)


def test_glancing_reading_does_not_carve_a_head_on_wall() -> None:
    incidences = [_wall_incidence(t) for t in np.linspace(-0.1, 0.1, 101)]
    assert math.radians(39) < min(incidences) < max(incidences) < math.radians(45)
    assert carve_arc(*WALL)[0] == ArcFate.FULLY_CARVED  # the paper loses the wall
    for beta_deg in (17.5, 20.0, 30.0, 39.0):
        assert carve_arc(*WALL, math.radians(beta_deg)) == (ArcFate.UNCHANGED, -0.1, 0.1)
    assert carve_arc(*WALL, math.radians(46.0))[0] == ArcFate.FULLY_CARVED


def test_critical_angle_inside_the_arc_cuts_where_the_incidence_equals_it() -> None:
    beta = math.radians(42.0)
    # The incidence grows with τ here; bisection for the τ where it equals β.
    a, b = -0.1, 0.1
    for _ in range(200):
        m = 0.5 * (a + b)
        a, b = (m, b) if _wall_incidence(m) < beta else (a, m)
    status, lo, hi = carve_arc(*WALL, beta)
    # Below that τ the incidence is under β and j's free space carves; above, it keeps.
    assert (status, lo, hi) == (ArcFate.SHRUNK, pytest.approx(a, abs=1e-12), 0.1)
    # The cut lies on the inscribed-angle circle through o_i and o_j: radius D / (2 sin β),
    # centre on the bisector y = 0.45 at x = ±(D/2) / tan β.
    px, py = math.cos(lo), math.sin(lo)
    radius, offset = 0.9 / (2 * math.sin(beta)), 0.45 / math.tan(beta)
    assert min(abs(math.hypot(px - k * offset, py - 0.45) - radius)
               for k in (1, -1)) == pytest.approx(0.0, abs=1e-12)


def test_readings_from_the_same_place_carve_at_any_critical_angle() -> None:
    # From the same origin every incidence is 0 (the line of sight is the normal).
    args = (0.0, 0.0, 1.0, -0.2, 0.2, 0.0, 0.0, 1.5, -0.3, 0.3, 0.0)
    for beta in (0.0, 0.1, OFF):
        assert carve_arc(*args, beta)[0] == ArcFate.FULLY_CARVED


def test_specular_zero_length_arc_is_a_point() -> None:
    # The point e(0) of the wall above, in j's free space at 42° incidence.
    point = (0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.9, 3.0, -0.9, -0.5, 0.0)
    assert _wall_incidence(0.0) == pytest.approx(math.atan(0.9))
    assert carve_arc(*point, math.radians(45.0))[0] == ArcFate.FULLY_CARVED
    assert carve_arc(*point, math.radians(40.0))[0] == ArcFate.UNCHANGED


def test_a_tilted_view_can_split_the_arc_in_specular_mode() -> None:
    # Reading j at (2, 0) looking back along -x at the unit circle: the incidence is 0 at
    # τ = 0 (in line with both origins) and grows away from it, so a small β keeps only
    # the middle of the carved set. Incidence at e(τ) seen from (2, 0): the angle between
    # e(τ) and e(τ) - (2, 0).
    beam = (math.pi - 1.0, math.pi + 1.0)
    args = (0.0, 0.0, 1.0, -0.5, 0.5, 2.0, 0.0, 1.1, *beam, 0.0)
    # The paper carves |e(τ) - (2, 0)|² = 5 - 4 cos τ < 1.21: |τ| < acos(0.9475).
    cut = math.acos(0.9475)
    assert arc_remainder(*args) == pytest.approx(np.array([[-0.5, -cut], [cut, 0.5]]), abs=1e-12)
    beta = math.radians(20.0)
    pieces = arc_remainder(*args, beta)
    # Carved: |τ| < τ* < cut, where the incidence (sin γ = 2 sin τ / |e(τ) - (2, 0)|, law of
    # sines) equals β.
    t_star = _bisect(lambda t: math.asin(2 * math.sin(t) / math.hypot(math.cos(t) - 2,
                                                                       math.sin(t))) - beta,
                     0.0, 0.5)
    assert t_star < cut
    assert pieces == pytest.approx(np.array([[-0.5, -t_star], [t_star, 0.5]]), abs=1e-12)


def _bisect(f, a: float, b: float) -> float:
    for _ in range(200):
        m = 0.5 * (a + b)
        a, b = (m, b) if f(m) < 0.0 else (a, m)
    return 0.5 * (a + b)


# -- shapely cross-check -------------------------------------------------------------------------

VERTICES = 4000


def _shapely_carved(case: Case) -> shapely.Geometry:
    ox, oy, r, lo, hi, fx, fy, fr, f_lo, f_hi, eps = case
    phi = np.linspace(f_lo, f_hi, VERTICES)
    radius = fr - eps
    ring = np.column_stack((fx + radius * np.cos(phi), fy + radius * np.sin(phi)))
    sector = shapely.Polygon(np.vstack(([fx, fy], ring)))
    tau = np.linspace(lo, hi, VERTICES)
    arc = shapely.LineString(np.column_stack((ox + r * np.cos(tau), oy + r * np.sin(tau))))
    return arc.intersection(sector)


@settings(max_examples=120, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**32 - 1))
def test_carved_set_matches_shapely(seed: int) -> None:
    case = _generic(np.random.default_rng(seed))
    r, lo, hi, radius = case[2], case[3], case[4], case[7] - case[10]
    if radius <= 0.0:
        return
    pieces = _pieces(case)
    carved_length = r * ((hi - lo) - float(np.sum(pieces[:, 1] - pieces[:, 0])))
    z = _shapely_carved(case)
    # Polygon chords sit ≤ R Δφ²/8 ≈ 4e-7 m inside the true circle; at a grazing crossing that
    # moves the intersection by up to ~sqrt(2 · 4e-7 · R) ≈ 1e-3 m.
    assert z.length == pytest.approx(carved_length, abs=2e-3)
    gaps = _all_pieces(case, pieces)
    if min(gaps, default=1.0) * r > 1e-2:  # every piece well resolved: count the carved parts
        parts = [g for g in getattr(z, "geoms", [z]) if g.length > 1e-6]
        carved_runs = len(gaps) - len(pieces)
        assert len(parts) == carved_runs


# -- the cheap rejection before the closed form (geometry/bounds.py) ----------------------------


def _random_arc_and_origin(rng: np.random.Generator, k: int) -> tuple[float, ...]:
    """Case ``k`` of the cheap-rejection tests: an arc (origin, radius, ``lo``, ``hi``) and a
    newer reading's origin; every tenth far from the origin (1e5 m), every 17th a point arc,
    every 13th with both origins at the same place."""
    ox, oy = rng.uniform(-3.0, 3.0, 2) * (1e5 if k % 10 == 0 else 1.0)
    r = rng.uniform(0.05, 5.0)
    lo = rng.uniform(-8.0, 8.0)
    hi = lo + (0.0 if k % 17 == 0 else rng.uniform(0.0, 3.1))
    fx, fy = np.array([ox, oy]) + rng.uniform(-6.0, 6.0, 2)
    if k % 13 == 0:
        fx, fy = ox, oy  # coincident origins
    return float(ox), float(oy), r, lo, hi, float(fx), float(fy)


def test_arc_clear_of_disk_only_for_arcs_carving_leaves_unchanged() -> None:
    """Whenever the test says "clear", every sample of the arc is outside the open disk and the
    closed form carves nothing; it says so for most arcs clearly outside. Half the cases put the
    disk's edge within 1e-15..1e-5 (relative) of the arc's nearest sample: near-tangencies."""
    rng = np.random.default_rng(11)
    clear_outside = said_clear = 0
    for k in range(4000):
        ox, oy, r, lo, hi, fx, fy = _random_arc_and_origin(rng, k)
        tau = np.linspace(lo, hi, SAMPLES)
        nearest = np.hypot(ox + r * np.cos(tau) - fx, oy + r * np.sin(tau) - fy).min()
        if k % 2:
            radius = nearest * (1.0 + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-15, -5))
        else:
            radius = rng.uniform(0.01, 8.0)
        f_lo = rng.uniform(-4.0, 4.0)
        sector = make_sector(fx, fy, radius, f_lo, f_lo + rng.uniform(0.0, 3.0), 0.0, OFF)
        clear = arc_clear_of_disk(ox, oy, r, math.cos(lo), math.sin(lo), math.cos(hi),
                                  math.sin(hi), sector)
        if clear:
            said_clear += 1
            assert nearest >= radius
            fate, _, _ = carve_arc(ox, oy, r, lo, hi, fx, fy, radius, sector.a1, sector.a2)
            assert fate == ArcFate.UNCHANGED
        if nearest > radius * (1.0 + 1e-3) + 1e-3 * (1.0 + abs(ox) + abs(oy)):
            clear_outside += 1
            assert clear, "an arc clearly outside the disk must be found clear"
    assert said_clear > 1000
    assert clear_outside > 500


def test_arc_clear_of_wedge_only_for_arcs_carving_leaves_unchanged() -> None:
    """Whenever the test says "clear", every sample of the arc is outside one of the sector's
    half-planes and the closed form carves nothing; it says so for most arcs clearly outside one.
    A third of the cases put an edge ray within 1e-15..1e-5 (relative) of the arc's nearest
    sample, by turning the sector about its origin: near-tangencies of the edge lines."""
    rng = np.random.default_rng(12)
    clear_outside = said_clear = 0
    for k in range(4000):
        ox, oy, r, lo, hi, fx, fy = _random_arc_and_origin(rng, k)
        tau = np.linspace(lo, hi, SAMPLES)
        px, py = ox + r * np.cos(tau) - fx, oy + r * np.sin(tau) - fy
        width = rng.uniform(0.0, 3.0)
        f_lo = rng.uniform(-4.0, 4.0)
        if k % 3 == 0:  # the lower edge ray through the arc's last sample on its right, nearly
            bearing = np.arctan2(py, px)
            f_lo = float(bearing.min()) + rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-15, -5)
        radius = rng.uniform(0.01, 12.0)
        sector = make_sector(fx, fy, radius, f_lo, f_lo + width, 0.0, OFF)
        beyond_lo = sector.u1x * py - sector.u1y * px  # < 0: right of the f_lo ray's line
        beyond_hi = px * sector.u2y - py * sector.u2x  # < 0: left of the f_hi ray's line
        clear = arc_clear_of_wedge(ox, oy, r, math.cos(lo), math.sin(lo), math.cos(hi),
                                   math.sin(hi), sector)
        if clear:
            said_clear += 1
            assert beyond_lo.max() < 0.0 or beyond_hi.max() < 0.0
            fate, _, _ = carve_arc(ox, oy, r, lo, hi, fx, fy, radius, sector.a1, sector.a2)
            assert fate == ArcFate.UNCHANGED
        # Samples miss the arc's extreme by up to r (Δτ)²/8 ≈ 3e-6 r.
        margin = 1e-3 * (1.0 + abs(ox) + abs(oy) + r)
        if beyond_lo.max() < -margin or beyond_hi.max() < -margin:
            clear_outside += 1
            assert clear, "an arc clearly outside a half-plane must be found clear"
    assert said_clear > 1000
    assert clear_outside > 500
