import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.geometry import circle_intersections
from sonarcarve.maps import PointSource
from sonarcarve.methods import METHODS, MethodConfig, make_method
from sonarcarve.methods import atm as atm_module
from sonarcarve.methods.atm import AtmMethod, AtmModel, CrossingStoreError, atm_error_bound
from sonarcarve.readings import Reading, ReadingBatch

PHI = math.radians(22.5)
INCH = 0.0254


def _bearing(a: np.ndarray, b: np.ndarray) -> float:
    d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
    return math.atan2(d[1], d[0])


def _reading_towards(k: int, origin: np.ndarray, target: np.ndarray, axis_offset: float = 0.0,
                     r: float | None = None) -> Reading:
    """A reading at ``origin`` whose beam axis is ``axis_offset`` off the bearing to ``target``."""
    rng = float(np.linalg.norm(np.asarray(target) - origin)) if r is None else r
    return Reading(t=float(k), sensor=k % 16, x=float(origin[0]), y=float(origin[1]),
                   theta=_bearing(origin, target) + axis_offset, range=rng, beam_width=PHI)


def _atm(method: AtmMethod) -> AtmModel:
    model = method.models[0]
    assert isinstance(model, AtmModel)
    return model


# --- circle-circle intersections against an independent root search -------------------------


def _sampled_intersections(o1: np.ndarray, r1: float, o2: np.ndarray, r2: float) -> list[float]:
    """Bearings (from o1) where circle 1 crosses circle 2: sign changes of |p - o2| - r2 on a
    fine grid, refined with Brent's method. Independent of the closed form."""

    def f(tau: float) -> float:
        p = o1 + r1 * np.array([math.cos(tau), math.sin(tau)])
        return float(np.linalg.norm(p - o2) - r2)

    grid = np.linspace(0.0, 2.0 * math.pi, 4097)
    values = np.array([f(t) for t in grid])
    roots = []
    for k in range(len(grid) - 1):
        if values[k] == 0.0:
            roots.append(float(grid[k]))
        elif values[k] * values[k + 1] < 0.0:
            roots.append(brentq(f, grid[k], grid[k + 1], xtol=1e-13))
    return roots


def _wrapped(a: np.ndarray | float) -> np.ndarray:
    return np.asarray((np.asarray(a) + math.pi) % (2.0 * math.pi) - math.pi)


coordinate = st.floats(-5.0, 5.0)
radius = st.floats(0.2, 6.0)


@settings(max_examples=60, deadline=None)
@given(x1=coordinate, y1=coordinate, r1=radius, x2=coordinate, y2=coordinate, r2=radius)
def test_closed_form_intersections_match_a_root_search(
    x1: float, y1: float, r1: float, x2: float, y2: float, r2: float
) -> None:
    o1, o2 = np.array([x1, y1]), np.array([x2, y2])
    d = float(np.linalg.norm(o2 - o1))
    # Near tangency the grid search cannot see the two crossings apart; stay clear of it.
    assume(abs(d - (r1 + r2)) > 0.05 and abs(d - abs(r1 - r2)) > 0.05 and d > 1e-3)
    hit = circle_intersections(o1, r1, o2, r2)
    roots = _sampled_intersections(o1, r1, o2, r2)
    if not hit.meets[0]:
        assert roots == []
        return
    assert len(roots) == 2
    for k in range(2):
        p1 = o1 + r1 * np.array([math.cos(hit.bearing1[0, k]), math.sin(hit.bearing1[0, k])])
        p2 = o2 + r2 * np.array([math.cos(hit.bearing2[0, k]), math.sin(hit.bearing2[0, k])])
        np.testing.assert_allclose(p1, p2, atol=1e-9)  # both bearings name the same point
        gaps = np.abs(_wrapped(np.asarray(roots) - hit.bearing1[0, k]))
        assert gaps.min() < 1e-7
        # Transversal angle from the two radius vectors, folded into [0, pi/2].
        u, v = p1 - o1, p1 - o2
        angle = math.acos(np.clip(u @ v / (np.linalg.norm(u) * np.linalg.norm(v)), -1.0, 1.0))
        assert hit.transversal[0] == pytest.approx(min(angle, math.pi - angle), abs=1e-7)


def test_concentric_and_separate_circles_do_not_meet() -> None:
    hit = circle_intersections([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0]], [1.0, 1.0, 1.0],
                               [[0.0, 0.0], [0.5, 0.0], [2.5, 0.0]], [1.0, 3.0, 1.0])
    assert hit.meets.tolist() == [False, False, False]
    assert np.isnan(hit.transversal).all()


# --- eq. 5.4: the bound holds for a common reflector and ranges within +-delta/2 --------------


@settings(max_examples=80, deadline=None)
@given(
    a1=st.floats(0.0, 2.0 * math.pi), gap=st.floats(math.radians(32.0), math.radians(148.0)),
    r1=st.floats(1.0, 6.0), r2=st.floats(1.0, 6.0),
    e1=st.floats(-0.5, 0.5), e2=st.floats(-0.5, 0.5),
)
def test_a_transversal_crossing_is_within_the_eq_5_4_bound(
    a1: float, gap: float, r1: float, r2: float, e1: float, e2: float
) -> None:
    psi = math.radians(30.0)
    p = np.array([0.3, -0.2])
    o1 = p - r1 * np.array([math.cos(a1), math.sin(a1)])
    o2 = p - r2 * np.array([math.cos(a1 + gap), math.sin(a1 + gap)])
    # Ranges quantised: each off by at most half a quantum.
    hit = circle_intersections(o1, r1 + e1 * INCH, o2, r2 + e2 * INCH)
    assert hit.meets[0]
    points = o1 + (r1 + e1 * INCH) * np.column_stack(
        (np.cos(hit.bearing1[0]), np.sin(hit.bearing1[0])))
    error = float(np.min(np.linalg.norm(points - p, axis=1)))
    assert error <= atm_error_bound(psi, INCH)


# --- the model ---------------------------------------------------------------------------------


def test_a_point_reflector_seen_from_many_places_is_recovered() -> None:
    # A corner at P seen from 12 origins spread over 150 degrees around it, at 1.5-4 m, each
    # beam axis a little off the true bearing (but the beam contains P). Ranges are quantised to
    # one inch, so each range is within delta/2 of |P - o|.
    rng = np.random.default_rng(3)
    p = np.array([2.0, 3.0])
    psi = math.radians(30.0)
    method = AtmMethod(history_size=50, beam_width=PHI, min_transversal=psi,
                       range_resolution=INCH)
    for k, angle in enumerate(np.linspace(0.0, math.radians(150.0), 12)):
        origin = p - rng.uniform(1.5, 4.0) * np.array([math.cos(angle), math.sin(angle)])
        true_range = float(np.linalg.norm(p - origin))
        quantised = round(true_range / INCH) * INCH
        method.add(_reading_towards(k, origin, p, rng.uniform(-0.4, 0.4) * PHI, quantised))
    local = method.local_map()
    assert local.count(PointSource.ATM) == len(local)  # every arc crossed a partner at >= 30°
    # With psi > phi the mirror crossing of a pair sharing P can never lie in both beams (its
    # bearings would put the two radii within phi of each other), so every kept crossing is
    # the perturbed P, within the eq. 5.4 bound; the median of crossings on one arc lies
    # between two of them, hence on the same short arc of points within the bound.
    bound = atm_error_bound(psi, INCH)
    errors = np.linalg.norm(local.xy - p, axis=1)
    assert np.all(errors <= bound)
    np.testing.assert_allclose(local.max_error, bound)


def test_exact_ranges_give_the_reflector_exactly() -> None:
    p = np.array([-1.0, 0.5])
    method = AtmMethod(history_size=10, beam_width=PHI, min_transversal=math.radians(30.0),
                       range_resolution=0.0)
    for k, angle in enumerate([0.0, 0.7, 1.4, 2.1]):
        origin = p - 2.5 * np.array([math.cos(angle), math.sin(angle)])
        method.add(_reading_towards(k, origin, p, 0.3 * PHI))
    local = method.local_map()
    assert local.source.tolist() == [int(PointSource.ATM)] * 4
    np.testing.assert_allclose(local.xy, np.tile(p, (4, 1)), atol=1e-9)


@pytest.mark.parametrize(("psi_deg", "kept"), [(30.0, False), (5.0, True)])
def test_shallow_crossings_are_dropped(psi_deg: float, kept: bool) -> None:
    # Two arcs through P whose radii meet at exactly 10 degrees there.
    p = np.array([0.0, 3.0])
    method = AtmMethod(history_size=10, beam_width=PHI, min_transversal=math.radians(psi_deg),
                       range_resolution=INCH)
    for k, angle in enumerate([math.radians(85.0), math.radians(95.0)]):
        method.add(_reading_towards(k, p - 3.0 * np.array([math.cos(angle), math.sin(angle)]), p))
    hit = circle_intersections([method.history.x[0], method.history.y[0]], 3.0,
                               [method.history.x[1], method.history.y[1]], 3.0)
    assert math.degrees(hit.transversal[0]) == pytest.approx(10.0)
    est = _atm(method).estimates(method.history.slots())
    assert est.processed.tolist() == [kept, kept]
    if kept:
        np.testing.assert_allclose(est.xy, [p, p], atol=1e-9)


@pytest.mark.parametrize(("psi_deg", "kept"), [(30.0, False), (10.0, True)])
def test_crossings_of_facing_sensors_fold_to_their_acute_angle(psi_deg: float,
                                                               kept: bool) -> None:
    # Sensors at (0, 0) and (2, 0) face each other and both hear something at 1.01 m: the
    # circles cross at (1, ±0.142), inside both beams, where the radii meet at 180° - 16.2°.
    # Folded into [0, 90°] that is 16.2°: a shallow crossing, dropped at ψ = 30°, kept at 10°.
    method = AtmMethod(history_size=10, beam_width=PHI, min_transversal=math.radians(psi_deg),
                       range_resolution=INCH)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.01))
    method.add(Reading(0.1, 1, 2.0, 0.0, math.pi, 1.01))
    half_angle = math.degrees(math.atan2(math.sqrt(1.01**2 - 1.0), 1.0))  # 8.1° off each axis
    assert 2 * half_angle == pytest.approx(16.2, abs=0.1)
    est = _atm(method).estimates(method.history.slots())
    assert est.processed.tolist() == [kept, kept]


@pytest.mark.parametrize("rotated", [0, 1])
@pytest.mark.parametrize(("offset", "kept"), [(0.6, False), (0.4, True)])
def test_crossings_outside_either_beam_are_dropped(rotated: int, offset: float,
                                                   kept: bool) -> None:
    # Two arcs through P = (1, 1.5) from (0, 0) and (2, 0): radii meet at 2 atan(1/1.5) = 67°.
    # The mirror crossing (1, -1.5) is behind both beams. One beam axis is turned by `offset`
    # beam widths away from P: at 0.6 P is outside that beam (half-width 0.5), at 0.4 inside.
    p = np.array([1.0, 1.5])
    method = AtmMethod(history_size=10, beam_width=PHI, min_transversal=math.radians(30.0),
                       range_resolution=INCH)
    for k, origin in enumerate([np.array([0.0, 0.0]), np.array([2.0, 0.0])]):
        method.add(_reading_towards(k, origin, p, offset * PHI if k == rotated else 0.0))
    est = _atm(method).estimates(method.history.slots())
    assert est.processed.tolist() == [kept, kept]
    assert _atm(method).counts[method.history.slots()].tolist() == [int(kept), int(kept)]


def test_an_arc_without_crossings_falls_back_to_its_centerline_point() -> None:
    method = AtmMethod(history_size=10, beam_width=PHI)
    method.add(Reading(0.0, 0, 1.0, 2.0, 0.5, 3.0, PHI))
    method.add(Reading(1.0, 1, 50.0, 2.0, 0.5, 1.0, PHI))  # far away: circles do not meet
    est = _atm(method).estimates(method.history.slots())
    assert not est.processed.any()
    assert est.source.tolist() == [int(PointSource.CENTERLINE)] * 2
    np.testing.assert_allclose(est.xy[0], [1.0 + 3.0 * math.cos(0.5), 2.0 + 3.0 * math.sin(0.5)])
    np.testing.assert_allclose(est.width, [PHI, PHI])
    # eq. 5.2-5.3 with E_m = phi/2: chord 2 r sin(phi/4).
    np.testing.assert_allclose(est.max_error, [6.0 * math.sin(PHI / 4), 2.0 * math.sin(PHI / 4)])


def test_crossings_stay_after_the_partner_leaves_the_history() -> None:
    p = np.array([0.0, 2.0])
    method = AtmMethod(history_size=2, beam_width=PHI, min_transversal=math.radians(30.0),
                       range_resolution=INCH)
    method.add(_reading_towards(0, np.array([-1.5, 0.0]), p))
    method.add(_reading_towards(1, np.array([1.5, 0.0]), p))
    method.add(Reading(2.0, 2, 40.0, 40.0, 0.0, 1.0, PHI))  # arc 0 leaves; nothing to cross
    local = method.local_map()
    assert local.reading_id.tolist() == [1, 2]
    assert local.source.tolist() == [int(PointSource.ATM), int(PointSource.CENTERLINE)]
    np.testing.assert_allclose(local.xy[0], p, atol=1e-9)
    # Slots are reused after 2 * capacity arcs; a reused slot must start without crossings.
    for k in range(3, 6):
        method.add(Reading(float(k), k, 40.0 * k, 40.0, 0.0, 1.0, PHI))
    assert method.local_map().source.tolist() == [int(PointSource.CENTERLINE)] * 2
    final = method.finish()
    assert final.source.tolist() == [int(PointSource.ATM)] * 2 + [int(PointSource.CENTERLINE)] * 4
    np.testing.assert_allclose(final.xy[:2], [p, p], atol=1e-9)


def _cluttered_stream(n: int, seed: int) -> list[Reading]:
    """Readings of a few point reflectors from random places, beams containing them."""
    rng = np.random.default_rng(seed)
    targets = rng.uniform(-3.0, 3.0, size=(4, 2))
    readings = []
    for k in range(n):
        target = targets[rng.integers(len(targets))]
        angle = rng.uniform(0.0, 2.0 * math.pi)
        origin = target - rng.uniform(0.5, 4.0) * np.array([math.cos(angle), math.sin(angle)])
        readings.append(_reading_towards(k, origin, target, rng.uniform(-0.45, 0.45) * PHI))
    return readings


def test_each_final_point_is_the_last_point_the_arc_had_in_the_local_map() -> None:
    # Retired rows must stay frozen and reused rows must start empty: the global map then holds,
    # for every arc, exactly the point it last had while it was live.
    method = AtmMethod(history_size=6, beam_width=PHI, min_transversal=math.radians(20.0),
                       range_resolution=INCH)
    last: dict[int, tuple[float, float, int]] = {}
    for k, reading in enumerate(_cluttered_stream(60, seed=5)):
        method.add(reading)
        local = method.local_map()
        for rid, xy, source in zip(local.reading_id, local.xy, local.source, strict=True):
            last[int(rid)] = (float(xy[0]), float(xy[1]), int(source))
        assert len(local) == min(k + 1, 6)
    final = method.finish()
    assert final.reading_id.tolist() == list(range(60))
    assert final.count(PointSource.ATM) > 10  # the stream does produce crossings
    for rid, xy, source in zip(final.reading_id, final.xy, final.source, strict=True):
        assert (xy[0], xy[1], source) == last[int(rid)]


def test_state_does_not_grow_with_the_log() -> None:
    capacity = 10
    method = AtmMethod(history_size=capacity, beam_width=PHI,
                       min_transversal=math.radians(20.0), range_resolution=INCH)
    model = _atm(method)
    assert model.counts.shape == (2 * capacity,)
    # Room for every crossing an arc can have: 2 a pair, with capacity - 1 older and newer arcs.
    most = 4 * (capacity - 1)
    assert model.bearings.shape[0] == 2 * capacity
    assert model.bearings.shape[1] <= most
    shapes = []
    for k, reading in enumerate(_cluttered_stream(25 * capacity, seed=8)):
        method.add(reading)
        if k in (5 * capacity, 25 * capacity - 1):
            shapes.append(model.bearings.shape)
    assert shapes[0] == shapes[1]
    assert model.bearings.shape[1] <= most
    assert model.counts.max() > 0
    assert model.counts.max() <= model.bearings.shape[1]
    assert model.counters()["atm_crossings"] > 0


def test_the_crossing_store_grows_on_demand_and_keeps_every_crossing() -> None:
    # 40 arcs from one point through one beam-wide fan of 16 sensors cross none; arcs from a
    # ring of origins all around a central post cross each other pairwise in their beams.
    # A store that starts at 2 columns must grow and still keep what a full-size store keeps.
    rng = np.random.default_rng(4)
    n = 120
    angle = rng.uniform(0.0, 2.0 * math.pi, n)
    dist = rng.uniform(1.0, 1.5, n)
    readings = [Reading(0.1 * i, i % 16, float(dist[i] * math.cos(angle[i])),
                        float(dist[i] * math.sin(angle[i])), float(angle[i] + math.pi),
                        float(dist[i]), PHI) for i in range(n)]
    counts = []
    for initial in (2, 4 * (n - 1)):
        method = AtmMethod(history_size=n, beam_width=PHI, min_transversal=math.radians(20.0),
                           range_resolution=INCH)
        model = _atm(method)
        model.bearings = np.zeros((model.bearings.shape[0], initial), dtype=np.float32)
        for reading in readings:
            method.add(reading)
        counts.append(model.counts.copy())
        assert model.counts.max() <= model.bearings.shape[1]
        if initial == 2:
            assert model.bearings.shape[1] > 2  # it grew
            small = (model, method.local_map())
        else:
            full = (model, method.local_map())
    np.testing.assert_array_equal(counts[0], counts[1])
    assert counts[0].max() > 2
    for slot in np.flatnonzero(counts[0]):
        c = counts[0][slot]
        np.testing.assert_array_equal(np.sort(small[0].bearings[slot, :c]),
                                      np.sort(full[0].bearings[slot, :c]))
    np.testing.assert_array_equal(small[1].xy, full[1].xy)


def test_a_store_beyond_the_memory_limit_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(atm_module, "MAX_ATM_STATE_BYTES", 32)
    method = AtmMethod(history_size=4, beam_width=math.radians(60.0),
                       min_transversal=math.radians(30.0), range_resolution=INCH)
    _atm(method).bearings = np.zeros((8, 1), dtype=np.float32)
    wide = math.radians(60.0)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.05, wide))
    with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
        method.add(Reading(1.0, 8, 2.0, 0.0, math.pi, 1.05, wide))
    assert issubclass(CrossingStoreError, SonarcarveError)
    # Half intersected, the method refuses to go on rather than map from a partial state:
    # no reading is stored, no map or measure is read.
    stored = method.history.appended
    with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
        method.add(Reading(2.0, 0, 0.0, 0.0, 0.0, 1.5, wide))
    with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
        method.add_many(ReadingBatch.from_readings([Reading(3.0, 0, 0.0, 0.0, 0.0, 1.5, wide)]))
    assert method.history.appended == stored
    slots = method.history.slots()
    for read in (method.local_map, method.measures, method.global_map, method.finish,
                 lambda: method.estimates(slots), lambda: _atm(method).estimates(slots)):
        with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
            read()


@pytest.mark.parametrize(("rows", "columns", "needed", "most", "grown"), [
    (100, 32, 33, 10_000, 64),  # doubled
    (100, 32, 200, 10_000, 256),  # doubled until enough
    (100, 32, 40, 50, 50),  # never past every crossing an arc can have
    # 1 GiB holds 2**30 / (4 * 200,000) = 1,342 float32 columns of 200,000 rows: a doubling
    # from 1,024 to 2,048 would not fit, what is left does.
    (200_000, 1024, 1025, 400_000, 1342),
])
def test_the_store_grows_by_doubling_within_its_bounds(rows: int, columns: int, needed: int,
                                                       most: int, grown: int) -> None:
    assert atm_module.grown_columns(rows, columns, needed, most) == grown


def test_the_store_is_refused_only_past_what_the_limit_holds() -> None:
    with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take 1\.0 GiB"):
        atm_module.grown_columns(200_000, 1024, 1343, 400_000)
    # Evidence carving's store is the same class under its own name.
    with pytest.raises(CrossingStoreError,
                       match=r"^evidence carving's crossing store would take 1\.0 GiB"):
        atm_module.grown_columns(200_000, 1024, 1343, 400_000, "evidence carving's")


@pytest.mark.parametrize(("psi", "delta"), [(-0.1, INCH), (1.6, INCH), (0.5, -1.0),
                                            (0.5, math.nan)])
def test_bad_parameters_are_refused(psi: float, delta: float) -> None:
    with pytest.raises(ConfigError, match=r"^(min_transversal|range_resolution) must"):
        AtmMethod(min_transversal=psi, range_resolution=delta)


def test_atm_is_registered() -> None:
    assert "atm" in METHODS
    method = make_method("atm", MethodConfig(history_size=7, min_transversal=0.4))
    assert isinstance(method, AtmMethod)
    assert method.name == "atm"
    assert _atm(method).min_transversal == 0.4
    assert method.history.capacity == 7


def test_both_crossings_of_one_pair_can_be_kept() -> None:
    # Two 60° beams facing each other from 2 m apart, ranges 1.05 m: the circles cross at
    # (1, ±0.32), 17.7° off both axes (inside the 30° half-widths), with radii at 144.5°, i.e.
    # 35.5° folded (>= 30°). Both crossings count, which is why an arc's store needs two
    # columns per partner.
    wide = math.radians(60.0)
    method = AtmMethod(history_size=4, beam_width=wide, min_transversal=math.radians(30.0),
                       range_resolution=INCH)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.05, wide))
    method.add(Reading(1.0, 8, 2.0, 0.0, math.pi, 1.05, wide))
    slots = method.history.slots()
    model = _atm(method)
    assert model.counts[slots].tolist() == [2, 2]
    half_chord = math.sqrt(1.05**2 - 1.0)
    expected = sorted([math.atan2(half_chord, 1.0), -math.atan2(half_chord, 1.0)])
    for slot in slots:
        np.testing.assert_allclose(sorted(model.bearings[slot, :2]), expected, atol=1e-6)
    est = model.estimates(slots)
    np.testing.assert_allclose(est.xy, [[1.05, 0.0], [2.0 - 1.05, 0.0]], atol=1e-6)
    np.testing.assert_allclose(est.width, [2.0 * expected[1]] * 2, atol=1e-6)


def test_psi_zero_is_refused() -> None:
    # ψ = 0 would give every ATM point an infinite bound (UX review, finding 4).
    with pytest.raises(ConfigError, match=r"min_transversal must lie in \(0, pi/2\] radians"):
        AtmMethod(history_size=4, beam_width=PHI, min_transversal=0.0)
    with pytest.raises(ConfigError, match="min_transversal"):
        MethodConfig(min_transversal=0.0)


def test_a_tiny_psi_keeps_every_crossing_with_a_huge_bound() -> None:
    method = AtmMethod(history_size=4, beam_width=PHI, min_transversal=1e-9,
                       range_resolution=INCH)
    reading = Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0, PHI)
    method.add(reading)
    method.add(reading)  # the same circle again: concentric, never a crossing
    method.add(Reading(2.0, 0, 0.1, 0.0, 0.0, 2.0, PHI))  # crosses both at 2.9°, far off-beam
    method.add(Reading(3.0, 0, 0.0, 0.1, 0.0, 2.0, PHI))  # crosses the first two in-beam
    est = _atm(method).estimates(method.history.slots())
    assert est.processed.tolist() == [True, True, False, True]
    assert est.max_error[0] > 1e6  # δ (1/sin ψ + 1/tan ψ) ≈ 2δ/ψ = 5e7 m
    assert atm_error_bound(0.0, 0.0) == 0.0


def test_cached_medians_follow_every_change_of_the_crossings() -> None:
    # estimates() recomputes only the rows whose crossings changed; after every reading its
    # medians and spans must equal numpy's over the stored crossings, row by row.
    method = AtmMethod(history_size=12, beam_width=PHI, min_transversal=math.radians(20.0),
                       range_resolution=INCH)
    model = _atm(method)
    for k, reading in enumerate(_cluttered_stream(80, seed=3)):
        method.add(reading)
        if k % 3:
            continue
        slots = method.history.slots()
        est = model.estimates(slots)
        for j, slot in enumerate(slots):
            c = model.counts[slot]
            if c == 0:
                assert not est.processed[j]
                continue
            values = model.bearings[slot, :c].astype(np.float64)
            axis = method.history.theta[slot] + np.median(values)
            r = method.history.r[slot]
            xy = (method.history.x[slot] + r * math.cos(axis),
                  method.history.y[slot] + r * math.sin(axis))
            np.testing.assert_allclose(est.xy[j], xy, rtol=0, atol=1e-12)
            assert est.width[j] == values.max() - values.min()
