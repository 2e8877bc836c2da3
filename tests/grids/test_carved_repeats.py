"""The carved grid's repeat rule: an echo that repeats its sensor's previous echo (the sensor
moved towards or away from one reflector) makes the earlier arc count
:attr:`CarvedGridParams.repeat_weight` (values computed by hand)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry.repeats import is_repeat
from sonarcarve.grids import OCCUPIED, CarvedGrid, CarvedGridParams, GridError
from sonarcarve.grids.carved import DEFAULT_SPREAD_LENGTH
from sonarcarve.grids.carved.repeats import repeat_kernel
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch, ReadingsError

H = 0.05
BOUNDS = (-0.5, -1.5, 3.5, 1.5)
L_HIT = math.log(0.7 / 0.3)
PHI = DEFAULT_BEAM_WIDTH
HALF = PHI / 2
TOL = 0.05

pytestmark = pytest.mark.usefixtures("carving_alone_under_the_grid")


def _repeat(p1: tuple[float, float], r1: float, t1: float, p2: tuple[float, float], r2: float,
            t2: float) -> bool:
    return bool(is_repeat(p1[0], p1[1], r1, t1, HALF, p2[0], p2[1], r2, t2, HALF, TOL))


def test_which_echo_pairs_repeat() -> None:
    # Driving 0.25 m straight at a post 2 m ahead: the range shrinks by the distance driven.
    assert _repeat((0.0, 0.0), 2.0, 0.0, (0.25, 0.0), 1.75, 0.0)
    # ... within the tolerance (0.04 off), and a post 0.3 m off the track (range 1.7758).
    assert _repeat((0.0, 0.0), 2.0, 0.0, (0.25, 0.0), 1.79, 0.0)
    assert _repeat((0.0, 0.0), math.hypot(2.0, 0.3), 0.0, (0.25, 0.0), math.hypot(1.75, 0.3),
                   0.0)
    # Driving away from it, the sensor looking back: the same, the other way round.
    assert _repeat((0.0, 0.0), 1.75, math.pi, (0.25, 0.0), 2.0, math.pi)
    # Driving 0.11 m at it (just over 2ε = 0.10 m): still a repeat.
    assert _repeat((0.0, 0.0), 2.0, 0.0, (0.11, 0.0), 1.89, 0.0)
    # Not a repeat: the range changed by 0.06 more than the distance driven ...
    assert not _repeat((0.0, 0.0), 2.0, 0.0, (0.25, 0.0), 1.69, 0.0)
    # ... a side sensor driving along a wall (the same range from 0.25 m further on: the two
    # echoes come from two points of the wall 0.25 m apart) ...
    assert not _repeat((0.0, 0.0), 1.0, math.pi / 2, (0.25, 0.0), 1.0, math.pi / 2)
    # ... the range shrank by the distance driven, but the sensor looks 45° off the track: the
    # circles touch on the track, outside its beam (they cross inside it, at one point) ...
    assert not _repeat((0.0, 0.0), 2.0, math.pi / 4, (0.25, 0.0), 1.75, math.pi / 4)
    # ... origins 2ε = 0.10 m apart or nearer: any range change fits, so no repeat, whether
    # the sensor drove at the post, stood still, or crept along a wall ...
    assert not _repeat((0.0, 0.0), 2.0, 0.0, (0.1, 0.0), 1.9, 0.0)
    assert not _repeat((0.0, 0.0), 2.0, 0.0, (0.0, 0.0), 2.0, 0.0)
    assert not _repeat((0.0, 0.0), 1.0, math.pi / 2, (0.03, 0.0), 1.0, math.pi / 2)
    # ... and standing still with another range.
    assert not _repeat((0.0, 0.0), 2.0, 0.0, (0.0, 0.0), 1.9, 0.0)


def _creeping_ring(step: float) -> list[Reading]:
    """A 16-sonar ring driving along a corridor (walls at y = ±1 m) ``step`` metres a ring
    cycle, 40 ms a sonar; beyond 3 m a sonar hears nothing."""
    rng = np.random.default_rng(0)
    readings, x, k = [], 0.0, 0
    while x < 5.0:
        for sensor in range(16):
            theta = sensor * 2 * math.pi / 16
            s = math.sin(theta)
            r = (1.0 / abs(s) if abs(s) > 1e-9 else math.inf) + float(rng.normal(0.0, 0.005))
            readings.append(Reading(t=0.04 * k, sensor=sensor, x=x, y=0.0, theta=theta,
                                    range=r if r <= 3.0 else math.inf, max_range=3.0))
            k += 1
        x += step
    return readings


def _wall_columns_marked(readings: list[Reading], repeat_weight: float) -> int:
    grid = CarvedGrid(0.05, (-0.5, -1.5, 6.5, 1.5),
                      params=CarvedGridParams(repeat_weight=repeat_weight))
    for start in range(0, len(readings), 8):
        grid.add_many(ReadingBatch.from_readings(readings[start:start + 8]))
    xs, ys = grid.cell_centers()
    rows, cols = np.abs(ys - 1.0) <= 0.1, (xs > 0.5) & (xs < 4.0)
    return int((grid.trinary()[np.ix_(rows, cols)] == OCCUPIED).any(axis=0).sum())


@pytest.mark.parametrize("step", [0.02, 0.03, 0.045, 0.1])
def test_a_robot_creeping_along_a_wall_keeps_the_wall(step: float) -> None:
    """Every side sensor of a ring creeping along a wall hears the same range from origins
    ``step`` apart. Found in review: with a "stood still" repeat case (origins within ε, the
    same range), at 2-4.5 cm a cycle each echo repeated the one before, every arc but the
    newest counted nothing, and the side wall was never marked (0 of 70 columns, against 17-70
    with the rule off). The rule must mark as much of the wall as counting every echo does."""
    readings = _creeping_ring(step)
    with_rule = _wall_columns_marked(readings, 0.0)
    assert with_rule > 0
    assert with_rule >= _wall_columns_marked(readings, 1.0)


# -- one sensor driving at a corner beside a gap ------------------------------------------------

#: A corner (a door's jamb) 0.25 m left of the track of sensor 0; the gap lies across the
#: track, where the corner's mirror image is: every circle through the corner centred on the
#: track passes through it too, so sensor 0 alone cannot tell the two apart.
CORNER = (2.5, 0.25)
MIRROR = (2.5, -0.25)


def _approach() -> list[Reading]:
    """Sensor 0 drives along y = 0 looking ahead (0.25 m a step, 5 steps) and hears the
    corner; sensor 1, 1.5 m to the left, looking 32° right, hears it from the side."""
    out = []
    for k in range(5):
        x = 0.25 * k
        out.append(Reading(float(k), 0, x, 0.0, 0.0, math.hypot(CORNER[0] - x, CORNER[1])))
        out.append(Reading(k + 0.5, 1, x, 1.5, math.radians(-32.0),
                           math.hypot(CORNER[0] - x, CORNER[1] - 1.5)))
    return out


def _near(grid: CarvedGrid, point: tuple[float, float], radius: float) -> np.ndarray:
    xs, ys = grid.cell_centers()
    cx, cy = np.meshgrid(xs, ys)
    return np.hypot(cx - point[0], cy - point[1]) < radius


@pytest.mark.parametrize("fresh", [False, True])
def test_a_sensor_driving_at_a_corner_leaves_the_gap_beside_it_open(fresh: bool) -> None:
    maps = {}
    for weight in (0.0, 1.0):
        grid = CarvedGrid(H, BOUNDS, params=CarvedGridParams(repeat_weight=weight,
                                                             fresh_arcs=fresh))
        grid.add_many(ReadingBatch.from_readings(_approach()))
        maps[weight] = grid.trinary()
        corner, mirror = _near(grid, CORNER, 0.05), _near(grid, MIRROR, 0.1)
    # Every echo of sensor 0 repeats the one before (its ranges shrink by the 0.25 m it drove:
    # 2.5125, 2.2638, 2.0156, 1.7678, 1.5207); summed, its five arcs mark the gap as well as
    # the corner. Counted once, the gap is left with the newest arc's spread value, and the
    # corner is marked by sensor 1, which hears it from the side: its echoes do not repeat
    # (the track lies outside its beam) and add up.
    assert np.any(maps[1.0][mirror] == OCCUPIED)
    assert not np.any(maps[0.0][mirror] == OCCUPIED)
    assert np.any(maps[0.0][corner] == OCCUPIED)


def _head_on(t: float, x: float, sensor: int = 0) -> Reading:
    """Sensor ``sensor`` at (x, 0) looking along +x at a wall 2 m from the origin."""
    return Reading(t, sensor, x, 0.0, 0.0, 2.0 - x)


@pytest.mark.parametrize("weight", [0.0, 0.25, 1.0])
def test_a_repeated_arc_counts_its_weight_live_and_when_it_leaves_the_history(
        weight: float) -> None:
    params = CarvedGridParams(repeat_weight=weight, fresh_arcs=False)
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=2)),
                      params=params)
    i, j = int(np.argmin(np.abs(grid.cell_centers()[1] - 0.025))), int(
        np.argmin(np.abs(grid.cell_centers()[0] - 1.975)))
    first = DEFAULT_SPREAD_LENGTH / (2.0 * PHI) * L_HIT  # s = L / (r φ), r = 2
    second = DEFAULT_SPREAD_LENGTH / (1.75 * PHI) * L_HIT  # r = 1.75
    grid.add_many(ReadingBatch.from_readings([_head_on(0.0, 0.0), _head_on(1.0, 0.25)]))
    # The cell (1.975, 0.025) lies on both arcs, in neither's free space.
    assert grid.live_log_odds[i, j] == pytest.approx(weight * first + second)
    # A reading behind pushes the first arc out of the history: final at its weight.
    grid.add(Reading(2.0, 1, 0.0, 0.0, math.pi, 0.3))
    assert grid.live_log_odds[i, j] == pytest.approx(second)
    assert grid.log_odds[i, j] == pytest.approx(weight * first + second, abs=1e-6)


def test_an_echo_repeats_any_earlier_echo_of_its_sensor_still_in_the_history() -> None:
    params = CarvedGridParams(fresh_arcs=False)
    first = DEFAULT_SPREAD_LENGTH / (2.0 * PHI) * L_HIT
    second = DEFAULT_SPREAD_LENGTH / (1.75 * PHI) * L_HIT
    between = [  # sensor 0 heard nothing, then heard something behind it (at π: carves nothing)
        Reading(0.4, 0, 0.1, 0.0, math.pi, math.inf, math.nan, 3.0),
        Reading(0.7, 0, 0.2, 0.0, math.pi, 0.3)]
    grid = CarvedGrid(H, BOUNDS, params=params)
    grid.add_many(ReadingBatch.from_readings([_head_on(0.0, 0.0), *between, _head_on(1.0, 0.25)]))
    i, j = int(np.argmin(np.abs(grid.cell_centers()[1] - 0.025))), int(
        np.argmin(np.abs(grid.cell_centers()[0] - 1.975)))
    assert grid.live_log_odds[i, j] == pytest.approx(second)  # the first counts nothing
    # A repeat heard after the first arc left the history (a history of 2 arcs: the echo
    # behind pushed it out) comes too late: the first arc was final, at its whole weight.
    grid = CarvedGrid(H, BOUNDS, method=make_method("carve", MethodConfig(history_size=2)),
                      params=params)
    grid.add_many(ReadingBatch.from_readings([_head_on(0.0, 0.0), *between, _head_on(1.0, 0.25)]))
    assert grid.log_odds[i, j] == pytest.approx(first + second, abs=1e-6)


# -- exactness with the rule on -----------------------------------------------------------------

def _approaching_ring(n: int, seed: int, no_echo: bool) -> list[Reading]:
    """A ring of 8 sensors driving at 0.3 m per ring cycle towards an end wall (x = 3.3 m)
    between side walls (y = ±1.2 m), with a post at (2.6, 0.3); ranges jittered. Sensor 0's
    echoes repeat one another (the post, then the wall)."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        sensor = k % 8
        x = -0.3 + 0.3 * (k // 8) % 2.4
        theta = sensor * math.pi / 4 + float(rng.normal(0.0, 0.02))
        c, s = math.cos(theta), math.sin(theta)
        hits = [d for d in ((1.2 / s) if s > 1e-9 else math.inf,
                            (-1.2 / s) if s < -1e-9 else math.inf,
                            ((3.3 - x) / c) if c > 1e-9 else math.inf) if d > 0]
        post = math.hypot(2.6 - x, 0.3)
        if abs(math.atan2(0.3, 2.6 - x) - theta) <= HALF:
            hits.append(post)
        r = min(hits) + float(rng.normal(0.0, 0.01))
        if no_echo and (r > 3.0 or rng.random() < 0.1):
            out.append(Reading(0.04 * k, sensor, x, 0.0, theta, math.inf, math.nan, 3.0))
        else:
            out.append(Reading(0.04 * k, sensor, x, 0.0, theta, min(r, 3.4)))
    return out


@pytest.mark.parametrize(("seed", "no_echo"), [(0, False), (1, True)])
def test_batches_and_reads_do_not_change_the_map_with_repeats(seed: int, no_echo: bool) -> None:
    readings = _approaching_ring(400, seed, no_echo)
    config = MethodConfig(history_size=30, max_incidence=math.radians(30.0))

    def grid(weight: float = 0.0) -> CarvedGrid:
        return CarvedGrid(H, BOUNDS, method=make_method("carve", config),
                          params=CarvedGridParams(repeat_weight=weight))

    whole = grid()  # one batch of 400, fed in chunks of the history's 30
    whole.add_many(ReadingBatch.from_readings(readings))
    pieces, single = grid(), grid()
    rng = np.random.default_rng(seed)
    start = 0
    while start < len(readings):
        size = int(rng.integers(1, 45))  # some batches longer than the history
        pieces.add_many(ReadingBatch.from_readings(readings[start:start + size]))
        pieces.refresh()
        start += size
    for reading in readings:
        single.add(reading)
    np.testing.assert_allclose(pieces.log_odds, whole.log_odds, rtol=0.0, atol=1e-5)
    np.testing.assert_allclose(single.log_odds, whole.log_odds, rtol=0.0, atol=1e-5)
    assert np.array_equal(pieces.trinary(), whole.trinary())
    # The rule acted on this stream: counting every echo gives another map.
    counted = grid(1.0)
    counted.add_many(ReadingBatch.from_readings(readings))
    assert np.abs(counted.log_odds - whole.log_odds).max() > 0.1


@pytest.mark.parametrize("bad", [-0.1, 1.5, math.nan, True, "0"])
def test_repeat_weight_must_lie_in_0_1(bad: object) -> None:
    with pytest.raises(GridError, match="repeat_weight"):
        CarvedGridParams(repeat_weight=bad)  # type: ignore[arg-type]


def test_a_bad_batch_marks_no_repeat() -> None:

    params = CarvedGridParams(fresh_arcs=False)
    clean, tried = CarvedGrid(H, BOUNDS, params=params), CarvedGrid(H, BOUNDS, params=params)
    for grid in (clean, tried):
        grid.add(_head_on(0.0, 0.0))
        grid.add(Reading(3.0, 1, 0.0, 0.0, math.pi, 0.3))  # behind, touches nothing
    # A repeat of the first echo, but from before the last reading: the method refuses it.
    with pytest.raises(ReadingsError):
        tried.add_many(ReadingBatch.from_readings([_head_on(1.0, 0.25)]))
    # The first arc keeps its whole weight: the next echo does not repeat it (0.5 m driven, 0.8
    # m nearer), and the cell (1.975, 0.025) is on the first arc alone.
    for grid in (clean, tried):
        grid.add(Reading(4.0, 0, 0.5, 0.0, 0.0, 1.2))
    assert np.array_equal(tried.log_odds, clean.log_odds)
    i, j = int(np.argmin(np.abs(clean.cell_centers()[1] - 0.025))), int(
        np.argmin(np.abs(clean.cell_centers()[0] - 1.975)))
    first = DEFAULT_SPREAD_LENGTH / (2.0 * PHI) * L_HIT
    assert tried.live_log_odds[i, j] == pytest.approx(first)


# -- the walk over each sensor's earlier arcs -------------------------------------------------


def _walk_over_every_arc(chain: np.ndarray, batch_chain: np.ndarray, seen_seq: np.ndarray,
                         marked: np.ndarray, seqs: np.ndarray, first: int, no_echo: np.ndarray,
                         sensor: np.ndarray, x: np.ndarray, y: np.ndarray, r: np.ndarray,
                         theta: np.ndarray, half: np.ndarray, hsensor: np.ndarray,
                         hx: np.ndarray, hy: np.ndarray, hr: np.ndarray, htheta: np.ndarray,
                         hwidth: np.ndarray, capacity: int, tol: float, factor: float) -> int:
    """The oracle: ``repeat_kernel``'s loop before c208a0f (``git show
    c208a0f^:src/sonarcarve/grids/carved/repeats.py``) in plain Python. Each echo tries every
    arc of its window, oldest first, whatever its sensor."""
    size = chain.shape[0]
    rows = np.empty(x.shape[0], dtype=np.int64)  # the row of the batch's arc first + i
    count = 0
    for k in range(x.shape[0]):
        if not no_echo[k]:
            rows[count] = k
            count += 1
    n_marked = 0
    for k in range(x.shape[0]):
        if no_echo[k]:
            continue
        for p in range(max(0, seqs[k] - capacity + 1), seqs[k]):
            if p >= first:
                j = rows[p - first]
                if sensor[j] != sensor[k] or batch_chain[p - first] == factor:
                    continue
                x1, y1, r1, t1, h1 = x[j], y[j], r[j], theta[j], half[j]
            else:
                s = p % size
                if hsensor[s] != sensor[k] or chain[s] == factor:
                    continue
                x1, y1, r1, t1, h1 = hx[s], hy[s], hr[s], htheta[s], 0.5 * hwidth[s]
            if not is_repeat(x1, y1, r1, t1, h1, x[k], y[k], r[k], theta[k], half[k], tol):
                continue
            if p >= first:
                batch_chain[p - first] = factor
            else:
                chain[p % size] = factor
                seen_seq[p % size] = -1
                marked[n_marked] = p % size
                n_marked += 1
    return n_marked


#: Sensor numbers of the random cases: small ones (the kernel looks a sensor's newest arc up in
#: an array), large ones and a mix (it scans back instead).
SENSOR_IDS = {"small": np.arange(6), "large": 10**8 + 3 + 10**8 * np.arange(6),
              "mixed": np.array([0, 1, 5, 2**31 - 1, 10**8 + 3, 70])}


def _arcs(rng: np.random.Generator, n: int, ids: np.ndarray, headings: np.ndarray,
          targets: np.ndarray) -> tuple[np.ndarray, ...]:
    """``n`` arcs ``(sensor, x, y, r, theta, width)``: each sensor drives along its heading
    towards its target, so that its echoes often repeat one another; one in five ranges is
    random, one in five beam widths not the default."""
    which = rng.integers(0, len(ids), n)
    dist = rng.uniform(0.3, 3.0, n)
    heading = headings[which]
    side = rng.normal(0.0, 0.02, n)
    x = targets[which, 0] - dist * np.cos(heading) - side * np.sin(heading)
    y = targets[which, 1] - dist * np.sin(heading) + side * np.cos(heading)
    r = np.where(rng.random(n) < 0.2, rng.uniform(0.3, 3.0, n), dist + rng.normal(0.0, 0.02, n))
    theta = heading + rng.normal(0.0, 0.05, n)
    width = np.where(rng.random(n) < 0.2, rng.uniform(0.1, 0.8, n), PHI)
    return ids[which], x, y, r, theta, width


def _walk_case(rng: np.random.Generator, ids: np.ndarray) -> dict[str, object]:
    """``repeat_kernel``'s arguments for a random batch after a random history (of a random
    capacity, after a random number of arcs: the ring of slots wraps), a fifth of the batch's
    readings no-echo ones, a sixth of the history's arcs already marked."""
    capacity = int(rng.integers(2, 13))
    size = 2 * capacity  # SonarHistory.storage_size
    first = int(rng.integers(0, 6 * capacity))  # arcs appended before the batch
    n = int(rng.integers(1, 3 * capacity))  # some batches longer than the history
    headings = rng.uniform(-math.pi, math.pi, len(ids))
    targets = rng.uniform(-3.0, 3.0, (len(ids), 2))
    no_echo = rng.random(n) < 0.2
    sensor, x, y, r, theta, width = _arcs(rng, n, ids, headings, targets)
    hsensor, hx, hy, hr, htheta, hwidth = _arcs(rng, size, ids, headings, targets)
    factor = float(rng.choice([0.0, 0.25]))
    return {"chain": np.where(rng.random(size) < 1 / 6, factor, 1.0),
            "batch_chain": np.ones(int(np.count_nonzero(~no_echo))),
            "seen_seq": rng.integers(0, 1000, size), "marked": np.full(capacity, -7),
            "seqs": first + np.cumsum(~no_echo) - 1, "first": first, "no_echo": no_echo,
            "sensor": sensor, "x": x, "y": y, "r": np.where(no_echo, math.inf, r),
            "theta": theta, "half": 0.5 * width, "hsensor": hsensor, "hx": hx, "hy": hy,
            "hr": hr, "htheta": htheta, "hwidth": hwidth, "capacity": capacity, "tol": TOL,
            "factor": factor}


@pytest.mark.parametrize("ids", sorted(SENSOR_IDS))
def test_the_walk_over_a_sensors_own_arcs_marks_what_the_walk_over_every_arc_marked(
        ids: str) -> None:
    rng = np.random.default_rng(sorted(SENSOR_IDS).index(ids))
    history_marks = batch_marks = 0
    for _ in range(300):
        case = _walk_case(rng, SENSOR_IDS[ids])
        new = {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in case.items()}
        old = {k: v.copy() if isinstance(v, np.ndarray) else v for k, v in case.items()}
        count = repeat_kernel(**new)
        assert count == _walk_over_every_arc(**old)
        for name in ("chain", "batch_chain", "seen_seq"):
            np.testing.assert_array_equal(new[name], old[name], err_msg=name)
        # The same slots, in another order (the walk goes newest first).
        assert sorted(new["marked"][:count]) == sorted(old["marked"][:count])
        history_marks += count
        batch_marks += int(np.count_nonzero(new["batch_chain"] != 1.0))
    # The cases exercise both kinds of marks, often.
    assert history_marks > 200
    assert batch_marks > 200
