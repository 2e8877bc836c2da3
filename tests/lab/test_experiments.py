"""Pieces of the experiments on hand-made inputs: path cutting, truth attribution, planning."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.lab.analyses import first_reading_within
from sonarcarve.lab.appendix import APPENDIX_EXPERIMENTS
from sonarcarve.lab.experiments import (
    EXPERIMENTS,
    ExperimentError,
    Scenario,
    Settings,
    cut_polyline,
    fig13_keep,
    removal_summary,
    run_experiments,
    run_simulation,
)
from sonarcarve.lab.instrument import ArcTable
from sonarcarve.maps import PointSource
from sonarcarve.methods.base import Removal
from sonarcarve.sim.sonar import EchoKind


def test_cut_polyline_by_hand() -> None:
    path = [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]
    np.testing.assert_allclose(cut_polyline(path, 1.0), [[0, 0], [1, 0]])
    np.testing.assert_allclose(cut_polyline(path, 3.0), [[0, 0], [3, 0]])
    np.testing.assert_allclose(cut_polyline(path, 5.5), [[0, 0], [3, 0], [3, 2.5]])
    np.testing.assert_allclose(cut_polyline(path, 100.0), path)
    np.testing.assert_allclose(cut_polyline(path, None), path)


def _table(removal: list[int]) -> ArcTable:
    n = len(removal)
    return ArcTable(
        sample=np.full(n, -1), reading_id=np.arange(n), range=np.ones(n),
        alive=np.array([r == Removal.NONE for r in removal]), processed=np.ones(n, bool),
        xy=np.zeros((n, 2)), width=np.zeros(n), max_error=np.zeros(n),
        source=np.zeros(n, np.int8), removal=np.array(removal, dtype=np.int8))


def test_removal_summary_by_hand() -> None:
    f, s, n = Removal.FULLY_CARVED, Removal.SPLIT, Removal.NONE
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
    final = _table([Removal.FULLY_CARVED, Removal.NONE])
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


def test_bad_requests_raise() -> None:
    with pytest.raises(ExperimentError, match="nope"):
        run_experiments(Settings.make(quick=True), ["nope"])
    with pytest.raises(ExperimentError, match="seeds"):
        Settings.make(seeds=0)


def test_quick_plans_are_small_and_distinct() -> None:
    settings = Settings.make(quick=True)
    for name, experiment in EXPERIMENTS.items():
        if name in APPENDIX_EXPERIMENTS:  # they run in summarise, with no jobs
            continue
        jobs = experiment.plan(settings)
        keys = [job.key for job in jobs]
        assert len(keys) == len(set(keys))
        assert 0 < len(jobs) <= 60
    full = Settings.make()
    assert full.seeds == 3
    assert math.isclose(full.method_config().beam_width, math.radians(22.5))


@pytest.mark.slow
def test_full_size_runs_show_the_papers_qualitative_claims() -> None:
    # Paper Fig. 4: ATM's refined map shows the approaching wall later than carving's (or never).
    # Paper Fig. 2: next to a door, carving's map shows it passable at least as often as
    # centerline's.
    res = run_experiments(Settings.make(seeds=1), ["t-junction", "openings"]).results
    refined = res["t_junction"]["refined"]
    carving_at = refined["carving"]["mean"]
    atm_at = refined["atm"]["mean"]
    assert carving_at is not None
    assert atm_at is None or atm_at < carving_at
    doors = res["openings_by_world"]
    door_share = {m: np.mean([v for k, v in doors[m]["1"].items() if k.startswith("doorway")])
                  for m in ("carving", "centerline")}
    assert door_share["carving"] >= door_share["centerline"]
