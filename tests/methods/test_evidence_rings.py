"""Evidence carving on a ring it was not developed on: a Pioneer's 8 front sonars (15° beams,
40° apart at the sides), simulated on a generated floor, against the simulator's truth.

The watch rule (``ConfidenceModel.unwatched_prior``, ``geometry/evidence/watch.py``) exists for
such a ring: its side walls are heard by one sensor only, which the fitted confidence read as a
spurious echo's silence. With the rule the map keeps far more of the true echoes and about as
many spurious ones; both claims are checked on the truth here (RESULTS, "Another ring"). So is
the occlusion map filter's (``MapFilter.occlusion_depth``): on such a ring most multipath points
are hidden behind a wall the finished map holds (RESULTS, "Points behind a surface of the map").
"""

from __future__ import annotations

import numpy as np
import pytest

from sonarcarve.filters import MapFilter
from sonarcarve.lab.scenarios import build_world
from sonarcarve.methods.evidence import ConfidenceModel, EvidenceMethod
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import follow_waypoints
from sonarcarve.sim.simulate import simulate
from sonarcarve.sim.sonar import EchoKind

Log = tuple[ReadingBatch, np.ndarray]  # readings and each one's truth kind


@pytest.fixture(scope="module")
def pioneer_log() -> Log:
    """The first 60 s of the held-out floor random:1's tour, driven by the Pioneer's front ring."""
    world = build_world("random:1")
    assert world.tour is not None
    run = simulate(world, load_robot("p3dx-front"), follow_waypoints(world.tour), 0)
    rows = np.flatnonzero(run.readings.t <= run.readings.t[0] + 60.0)
    assert len(rows) > 1000
    return run.readings[rows], run.truth.kind[rows]


def _kept_and_removed(log: Log, model: ConfidenceModel) -> tuple[float, float]:
    readings, kind = log
    gmap = process_readings(readings, EvidenceMethod(confidence_model=model)).global_map
    kept = np.zeros(len(readings), dtype=bool)
    kept[gmap.reading_id] = True
    direct = kind == EchoKind.DIRECT
    return float(np.mean(kept[direct])), float(np.mean(~kept[~direct]))


def test_the_watch_rule_keeps_a_sparse_rings_walls(pioneer_log: Log) -> None:
    kept, removed = _kept_and_removed(pioneer_log, ConfidenceModel())
    kept_before, removed_before = _kept_and_removed(pioneer_log,
                                                    ConfidenceModel(unwatched_prior=False))
    assert kept >= 0.85 > kept_before  # the share; 74 % before, over six runs
    assert kept - kept_before >= 0.10
    assert removed >= removed_before - 0.03  # spurious echoes kept: at most a few more


def test_the_occlusion_filter_drops_most_multipath_of_a_sparse_ring(pioneer_log: Log) -> None:
    readings, kind = pioneer_log
    multipath = kind == EchoKind.MULTIPATH
    direct = kind == EchoKind.DIRECT
    shares = []
    for map_filter in (None, MapFilter(occlusion_depth=0.5)):
        gmap = process_readings(readings, EvidenceMethod(), map_filter=map_filter).global_map
        kept = np.zeros(len(readings), dtype=bool)
        kept[gmap.reading_id] = True
        shares.append((int(np.sum(kept[multipath])), float(np.mean(kept[direct])),
                       float(np.mean(~kept[~direct]))))
    (multipath_before, kept_before, removed_before), (multipath_after, kept_after,
                                                      removed_after) = shares
    assert multipath_before >= 20  # the problem is there to solve
    assert multipath_after <= multipath_before / 2
    assert removed_after >= removed_before + 0.10
    assert kept_after >= 0.85  # the share of direct echoes still kept
    assert kept_before - kept_after <= 0.05
