import math

import numpy as np
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
