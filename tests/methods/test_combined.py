import itertools
import math
import threading

import numpy as np
import pytest

from sonarcarve.maps import PointSource
from sonarcarve.methods import METHODS, MethodConfig, make_method
from sonarcarve.methods import atm as atm_module
from sonarcarve.methods.atm import AtmMethod, AtmModel, CrossingStoreError
from sonarcarve.methods.base import Estimates, SonarMethod
from sonarcarve.methods.carving import CarvingMethod, CarvingModel
from sonarcarve.methods.combined import CombinedMethod, combine_carving_atm
from sonarcarve.readings import Reading, ReadingBatch
from sonarcarve.sim.world import World

PHI = math.radians(22.5)
INCH = 0.0254


def _room_stream(seed: int) -> list[Reading]:
    """A 16-sensor ring driven round a room with a box in it.

    Echo range: the nearest wall over 31 rays across the beam, plus 5 mm noise, quantised to
    one inch; echoes beyond 6 m are lost.
    """
    walls = np.array([
        [0.0, 0.0, 8.0, 0.0], [8.0, 0.0, 8.0, 5.0], [8.0, 5.0, 0.0, 5.0], [0.0, 5.0, 0.0, 0.0],
        [3.0, 2.0, 5.0, 2.0], [5.0, 2.0, 5.0, 3.0], [5.0, 3.0, 3.0, 3.0], [3.0, 3.0, 3.0, 2.0],
    ])
    world = World(walls, "room-with-box")
    rng = np.random.default_rng(seed)
    path = np.array([[1.0, 1.0], [7.0, 1.0], [7.0, 4.0], [1.0, 4.0], [1.0, 1.2]])
    readings: list[Reading] = []
    for start, end in itertools.pairwise(path):
        heading = math.atan2(*(end - start)[::-1])
        steps = int(np.linalg.norm(end - start) / 0.15)
        for s in range(steps):
            centre = start + (end - start) * s / steps
            for sensor in range(16):
                theta = heading + sensor * 2.0 * math.pi / 16
                origin = centre + 0.2 * np.array([math.cos(theta), math.sin(theta)])
                rays = theta + np.linspace(-PHI / 2, PHI / 2, 31)
                distance, _ = world.cast_rays(origin, rays)
                r = float(distance.min()) + rng.normal(0.0, 0.005)
                r = round(r / INCH) * INCH
                if 0.1 < r < 6.0:
                    readings.append(Reading(float(len(readings)), sensor, float(origin[0]),
                                            float(origin[1]), theta, r, PHI))
    return readings


def _model(method: SonarMethod, kind: type) -> object:
    (model,) = (m for m in method.models if isinstance(m, kind))
    return model


def test_combined_is_at_least_as_good_as_either_method_on_every_arc() -> None:
    size, psi, tol = 60, math.radians(30.0), 0.025
    carving = CarvingMethod(size, PHI, range_tolerance=tol)
    atm = AtmMethod(size, PHI, min_transversal=psi, range_resolution=INCH)
    both = CombinedMethod(size, PHI, range_tolerance=tol, min_transversal=psi,
                          range_resolution=INCH)
    labels_seen: set[int] = set()
    stream = _room_stream(seed=1)
    assert len(stream) > 500
    for k, reading in enumerate(stream):
        for method in (carving, atm, both):
            method.add(reading)
        if k % 25:
            continue
        slots = both.history.slots()
        np.testing.assert_array_equal(slots, carving.history.slots())
        c, a, b = carving.estimates(slots), atm.estimates(slots), both.estimates(slots)
        # Table I: processed by either, so the share is at most the smaller one.
        assert np.mean(~b.processed) <= min(np.mean(~c.processed), np.mean(~a.processed))
        assert b.alive.tolist() == c.alive.tolist()  # carving removes, ATM never does
        live = b.alive
        assert np.all(b.max_error[live] <= c.max_error[live])
        # Up to rounding: an uncarved arc's width (θ + φ/2) - (θ - φ/2) is φ to within an ulp.
        assert np.all(b.max_error[live] <= a.max_error[live] * (1.0 + 1e-12))
        assert set(b.source[live].tolist()) <= {int(s) for s in PointSource}
        # Each point is one model's own point, labelled with that model.
        from_atm = live & (b.source == PointSource.ATM)
        np.testing.assert_array_equal(b.xy[from_atm], a.xy[from_atm])
        np.testing.assert_array_equal(b.xy[live & ~from_atm], c.xy[live & ~from_atm])
        assert np.all(b.source[live & ~from_atm] == c.source[live & ~from_atm])
        labels_seen |= set(b.source[live].tolist())
    assert labels_seen == {int(s) for s in PointSource}  # the stream exercises every choice
    # Running both on one history changes neither model's state.
    assert _model(both, AtmModel).counters() == _model(atm, AtmModel).counters()
    assert _model(both, CarvingModel).counters() == _model(carving, CarvingModel).counters()
    # The final map keeps exactly the arcs carving kept.
    assert both.finish().reading_id.tolist() == carving.finish().reading_id.tolist()


def _estimates(processed: list[bool], max_error: list[float], source: PointSource,
               alive: list[bool] | None = None) -> Estimates:
    n = len(processed)
    return Estimates(
        alive=np.array(alive if alive is not None else [True] * n),
        processed=np.array(processed),
        xy=np.full((n, 2), float(source)),  # tells the two models' points apart
        width=np.full(n, 0.1 * float(source)),
        max_error=np.array(max_error),
        source=np.full(n, int(source), dtype=np.int8),
    )


def test_the_smaller_bound_wins_ties_go_to_carving_and_unprocessed_atm_never_counts() -> None:
    carving = _estimates([True, True, False, True, False], [0.2, 0.1, 0.1, 0.1, 0.3],
                         PointSource.CARVED, alive=[True, True, True, False, True])
    atm = _estimates([True, True, False, True, True], [0.1, 0.1, 0.01, 0.01, 0.3],
                     PointSource.ATM)
    out = combine_carving_atm(carving, atm)
    assert out.source.tolist() == [PointSource.ATM, PointSource.CARVED, PointSource.CARVED,
                                   PointSource.ATM, PointSource.CARVED]
    assert out.xy[:, 0].tolist() == [float(s) for s in out.source]
    assert out.max_error.tolist() == [0.1, 0.1, 0.1, 0.01, 0.3]
    assert out.alive.tolist() == [True, True, True, False, True]  # carving's removal stands
    assert out.processed.tolist() == [True, True, False, True, True]


def test_combined_is_registered_and_configured() -> None:
    assert "combined" in METHODS
    config = MethodConfig(history_size=9, range_tolerance=0.01, min_transversal=0.5,
                          range_resolution=0.01)
    method = make_method("combined", config)
    assert isinstance(method, CombinedMethod)
    carving, atm = method.models
    assert isinstance(carving, CarvingModel)
    assert isinstance(atm, AtmModel)
    assert carving.range_tolerance == pytest.approx(0.01)
    assert atm.min_transversal == pytest.approx(0.5)
    assert atm.range_resolution == pytest.approx(0.01)
    assert carving.history is atm.history is method.history  # one shared history


def _wandering_stream(n: int, seed: int, *, spread: float, huge_share: float) -> ReadingBatch:
    """A robot wandering over ``spread`` metres: random bearings, ranges and beam widths, some
    coincident origins, some huge ranges (arcs beyond the index's cells), some no-echo
    readings (free space up to ``max_range``)."""
    rng = np.random.default_rng(seed)
    xy = np.mod(rng.normal(0.0, 0.05, (n, 2)).cumsum(axis=0), spread)
    for i in np.flatnonzero(rng.random(n) < 0.1):
        xy[i] = xy[max(i - 1, 0)]
    r = np.round(rng.uniform(0.05, 4.0, n) / INCH) * INCH + INCH
    huge = rng.random(n) < huge_share
    r[huge] = rng.uniform(50.0, 5e3, int(huge.sum()))
    max_range = np.full(n, np.nan)
    silent = rng.random(n) < 0.05
    r[silent] = np.inf
    max_range[silent] = rng.uniform(0.5, 6.0, int(silent.sum()))
    return ReadingBatch.from_arrays(
        t=np.arange(n) * 0.01, sensor=rng.integers(0, 16, n), x=xy[:, 0], y=xy[:, 1],
        theta=rng.uniform(-3.0 * math.pi, 3.0 * math.pi, n), range=r,
        beam_width=np.where(rng.random(n) < 0.3, rng.uniform(0.05, 2.5, n), np.nan),
        max_range=max_range,
    )


def _feed_mixed(method: SonarMethod, batch: ReadingBatch) -> None:
    """Blocks with single readings between them."""
    cut = len(batch) // 3
    method.add_many(batch[:cut])
    for i in range(cut, cut + 25):
        method.add(batch[i])
    method.add_many(batch[cut + 25:])


def _room_batch(seed: int) -> ReadingBatch:
    stream = _room_stream(seed)
    columns = ("t", "sensor", "x", "y", "theta", "range", "beam_width")
    return ReadingBatch.from_arrays(**{c: np.array([getattr(r, c) for r in stream])
                                       for c in columns})


@pytest.mark.parametrize(("stream", "history", "max_incidence"), [
    ("wander 0 3.0 0.0", 40, 0.5 * math.pi),
    ("wander 1 1.5 0.02", 150, 0.5 * math.pi),
    ("wander 2 8.0 0.02", 60, math.radians(17.5)),
    ("wander 3 2.0 0.0", 900, 0.5 * math.pi),  # no eviction
    ("room 2", 400, 0.5 * math.pi),  # ATM's crossing store grows inside the joint kernel
])
def test_combined_leaves_each_model_as_it_runs_alone(stream: str, history: int,
                                                     max_incidence: float) -> None:
    # The oracles are the two methods run on their own (each with its own index); combined
    # runs both in one kernel over one index of every live arc.
    kind, seed, *rest = stream.split()
    if kind == "room":
        batch = _room_batch(int(seed))
    else:
        batch = _wandering_stream(800, int(seed), spread=float(rest[0]),
                                  huge_share=float(rest[1]))
    config = MethodConfig(history_size=history, max_incidence=max_incidence)
    both = make_method("combined", config)
    carving = make_method("carve", config)
    atm = make_method("atm", config)
    committed: list[list[Estimates]] = [[], [], []]
    for method, out in zip((both, carving, atm), committed, strict=True):
        method.add_commit_listener(lambda _h, _s, est, out=out: out.append(est))
        _feed_mixed(method, batch)
    c_model, a_model = _model(both, CarvingModel), _model(both, AtmModel)
    c_alone, a_alone = _model(carving, CarvingModel), _model(atm, AtmModel)
    assert isinstance(c_model, CarvingModel)
    assert isinstance(c_alone, CarvingModel)
    assert isinstance(a_model, AtmModel)
    assert isinstance(a_alone, AtmModel)
    live = both.history.slots()
    for field in ("lo", "hi", "bounds", "tips", "status", "carved"):
        np.testing.assert_array_equal(getattr(c_model, field)[live], getattr(c_alone, field)[live])
    np.testing.assert_array_equal(a_model.counts, a_alone.counts)
    for slot in np.flatnonzero(a_alone.counts):
        c = a_alone.counts[slot]
        np.testing.assert_array_equal(np.sort(a_model.bearings[slot, :c]),
                                      np.sort(a_alone.bearings[slot, :c]))
    assert c_model.counters() == c_alone.counters()
    assert a_model.counters() == a_alone.counters()
    if kind == "room":
        assert a_model.bearings.shape[1] > 32  # the store grew (the kernel stopped and resumed)
    # Every field of every row, removed arcs included, live and as committed:
    # combine_carving_atm of the two alone (combined computes ATM's medians only where used).
    pairs = [(both.estimates(live), carving.estimates(live), atm.estimates(live))]
    for method in (both, carving, atm):
        method.finish()
    pairs += list(zip(*committed, strict=True))
    assert len(pairs) > (2 if history < 800 else 1)
    for got, alone_c, alone_a in pairs:
        want = combine_carving_atm(alone_c, alone_a)
        for field in ("alive", "processed", "xy", "width", "max_error", "source", "fate"):
            np.testing.assert_array_equal(getattr(got, field), getattr(want, field))
            assert getattr(got, field).dtype == getattr(want, field).dtype, field
        assert got.confidence is want.confidence is None


def test_a_store_beyond_the_memory_limit_stops_combined_for_good(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # ATM's test case (test_atm.py): 32 bytes hold no column of 8 rows, so the first pair of
    # facing arcs that cross cannot be stored. Combined then refuses every reading (a no-echo
    # one too: carving must not carve from it) and every map.
    monkeypatch.setattr(atm_module, "MAX_ATM_STATE_BYTES", 32)
    wide = math.radians(60.0)
    method = CombinedMethod(history_size=4, beam_width=wide, min_transversal=math.radians(30.0),
                            range_resolution=INCH)
    atm = _model(method, AtmModel)
    carving = _model(method, CarvingModel)
    assert isinstance(atm, AtmModel)
    assert isinstance(carving, CarvingModel)
    atm.bearings = np.zeros((8, 1), dtype=np.float32)
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.05, wide))
    with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
        method.add(Reading(1.0, 8, 2.0, 0.0, math.pi, 1.05, wide))
    stored = method.history.appended
    carved = carving.lo.copy(), carving.hi.copy(), carving.status.copy()
    no_echo = Reading(2.0, 0, 0.0, 0.0, 0.0, math.inf, wide, max_range=3.0)
    for feed in (lambda: method.add(no_echo),
                 lambda: method.add_many(ReadingBatch.from_readings([no_echo])),
                 lambda: method._feed_no_echo(no_echo, wide),
                 lambda: method.add(Reading(2.0, 0, 0.0, 0.0, 0.0, 1.5, wide))):
        with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
            feed()
    assert method.history.appended == stored
    for before, after in zip(carved, (carving.lo, carving.hi, carving.status), strict=True):
        np.testing.assert_array_equal(before, after)
    slots = method.history.slots()
    for read in (method.local_map, method.measures, method.global_map, method.finish,
                 lambda: method.estimates(slots)):
        with pytest.raises(CrossingStoreError, match=r"^ATM's crossing store would take"):
            read()


def test_a_grown_atm_store_reaches_the_next_single_add() -> None:
    # A block grows ATM's store inside the joint kernel; the single add() after it must write
    # to the grown store (the kernel's cached arguments are rebuilt), so both models end as
    # when run alone, every field of every row.
    batch = _room_batch(2)
    config = MethodConfig(history_size=400)
    both, carving, atm = (make_method(name, config) for name in ("combined", "carve", "atm"))
    cut = 1100  # of 1,888 readings: the store first outgrows 32 columns after about 1,000
    for method in (both, carving, atm):
        method.add_many(batch[:cut])
    a_model = _model(both, AtmModel)
    assert isinstance(a_model, AtmModel)
    assert a_model.bearings.shape[1] > 32  # the block grew the store
    assert isinstance(both, CombinedMethod)
    for i in range(cut, cut + 10):
        for method in (both, carving, atm):
            method.add(batch[i])
        assert both._arguments is not None
        assert any(argument is a_model.bearings for argument in both._arguments)
    c_model, c_alone, a_alone = (_model(both, CarvingModel), _model(carving, CarvingModel),
                                 _model(atm, AtmModel))
    assert isinstance(c_model, CarvingModel)
    assert isinstance(a_alone, AtmModel)
    for field in ("lo", "hi", "bounds", "tips", "status", "carved"):
        np.testing.assert_array_equal(getattr(c_model, field), getattr(c_alone, field))
    np.testing.assert_array_equal(a_model.counts, a_alone.counts)
    for slot in np.flatnonzero(a_alone.counts):
        c = a_alone.counts[slot]
        np.testing.assert_array_equal(np.sort(a_model.bearings[slot, :c]),
                                      np.sort(a_alone.bearings[slot, :c]))


def test_a_store_growth_that_never_reaches_the_kernel_fails_instead_of_looping(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # If the joint kernel kept the old store after a growth it would stop at the same arc
    # for ever (found by mutation: the test above then hangs). A growth that changes nothing
    # stands in for that bug here.
    batch = _room_batch(2)
    both = make_method("combined", MethodConfig(history_size=400))
    a_model = _model(both, AtmModel)
    assert isinstance(a_model, AtmModel)
    monkeypatch.setattr(a_model, "make_room", lambda needed: None)
    raised: list[BaseException] = []

    def feed() -> None:
        try:
            both.add_many(batch[:1100])
        except BaseException as error:  # handed to the test thread
            raised.append(error)

    # In a daemon thread, bounded: without the guard the feed never returns, and the test
    # must fail rather than hang the suite.
    worker = threading.Thread(target=feed, daemon=True)
    worker.start()
    worker.join(timeout=120)
    assert not worker.is_alive(), "add_many looped instead of failing"
    assert len(raised) == 1
    assert isinstance(raised[0], RuntimeError)
    assert "stopped twice at the same arc" in str(raised[0])


@pytest.mark.parametrize("seed", [0, 1])
def test_point_bearings_are_what_the_estimates_give_the_grids_bands(seed: int) -> None:
    # The carved grid reads a band's bearing, width and life from point_bearings in place of
    # the estimates (review rev16): the bearing of the estimate's point seen from its sensor,
    # bit for bit, for live and removed arcs (the estimates themselves are checked against the
    # two models run alone above).
    batch = _wandering_stream(600, seed, spread=2.0, huge_share=0.02)
    both = make_method("combined", MethodConfig(history_size=80, max_incidence=math.radians(20)))
    assert isinstance(both, CombinedMethod)
    both.add_many(batch)
    h = both.history
    live = h.slots()
    for slots in (live, live[::-1][:7], live[:1], live[:0]):
        est = both.estimates(slots)
        bearing, width, alive = both.point_bearings(slots)
        want = np.arctan2(est.xy[:, 1] - h.y[slots], est.xy[:, 0] - h.x[slots])
        np.testing.assert_array_equal(bearing.view(np.int64), want.view(np.int64))
        np.testing.assert_array_equal(width.view(np.int64), est.width.view(np.int64))
        np.testing.assert_array_equal(alive, est.alive)
    assert not both.estimates(live).alive.all()  # removed arcs are among them


def test_a_slot_outside_the_history_or_not_an_integer_is_an_index_error() -> None:
    # The compiled passes do not check their indices: a slot past the storage read other
    # memory (garbage, or a crash for a far one) until review rev16. Numpy's rules otherwise:
    # a negative slot counts back from the end.
    both = make_method("combined", MethodConfig(history_size=20))
    assert isinstance(both, CombinedMethod)
    both.add_many(_wandering_stream(60, 3, spread=2.0, huge_share=0.0))
    storage = both.history.storage_size
    for slot in (storage, storage + 3, -storage - 1):
        for ask in (both.estimates, both.point_bearings):
            with pytest.raises(IndexError, match=f"slot {slot} is out of bounds"):
                ask(np.array([0, slot]))
    last = both.estimates(np.array([-1]))
    np.testing.assert_array_equal(last.xy, both.estimates(np.array([storage - 1])).xy)
    for ask in (both.estimates, both.point_bearings):  # not truncated to slot 1
        with pytest.raises(IndexError, match="slots must be integers"):
            ask(np.array([1.5]))
    assert len(both.estimates([]).xy) == 0  # an empty list is no float slot
