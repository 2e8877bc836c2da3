""":mod:`sonarcarve.lab.demo.runs`: each measure of the table, checked independently."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from sonarcarve.lab.demo import SAMPLE_EVERY, DemoResult, run_demo
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.sim.sonar import EchoKind

PERCENT_FIELDS = ("unprocessed_pct", "fully_carved_pct", "spurious_removed_pct", "true_lost_pct")


def test_error_is_the_distance_to_the_true_walls(doorway: DemoResult) -> None:
    # Reference: shapely's point-to-line distance against the world's walls.
    walls = shapely.MultiLineString([s.reshape(2, 2) for s in doorway.world.segments])
    for row in doorway.methods:
        xy = doorway.global_maps[row.method].xy
        distance = shapely.distance(shapely.points(xy), walls)
        assert row.median_error_m == pytest.approx(float(np.median(distance)), abs=1e-9)
        assert row.p90_error_m == pytest.approx(float(np.percentile(distance, 90)), abs=1e-9)


def test_removed_shares_are_readings_missing_from_the_map(doorway: DemoResult) -> None:
    kind = doorway.simulation.truth.kind
    spurious = kind != EchoKind.DIRECT
    assert spurious.any()
    assert (~spurious).any()
    for row in doorway.methods:
        kept = np.zeros(len(kind), dtype=bool)
        kept[doorway.global_maps[row.method].reading_id] = True
        assert row.spurious_removed_pct == pytest.approx(100.0 * np.mean(~kept[spurious]))
        assert row.true_lost_pct == pytest.approx(100.0 * np.mean(~kept[~spurious]))
        assert row.map_points == int(kept.sum())
    assert doorway.summary("centerline").fully_carved_pct == 0.0


def test_unprocessed_share_matches_the_methods_own_measure(doorway: DemoResult) -> None:
    # Reference: feed the readings one by one and ask the method (SonarMethod.measures) every
    # SAMPLE_EVERY readings; the doorway run never fills a 250-arc history, so every sample
    # counts and all have to be weighted by their history length.
    readings = doorway.simulation.readings
    for name in ("carve", "atm"):
        method = make_method(name, MethodConfig(history_size=250))
        unprocessed = total = 0.0
        for i, reading in enumerate(readings, start=1):
            method.add(reading)
            if i % SAMPLE_EVERY == 0:
                m = method.measures()
                unprocessed += m.unprocessed_share * m.in_history
                total += m.in_history
        assert doorway.summary(name).unprocessed_pct == pytest.approx(100.0 * unprocessed / total)


def test_same_seed_same_numbers(doorway: DemoResult) -> None:
    again = run_demo("doorway", seed=0, methods=("carve",))
    first = doorway.summary("carve")
    second = again.summary("carve")
    for name in ("median_error_m", "p90_error_m", *PERCENT_FIELDS, "map_points"):
        a, b = getattr(first, name), getattr(second, name)
        assert a == b or (math.isnan(a) and math.isnan(b))
