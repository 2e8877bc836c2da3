import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonarcarve.polling import (
    FiringCause,
    PolledLog,
    PolledReadings,
    PollingError,
    SonarPoller,
    StampedFirings,
    heading_error_bound,
    naive_firings,
    naive_stamps,
    poll_firings,
    poll_readings,
    position_error_bound,
    readings_from_firings,
    sequential_firings,
    simulate_polls,
)

NAN = math.nan


def _feed(poller: SonarPoller, polls: list[tuple[float, list[float]]]) -> list[list[tuple]]:
    out = []
    for t, values in polls:
        out.append([(f.sensor, f.cause.name, round(f.t_low, 9), round(f.t_high, 9), f.value)
                    for f in poller.feed(t, values)])
    return out


def test_hand_example_change_and_timeout() -> None:
    # Sensors 0, 1, 2 fire every 0.1 s at 0.05, 0.15, 0.25, 0.35 ...; sensor 0 reads 1 twice,
    # so its firing at 0.35 changes nothing. The host polls every 0.1 s.
    polls = [(0.0, [NAN, NAN, NAN]), (0.1, [1, NAN, NAN]), (0.2, [1, 2, NAN]),
             (0.3, [1, 2, 3]), (0.4, [1, 2, 3]), (0.5, [1, 5, 3])]
    got = _feed(SonarPoller([0, 1, 2], timeout=0.1), polls)
    assert got == [
        [],
        [(0, "CHANGED", 0.0, 0.1, 1)],  # the only change: anchors l
        [(1, "CHANGED", 0.1, 0.2, 2)],
        [(2, "CHANGED", 0.2, 0.3, 3)],
        # 0.3 + 0.1 <= 0.4: sensor 0 must have fired, in [lo_l, hi_l + timeout] = [0.2, 0.4]
        [(0, "TIMEOUT", 0.2, 0.4, 1)],
        # sensor 1 changed: after the poll at 0.4, and at most 0.1 after sensor 0 (<= 0.4 + 0.1)
        [(1, "CHANGED", 0.4, 0.5, 5)],
    ]
    # Knowing the interval exactly (min_interval = timeout) pins the timeout firing down more.
    exact = _feed(SonarPoller([0, 1, 2], timeout=0.1, min_interval=0.1), polls)
    assert exact[4] == [(0, "TIMEOUT", 0.3, 0.4, 1)]


def test_hand_example_sensors_between_l_and_a_changed_sensor_fired_too() -> None:
    # True firings: s0 0.05 (v1), s1 0.15 (v2), s2 0.25 (v3), s0 0.35 (v4), s1 0.45 (v2 again),
    # s2 0.55 (v6); timeout 0.15; the host misses the poll at 0.5.
    polls = [(0.0, [NAN] * 3), (0.1, [1, NAN, NAN]), (0.2, [1, 2, NAN]), (0.3, [1, 2, 3]),
             (0.4, [4, 2, 3]), (0.6, [4, 2, 6])]
    got = _feed(SonarPoller([0, 1, 2], timeout=0.15), polls)
    assert got[4] == [(0, "CHANGED", 0.3, 0.4, 4)]
    # s2 changed, so s1 fired between s0 (in [0.3, 0.4]) and s2 (in [0.4, 0.6]):
    # s1 <= 0.4 + 0.15 = 0.55 and s1 >= s0 >= 0.3; s2 >= 0.4 (changed after the last poll).
    assert got[5] == [(1, "BETWEEN", 0.3, 0.55, 2), (2, "CHANGED", 0.4, 0.6, 6)]
    naive = naive_firings(_log(polls))
    assert naive.sensor.tolist() == [0, 1, 2, 0, 2]  # the naive host never sees s1's repeat


def test_startup_with_two_changes_anchors_when_only_one_order_fits() -> None:
    # Eight sensors, firings at least 0.1 s apart; the poll interval 0.25 s holds at most three
    # firings, so sensors 2 and 4 changing means 2, 3, 4 (4 ... 2 would be seven firings).
    poller = SonarPoller(range(8), timeout=0.12, min_interval=0.1)
    poller.feed(0.0, [0.0] * 8)
    got = poller.feed(0.25, [0, 0, 7, 0, 9, 0, 0, 0])
    assert [(f.sensor, f.cause) for f in got] == [
        (2, FiringCause.CHANGED), (3, FiringCause.BETWEEN), (4, FiringCause.CHANGED)]
    assert (got[0].t_low, got[2].t_high) == (0.0, 0.25)
    # s2 >= 0; s3 >= s2 + 0.1; s4 >= s3 + 0.1 >= 0.2 and s4 <= 0.25, so s2 <= 0.05, s3 <= 0.15
    assert [round(f.t_high, 9) for f in got] == [0.05, 0.15, 0.25]
    assert [round(f.t_low, 9) for f in got] == [0.0, 0.1, 0.2]
    assert poller.last_known is not None
    assert poller.last_known[0] == 4
    # Without min_interval the order is ambiguous: only the bare intervals, no anchor.
    blind = SonarPoller(range(8), timeout=0.12)
    blind.feed(0.0, [0.0] * 8)
    got = blind.feed(0.25, [0, 0, 7, 0, 9, 0, 0, 0])
    assert [(f.sensor, f.t_low, f.t_high) for f in got] == [(2, 0.0, 0.25), (4, 0.0, 0.25)]
    assert blind.last_known is None


def test_contradiction_restarts_without_raising() -> None:
    poller = SonarPoller([0, 1, 2], timeout=0.1, min_interval=0.1)
    poller.feed(0.0, [0, 0, 0])
    poller.feed(0.05, [1, 0, 0])  # s0 fired in [0, 0.05]
    got = poller.feed(0.06, [1, 1, 0])  # s1 cannot fire 0.1 s after s0 by 0.06
    assert poller.contradictions == 1
    assert [(f.sensor, f.t_low, f.t_high) for f in got] == [(1, 0.05, 0.06)]


def _log(polls: list[tuple[float, list[float]]]) -> PolledLog:
    m = len(polls)
    return PolledLog(t=[t for t, _ in polls], values=[v for _, v in polls], x=np.zeros(m),
                     y=np.zeros(m), heading=np.zeros(m))


def _values(rng: np.random.Generator, sensors: np.ndarray, p_same: float) -> np.ndarray:
    """Random integer values; with probability p_same a firing repeats its sensor's last one."""
    values = rng.integers(1, 10**6, sensors.shape[0]).astype(float)
    last: dict[int, float] = {}
    for k, s in enumerate(sensors.tolist()):
        if s in last and rng.random() < p_same:
            values[k] = last[s]
        last[s] = values[k]
    return values


def _true_index(ft: np.ndarray, fs: np.ndarray, sensor: np.ndarray,
                poll_time: np.ndarray) -> np.ndarray:
    """Each sensor's latest true firing at or before the poll: what the host's value shows."""
    out = np.full(sensor.shape[0], -1)
    for s in np.unique(sensor):
        rows = np.flatnonzero(fs == s)
        mine = sensor == s
        out[mine] = rows[np.searchsorted(ft[rows], poll_time[mine], side="right") - 1]
    return out


def _check_recovery(seed: int, n: int, interval: float, jitter: float, max_gap: float,
                    p_same: float, know_min: bool) -> None:
    """Simulate, poll (gaps up to ``max_gap`` shortest firing intervals), and check."""
    rng = np.random.default_rng(seed)
    order = rng.permutation(n)
    ft, fs = sequential_firings(order, interval, 40 * n, t0=0.013, jitter=jitter, rng=rng)
    fv = _values(rng, fs, p_same)
    dp = max_gap * (interval - jitter)  # longest poll interval
    pt = ft[0] - 0.5 * dp + np.cumsum(rng.uniform(0.3, 1.0, int(ft[-1] / (0.3 * dp)) + 2) * dp)
    pt = pt[pt < ft[-1]]  # the schedule (A1) ends with the last true firing
    log = simulate_polls(ft, fs, fv, pt, n)
    poller = SonarPoller(order, interval, (interval - jitter) if know_min else 0.0)
    firings, before_anchor = [], None
    for j in range(len(log)):
        firings += poller.feed(float(log.t[j]), log.values[j])
        if before_anchor is None and poller.last_known is not None:
            before_anchor = len(firings) - sum(1 for f in firings if f.poll == j)
    got = StampedFirings.from_firings(firings)
    idx = _true_index(ft, fs, got.sensor, log.t[got.poll])
    # Every stamp's interval holds the true firing time, with the true value.
    assert np.all(got.t_low <= ft[idx] + 1e-9)
    assert np.all(ft[idx] <= got.t_high + 1e-9)
    np.testing.assert_array_equal(got.value, fv[idx])
    assert np.all(np.abs(got.t - ft[idx]) <= got.error_bound + 1e-9)
    assert len(np.unique(idx)) == len(idx)  # no firing stamped twice
    assert poller.contradictions == 0
    # Every firing whose value changed is found; after the anchor, every firing in between too
    # (the repeats a naive host misses).
    previous = np.full(n, np.nan)
    changed = np.zeros(len(ft), dtype=bool)
    for k in range(len(ft)):
        changed[k] = fv[k] != previous[fs[k]]
        previous[fs[k]] = fv[k]
    seen_changes = np.flatnonzero(changed & (ft <= pt[-1]) & (ft > pt[0]))
    assert set(seen_changes.tolist()) <= set(idx.tolist())
    if before_anchor is not None and before_anchor < len(idx):
        tail = idx[before_anchor:]
        np.testing.assert_array_equal(tail, np.arange(tail[0], tail[0] + len(tail)))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(2, 12), interval=st.floats(0.005, 0.2),
       gap_frac=st.floats(0.05, 0.95), p_same=st.floats(0.0, 0.6), know_min=st.booleans())
def test_polling_recovers_fixed_period_firings(seed: int, n: int, interval: float,
                                               gap_frac: float, p_same: float,
                                               know_min: bool) -> None:
    # Fixed period (timeout = period): exact while polls come every < n - 1 firings.
    _check_recovery(seed, n, interval, 0.0, gap_frac * (n - 1), p_same, know_min)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(4, 10), interval=st.floats(0.01, 0.1),
       jitter_frac=st.floats(0.0, 0.05), gap_frac=st.floats(0.05, 0.5),
       p_same=st.floats(0.0, 0.3), know_min=st.booleans())
def test_polling_bounds_hold_with_jittery_intervals(seed: int, n: int, interval: float,
                                                    jitter_frac: float, gap_frac: float,
                                                    p_same: float, know_min: bool) -> None:
    # Intervals in [0.95, 1] x timeout: a run of unchanged values widens the bounds slowly.
    _check_recovery(seed, n, interval, jitter_frac * interval, gap_frac * (n - 1), p_same,
                    know_min)


@pytest.mark.parametrize(("seed", "n", "poll_frac", "p_same"),
                         [(0, 8, 0.3, 0.3), (1, 16, 0.05, 0.3), (2, 8, 3.0, 0.2),
                          (3, 4, 1.5, 0.0)])
def test_naive_stamps_err_more_than_polling_on_average(seed: int, n: int, poll_frac: float,
                                                       p_same: float) -> None:
    rng = np.random.default_rng(seed)
    interval = 0.04
    ft, fs = sequential_firings(np.arange(n), interval, 100 * n)
    fv = _values(rng, fs, p_same)
    # Polls at a random phase and with uneven gaps, so that firings do not fall on polls.
    dp = poll_frac * interval
    pt = np.cumsum(rng.uniform(0.5, 1.0, int(ft[-1] / (0.5 * dp))) * dp)
    pt = pt[pt < ft[-1]]
    log = simulate_polls(ft, fs, fv, pt, n)
    error = []
    for firings in (poll_firings(log, np.arange(n), interval), naive_firings(log)):
        idx = _true_index(ft, fs, firings.sensor, log.t[firings.poll])
        error.append(dict(zip(idx.tolist(), np.abs(firings.t - ft[idx]).tolist(), strict=True)))
    common = sorted(set(error[0]) & set(error[1]))
    assert len(common) > 50
    polled = np.mean([error[0][k] for k in common])
    naive = np.mean([error[1][k] for k in common])
    assert polled < naive
    if p_same > 0:  # polling also stamps the repeats the naive host never sees
        assert len(error[0]) > len(error[1])


def test_readings_from_firings_places_sensors_by_mount_and_pose() -> None:
    # Robot moving along +x at 1 m/s, facing +y; sensors at (0.1, 0.2) and (0, -0.2).
    polls = [(0.0, [NAN, NAN]), (0.2, [1500.0, NAN]), (0.4, [1500.0, 5110.0]),
             (0.6, [900.0, 5110.0])]
    m = len(polls)
    t = np.array([p for p, _ in polls])
    log = PolledLog(t=t, values=[v for _, v in polls], x=t * 1.0, y=np.zeros(m),
                    heading=np.full(m, math.pi / 2))
    mounts = [[0.1, 0.2, 0.3], [0.0, -0.2, -1.0]]
    out = poll_readings(log, [0, 1], timeout=0.25, mounts=mounts, value_scale=0.001,
                        no_echo=5110.0)
    b = out.batch
    # s0 fired in [0, 0.2] (stamp 0.1, robot at x = 0.1); s1 fired between, no echo; s0 in
    # [0.4, 0.6] (changed), stamp 0.5.
    assert b.sensor.tolist() == [0, 0]
    np.testing.assert_allclose(b.t, [0.1, 0.5])
    # Heading π/2: the robot's forward axis is +y, its left is -x.
    np.testing.assert_allclose(b.x, [0.1 - 0.2, 0.5 - 0.2])
    np.testing.assert_allclose(b.y, [0.1, 0.1])
    np.testing.assert_allclose(b.theta, math.pi / 2 + 0.3)
    np.testing.assert_allclose(b.range, [1.5, 0.9])
    np.testing.assert_allclose(out.stamp_error, [0.1, 0.1])
    naive = naive_stamps(log, mounts, value_scale=0.001, no_echo=5110.0)
    np.testing.assert_allclose(naive.batch.t, [0.2, 0.6])
    assert np.all(np.isnan(naive.stamp_error))


def test_stamp_bounds_take_the_largest_bound_and_naive_stamps_have_none() -> None:
    # The log of the test above: two readings, each stamped to within 0.1 s.
    polls = [(0.0, [NAN, NAN]), (0.2, [1500.0, NAN]), (0.4, [1500.0, 5110.0]),
             (0.6, [900.0, 5110.0])]
    t = np.array([p for p, _ in polls])
    log = PolledLog(t=t, values=[v for _, v in polls], x=t * 1.0, y=np.zeros(len(t)),
                    heading=np.full(len(t), math.pi / 2))
    mounts = [[0.1, 0.2, 0.3], [0.0, -0.2, -1.0]]
    out = poll_readings(log, [0, 1], timeout=0.25, mounts=mounts, value_scale=0.001,
                        no_echo=5110.0)
    # 0.1 s at 1 m/s and 0.5 rad/s, the sensor 0.2236 m out: 0.1 (1 + 0.5 * 0.2236) m, 0.05 rad.
    position, heading = out.stamp_bounds(1.0, turn_rate=0.5, sensor_offset=math.hypot(0.1, 0.2))
    assert position == pytest.approx(0.1 * (1.0 + 0.5 * math.hypot(0.1, 0.2)))
    assert heading == pytest.approx(0.05)
    wider = PolledReadings(out.batch, np.array([0.1, 0.3]), out.firing)
    assert wider.stamp_bounds(1.0) == pytest.approx((0.3, 0.0))  # the largest, not the mean
    naive = naive_stamps(log, mounts, value_scale=0.001, no_echo=5110.0)
    with pytest.raises(PollingError, match="no stamp error bound"):
        naive.stamp_bounds(1.0)
    unbounded = PolledReadings(out.batch, np.array([0.1, np.inf]), out.firing)
    with pytest.raises(PollingError, match="no finite bound"):  # inf is not "unknown"
        unbounded.stamp_bounds(1.0)
    for bad in ({"speed": math.nan}, {"speed": -1.0}, {"speed": 1.0, "turn_rate": math.inf},
                {"speed": 1.0, "sensor_offset": -0.2}):
        with pytest.raises(PollingError, match="must be finite and >= 0"):
            out.stamp_bounds(**bad)


def test_pose_interpolation_turns_the_short_way_across_pi() -> None:
    poller = SonarPoller([0], timeout=1.0)
    poller.feed(0.0, [1.0], (0.0, 0.0, math.pi - 0.1))
    (f,) = poller.feed(0.2, [2.0], (2.0, 0.0, -math.pi + 0.1))
    assert f.t == pytest.approx(0.1)
    assert f.x == pytest.approx(1.0)
    assert math.cos(f.heading) == pytest.approx(-1.0)  # half way is π, not 0


def test_error_bound_helpers() -> None:
    np.testing.assert_allclose(position_error_bound([0.0, 0.1], speed=0.5), [0.0, 0.05])
    np.testing.assert_allclose(
        position_error_bound(0.1, speed=0.5, turn_rate=-2.0, sensor_offset=0.2), 0.05 + 0.04)
    np.testing.assert_allclose(heading_error_bound(0.1, turn_rate=-2.0), 0.2)


def test_simulated_polls_show_latest_values() -> None:
    log = simulate_polls([0.1, 0.2, 0.3], [0, 1, 0], [5.0, 6.0, 5.0], [0.05, 0.1, 0.25, 0.4], 2)
    np.testing.assert_array_equal(log.values, [[NAN, NAN], [5, NAN], [5, 6], [5, 6]])
    t, s = sequential_firings([2, 0], [0.1, 0.5, 0.3], 4, t0=1.0)
    np.testing.assert_allclose(t, [1.0, 1.3, 1.4, 1.7])  # after 2 wait 0.3, after 0 wait 0.1
    assert s.tolist() == [2, 0, 2, 0]


@pytest.mark.parametrize(("make", "text"), [
    (lambda: SonarPoller([0, 0], 0.1), "distinct sensor indices"),
    (lambda: SonarPoller([0, 1], 0.0), "timeouts must be finite and > 0"),
    (lambda: SonarPoller([0, 1], [0.1]), "one per sensor"),
    (lambda: SonarPoller([0, 1], 0.1, min_interval=0.2), "min_interval must lie"),
    (lambda: PolledLog(t=[0, 1], values=[[1]], x=[0, 0], y=[0, 0], heading=[0, 0]),
     "values must have shape"),
    (lambda: PolledLog(t=[0, 0], values=[[1], [1]], x=[0, 0], y=[0, 0], heading=[0, 0]),
     "strictly increasing"),
    (lambda: readings_from_firings(naive_firings(_log([(0, [1, 1]), (1, [2, 2])])), [[0, 0, 0]]),
     "mounts has 1 rows"),
])
def test_bad_parameters_raise_polling_errors(make: object, text: str) -> None:
    with pytest.raises(PollingError, match=text):
        make()  # type: ignore[operator]


def test_poll_time_must_increase_and_values_keep_their_length() -> None:
    poller = SonarPoller([0, 1], 0.1)
    poller.feed(1.0, [1, 2])
    with pytest.raises(PollingError, match="not after the previous poll"):
        poller.feed(1.0, [1, 2])
    with pytest.raises(PollingError, match="3 values, expected 2"):
        poller.feed(2.0, [1, 2, 3])


def test_l_s_own_sensor_changing_again_is_a_whole_cycle() -> None:
    # Order 0, 1; timeout 0.1. Sensor 0 fired in (0, 0.04]: it is l. At 0.2 only sensor 0 has
    # changed again, so sensor 1 fired in between (with its old value) and then sensor 0:
    # T1 in [T_l, T_l + 0.1] = [0, 0.14]; T2 in (0.04, 0.2] and T2 <= T1 + 0.1 = 0.24.
    got = _feed(SonarPoller([0, 1], timeout=0.1),
                [(0.0, [1.0, 2.0]), (0.04, [1.5, 2.0]), (0.2, [1.7, 2.0])])
    assert got == [[], [(0, "CHANGED", 0.0, 0.04, 1.5)],
                   [(1, "BETWEEN", 0.0, 0.14, 2.0), (0, "CHANGED", 0.04, 0.2, 1.7)]]


def test_stamped_firing_error_bound_is_half_its_interval() -> None:
    poller = SonarPoller([0, 1], timeout=0.1)
    poller.feed(0.0, [1.0, 2.0])
    (f,) = poller.feed(0.04, [1.5, 2.0])
    assert (f.t_low, f.t_high) == (0.0, 0.04)
    assert f.error_bound == pytest.approx(0.02)


def test_readings_come_out_in_time_order_with_their_firing_index() -> None:
    # Firings listed out of time order (as a caller may build them): the readings are sorted by
    # stamp, and `firing` still names each one's row in the firings.
    firings = StampedFirings(
        sensor=np.array([0, 1, 0]), value=np.array([1.0, 2.0, 3.0]), t=np.array([0.3, 0.1, 0.2]),
        t_low=np.array([0.25, 0.05, 0.15]), t_high=np.array([0.35, 0.15, 0.25]),
        cause=np.zeros(3, dtype=np.int8), poll=np.array([3, 1, 2]), x=np.zeros(3),
        y=np.zeros(3), heading=np.zeros(3))
    out = readings_from_firings(firings, [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert out.batch.t.tolist() == [0.1, 0.2, 0.3]
    assert out.firing.tolist() == [1, 2, 0]
    assert out.batch.range.tolist() == [2.0, 3.0, 1.0]
    np.testing.assert_allclose(out.stamp_error, [0.05, 0.05, 0.05])


def test_sequential_firings_refuse_a_zero_gap() -> None:
    # Two firings at the same instant break "one at a time" (A1).
    with pytest.raises(PollingError, match="must stay > 0"):
        sequential_firings([0, 1], [0.1, 0.0], 4)
    t, sensor = sequential_firings([0, 1], [0.1, 0.2], 4, t0=1.0)
    np.testing.assert_allclose(t, [1.0, 1.1, 1.3, 1.4])
    assert sensor.tolist() == [0, 1, 0, 1]
