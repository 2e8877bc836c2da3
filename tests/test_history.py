import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sonarcarve.history import SonarHistory
from sonarcarve.readings import Reading


def _reading(k: int) -> Reading:
    return Reading(t=float(k), sensor=k % 16, x=0.1 * k, y=0.0, theta=0.0, range=1.0 + k)


@settings(max_examples=60, deadline=None)
@given(capacity=st.integers(1, 12), count=st.integers(0, 60))
def test_ring_buffer_keeps_the_newest_n_in_order(capacity: int, count: int) -> None:
    history = SonarHistory(capacity)
    for k in range(count):
        history.append(_reading(k), k, math.radians(22.5))
    live = history.reading_id[history.slots()].tolist()
    assert live == list(range(max(0, count - capacity), count))
    assert len(history) == min(count, capacity)


@settings(max_examples=60, deadline=None)
@given(capacity=st.integers(1, 10), count=st.integers(0, 80))
def test_every_arc_is_evicted_once_in_arrival_order(capacity: int, count: int) -> None:
    evicted: list[int] = []
    history = SonarHistory(capacity)
    history._on_evict = lambda slots: evicted.extend(history.reading_id[slots].tolist())
    for k in range(count):
        history.append(_reading(k), k, 0.4)
        # Retired arcs reach the hook no later than `capacity` appends after they left.
        assert len(evicted) >= max(0, k + 1 - 2 * capacity)
    history.flush_retired()
    assert evicted == list(range(max(0, count - capacity)))
    history.flush()
    assert evicted == list(range(count))


def test_retired_rows_stay_frozen_until_committed() -> None:
    seen: list[float] = []
    history = SonarHistory(3)
    history._on_evict = lambda slots: seen.extend(history.r[slots].tolist())
    for k in range(7):
        history.append(_reading(k), k, 0.4)
    # Rows are reused after 2 * capacity appends; each arc must reach the hook with its own values.
    history.flush()
    assert seen == [1.0 + k for k in range(7)]


def test_full_beam_is_stored_as_theta_minus_plus_half_width() -> None:
    history = SonarHistory(4)
    slot = history.append(Reading(0.0, 0, 1.0, 2.0, 0.5, 3.0), 0, 0.2)
    assert history.theta1[slot] == 0.5 - 0.1
    assert history.theta2[slot] == 0.5 + 0.1


def test_memory_does_not_grow_with_the_log() -> None:
    history = SonarHistory(5)
    sizes = {history.x.nbytes}
    for k in range(200):
        history.append(_reading(k), k, 0.4)
        sizes.add(history.x.nbytes)
    assert sizes == {np.zeros(10).nbytes}


def _arrays(ids: range) -> dict[str, np.ndarray]:
    """append_many's columns for readings ``ids`` as :func:`_reading` makes them."""
    k = np.array(ids, dtype=np.float64)
    return {"x": 0.1 * k, "y": np.zeros(len(k)), "r": 1.0 + k, "theta": np.zeros(len(k)),
            "t": k, "sensor": np.array(ids, dtype=np.int64) % 16,
            "beam_width": np.full(len(k), 0.4)}


def test_append_many_across_the_end_of_the_storage_numbers_every_arc() -> None:
    # Capacity 3: storage of 6 rows. 4 arcs one by one (slots 0-3); arc 0 has retired. A block
    # of 3 then fills slots 4, 5 and, wrapping, 0: ids 4, 5, 6 whichever part they land in.
    evicted: list[int] = []
    history = SonarHistory(3)
    history._on_evict = lambda slots: evicted.extend(history.reading_id[slots].tolist())
    for k in range(4):
        history.append(_reading(k), k, 0.4)
    history.commit_for_room()  # room 2: nothing to commit yet
    assert (evicted, history.room()) == ([], 2)
    history.flush_retired()
    assert (evicted, history.room()) == ([0], 3)
    history.append_many(**_arrays(range(4, 7)), first_id=4)
    assert history.reading_id.tolist() == [6, 1, 2, 3, 4, 5]
    assert history.r.tolist() == [7.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    assert history.theta2.tolist() == [0.2] * 6
    assert history.reading_id[history.slots()].tolist() == [4, 5, 6]
    assert history.room() == 0
    history.commit_for_room()  # arcs 1, 2, 3 have retired too (3 live of 7 appended)
    assert evicted == [0, 1, 2, 3]
    assert history.room() == 3


def test_append_many_refuses_more_arcs_than_room() -> None:
    history = SonarHistory(2)  # storage of 4 rows
    history.append_many(**_arrays(range(3)), first_id=0)
    assert history.room() == 1
    with pytest.raises(ValueError, match="append_many of 2 arcs with room for 1"):
        history.append_many(**_arrays(range(3, 5)), first_id=3)
    assert history.appended == 3


def test_window_is_the_live_arcs_right_after_an_arc_was_appended() -> None:
    history = SonarHistory(3)
    for k in range(5):
        history.append(_reading(k), k, 0.4)
    ids = history.reading_id
    assert ids[history.window(0)].tolist() == [0]
    assert ids[history.window(1)].tolist() == [0, 1]
    assert ids[history.window(3)].tolist() == [1, 2, 3]
    assert ids[history.window(4)].tolist() == [2, 3, 4]


COLUMNS = ("x", "y", "r", "theta", "theta1", "theta2", "t", "beam_width", "sensor", "reading_id")


@settings(max_examples=40, deadline=None)
@given(capacity=st.integers(1, 9), blocks=st.lists(st.integers(1, 9), min_size=1, max_size=12),
       seed=st.integers(0, 2**16))
def test_append_many_writes_every_row_as_append_does(capacity: int, blocks: list[int],
                                                     seed: int) -> None:
    # Blocks that fit and blocks that wrap the storage (review rev16: since 032b09a a block that
    # fits is written with its columns unsliced, one that wraps in two parts), every column of
    # every row against one append per reading, with widths, bearings and ids that differ.
    rng = np.random.default_rng(seed)
    one, many = SonarHistory(capacity), SonarHistory(capacity)
    next_id = 5
    for size in blocks:
        many.commit_for_room()
        many.flush_retired()
        n = min(size, many.room())
        cols = {"x": rng.normal(size=n), "y": rng.normal(size=n),
                "r": rng.uniform(0.1, 5.0, n), "theta": rng.uniform(-3.0, 3.0, n),
                "t": np.sort(rng.uniform(0.0, 9.0, n)), "sensor": rng.integers(0, 16, n),
                "beam_width": rng.uniform(0.1, 1.0, n)}
        many.append_many(**cols, first_id=next_id)
        for k in range(n):
            one.append(Reading(t=float(cols["t"][k]), sensor=int(cols["sensor"][k]),
                               x=float(cols["x"][k]), y=float(cols["y"][k]),
                               theta=float(cols["theta"][k]), range=float(cols["r"][k])),
                       next_id + k, float(cols["beam_width"][k]))
        next_id += n
        one.flush_retired()
        assert many.appended == one.appended
        for name in COLUMNS:
            np.testing.assert_array_equal(getattr(many, name)[many.slots()],
                                          getattr(one, name)[one.slots()], err_msg=name)


def test_append_many_takes_columns_with_a_step() -> None:
    # A batch sliced with a step hands append_many columns that are not contiguous (the
    # compiled store takes any layout): the rows are those of the same values contiguous.
    rng = np.random.default_rng(3)
    cols = {"x": rng.normal(size=14), "y": rng.normal(size=14), "r": rng.uniform(0.1, 5.0, 14),
            "theta": rng.uniform(-3.0, 3.0, 14), "t": np.arange(14.0),
            "sensor": rng.integers(0, 16, 14), "beam_width": rng.uniform(0.1, 1.0, 14)}
    stepped, plain = SonarHistory(4), SonarHistory(4)
    stepped.append_many(**{k: v[::2] for k, v in cols.items()}, first_id=3)
    plain.append_many(**{k: v[::2].copy() for k, v in cols.items()}, first_id=3)
    for name in COLUMNS:
        np.testing.assert_array_equal(getattr(stepped, name), getattr(plain, name),
                                      err_msg=name)
    assert plain.reading_id.tolist() == [3, 4, 5, 6, 7, 8, 9, -1]
    theta, width = cols["theta"][::2], cols["beam_width"][::2]
    np.testing.assert_array_equal(plain.theta1[:7], theta - 0.5 * width)
    np.testing.assert_array_equal(plain.theta2[:7], theta + 0.5 * width)
