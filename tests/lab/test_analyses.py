"""Analyses of recorded runs on hand-made inputs: removal shares, Fig. 13's rule, openings."""

from __future__ import annotations

import numpy as np
import pytest

from sonarcarve.geometry import ArcFate
from sonarcarve.lab.analyses import fig13_keep, first_reading_within, removal_summary
from sonarcarve.lab.instrument import ArcTable
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import PointSource
from sonarcarve.sim.sonar import EchoKind


def _table(removal: list[int]) -> ArcTable:
    n = len(removal)
    return ArcTable(
        sample=np.full(n, -1), reading_id=np.arange(n), range=np.ones(n),
        alive=np.array([r == ArcFate.ALIVE for r in removal]), processed=np.ones(n, bool),
        xy=np.zeros((n, 2)), width=np.zeros(n), max_error=np.zeros(n),
        source=np.zeros(n, np.int8), removal=np.array(removal, dtype=np.int8))


def test_removal_summary_by_hand() -> None:
    f, s, n = ArcFate.FULLY_CARVED, ArcFate.SPLIT, ArcFate.ALIVE
    d, x, fl = EchoKind.DIRECT, EchoKind.CROSSTALK, EchoKind.FLOOR
    final = _table([f, n, s, f, n, f])
    kind = np.array([d, d, d, x, fl, d])
    out = removal_summary(final, kind)
    assert out["share"] == pytest.approx(50.0)  # 3 of 6 fully carved
    assert out["split_share"] == pytest.approx(100 / 6)
    assert out["spurious_removed"] == pytest.approx(50.0)  # crosstalk yes, floor no
    assert out["true_lost"] == pytest.approx(50.0)  # 2 of the 4 direct readings
    assert out["spurious_of_removed"] == pytest.approx(100 / 3)
    assert out["true_lost_or_split"] == pytest.approx(75.0)
    assert out["spurious_readings"] == pytest.approx(100 / 3)


def test_removal_summary_follows_reading_ids() -> None:
    # Rows out of reading order must be matched to their own reading's kind.
    final = _table([ArcFate.FULLY_CARVED, ArcFate.ALIVE])
    final = final.select(np.array([1, 0]))
    kind = np.array([EchoKind.MULTIPATH, EchoKind.DIRECT])
    out = removal_summary(final, kind)
    assert out["spurious_removed"] == pytest.approx(100.0)
    assert out["true_lost"] == pytest.approx(0.0)


def test_fig13_keeps_atm_medians_and_bounded_carved_points() -> None:
    source = np.array([PointSource.ATM, PointSource.CENTERLINE, PointSource.CARVED],
                      dtype=np.int8)
    max_error = np.array([0.14, 0.01, 0.2])
    assert fig13_keep(source, max_error, "atm", 0.1).tolist() == [True, False, False]
    assert fig13_keep(source, max_error, "carve", 0.1).tolist() == [False, True, False]


def test_opening_distance_is_measured_along_the_drive() -> None:
    # Head-on drive from the origin towards a door centred on (0, 4.5).
    sim = run_simulation(Scenario("doorway:0.8", 0, path=((0.0, 0.0), (0.0, 3.7))))
    gap = sim.world.openings[0].tolist()
    stop = first_reading_within(sim, gap, 2.0)
    assert stop > 1
    y = sim.trajectory.pose_at(sim.readings.t[[stop - 2, stop - 1]])[1]
    assert y[0] < 4.5 - 2.0 <= y[1]
    assert first_reading_within(sim, gap, 0.1) == 0  # the drive stops 0.8 m short
