"""Split arcs are labelled split, fully carved arcs fully carved, everywhere a fate is reported.

The scene is worked out by hand (the same geometry as ``arc_remainder``'s doctest): an arc of
radius 2 about the origin over bearings [-0.4, 0.4], then a reading from (1, 0) along +x with a
0.1 rad beam and a 5 m range. The beam's edges leave (1, 0) at ±0.05 rad and cross the circle
near bearings ±0.025 (2 sin τ = tan 0.05 (2 cos τ - 1) gives τ ≈ 0.0251), and the whole arc is
nearer to (1, 0) than 5 m, so the freespace takes a thin slice out of the arc's middle: two
pieces remain, and the arc is split (paper, section 3), not fully carved.
"""

from __future__ import annotations

import pytest

from sonarcarve.geometry import ArcFate
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.methods.base import Estimates
from sonarcarve.readings import Reading
from sonarcarve.typing import SlotArray

WIDE_ARC = Reading(0.0, 0, 0.0, 0.0, 0.0, 2.0, 0.8)
THIN_BEAM = Reading(1.0, 1, 1.0, 0.0, 0.0, 5.0, 0.1)
# From the same place as WIDE_ARC, farther and wider: the freespace covers the whole arc.
COVERING = Reading(1.0, 1, 0.0, 0.0, 0.0, 3.0, 1.0)


@pytest.mark.parametrize("name", ["carve", "combined"])
@pytest.mark.parametrize(("newer", "fate", "counts"), [
    (THIN_BEAM, ArcFate.SPLIT, {"split": 1, "fully_carved": 0}),
    (COVERING, ArcFate.FULLY_CARVED, {"split": 0, "fully_carved": 1}),
])
def test_the_fate_label_and_counters_name_the_cause(
    name: str, newer: Reading, fate: ArcFate, counts: dict[str, int]
) -> None:
    method = make_method(name, MethodConfig(history_size=5, range_tolerance=0.0))
    committed: dict[int, int] = {}

    def record(history: object, slots: SlotArray, est: Estimates) -> None:
        assert est.fate is not None
        ids = method.history.reading_id[slots].tolist()
        committed.update(zip(ids, est.fate.tolist(), strict=True))

    method.add_commit_listener(record)
    method.add(WIDE_ARC)
    method.add(newer)
    est = method.estimates(method.history.slots())
    assert est.fate is not None
    assert est.fate.tolist() == [fate, ArcFate.ALIVE]
    assert est.alive.tolist() == [False, True]
    measures = method.measures()
    assert (measures.split, measures.fully_carved) == (counts["split"], counts["fully_carved"])
    assert method.local_map().reading_id.tolist() == [1]
    method.finish()
    assert committed == {0: fate, 1: ArcFate.ALIVE}


def test_the_split_scene_really_splits() -> None:
    """The scene's premise, from the closed form (independent of the methods' bookkeeping)."""
    from sonarcarve.geometry import arc_remainder

    pieces = arc_remainder(0.0, 0.0, 2.0, -0.4, 0.4, 1.0, 0.0, 5.0, -0.05, 0.05)
    assert pieces.shape == (2, 2)
    assert pieces[0, 1] == pytest.approx(-0.0251, abs=1e-4)
    assert pieces[1, 0] == pytest.approx(0.0251, abs=1e-4)
