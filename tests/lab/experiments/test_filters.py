"""Appendix B, the filters experiment: keys, shares, filters only remove, counts by hand."""

from __future__ import annotations

import numpy as np
import pytest

from sonarcarve.lab.experiments import EXPERIMENTS, Settings
from sonarcarve.lab.experiments.appendix_base import AppendixSettings
from sonarcarve.lab.experiments.base import Page
from sonarcarve.lab.experiments.filters import (
    JUMP_THRESHOLD,
    OUTLIER_NEIGHBOURS,
    OUTLIER_RADIUS,
    FiltersResult,
    filters_experiment,
    markdown,
)
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.sim.simulate import Simulation
from sonarcarve.sim.sonar import EchoKind

METHODS = {"centerline", "carving", "combined"}
VARIANTS = {"none", "max_range", "jump", "outliers", "max_error", "all"}
SHARES = ("spurious_removed_by_filters", "direct_removed_by_filters", "spurious_removed",
          "direct_removed", "spurious_points")
COUNTS = ("readings_dropped", "points_before_map_filter", "points_dropped", "points")
#: The paper's 150 inches, written out here rather than imported.
MAX_RANGE = 150 * 0.0254


@pytest.fixture(scope="module")
def quick() -> tuple[FiltersResult, Simulation]:
    settings = AppendixSettings.make(quick=True)
    res = filters_experiment(settings)[0]
    # The same scenario the experiment drives (one seed, the first 40 m of the office tour).
    sim = run_simulation(Scenario("office", 0, max_length=settings.tour_length))
    return res, sim


def test_registered_as_an_appendix_experiment() -> None:
    assert EXPERIMENTS["filters"].section == "appendix"
    assert EXPERIMENTS["filters"].markdown is markdown


def test_every_key_and_share_in_range(quick: tuple[FiltersResult, Simulation]) -> None:
    res, sim = quick
    assert set(res.methods) == METHODS
    assert set(res.variants) == VARIANTS
    assert res.scenario["readings"] == len(sim.readings)
    for entries in res.methods.values():
        assert set(entries) == VARIANTS
        for e in entries.values():
            for key in COUNTS:
                assert e[key] >= 0
            if e["points"] == 0:  # centerline with every filter can lose every point
                assert e["spurious_points"] is None
                assert e["error"]["median"] is None
            else:
                assert 0.0 <= e["spurious_points"] <= 100.0
                assert 0.0 <= e["error"]["median"] <= e["error"]["p90"]
            for key in SHARES[:-1]:  # the removed shares: over readings, always defined
                assert e[key] is not None
                assert 0.0 <= e[key] <= 100.0, key


def test_filters_only_remove(quick: tuple[FiltersResult, Simulation]) -> None:
    res, sim = quick
    n = len(sim.readings)
    for label, entries in res.methods.items():
        none = entries["none"]
        assert none["readings_dropped"] == none["points_dropped"] == 0
        assert none["spurious_removed_by_filters"] == none["direct_removed_by_filters"] == 0.0
        for e in entries.values():
            assert e["points"] == e["points_before_map_filter"] - e["points_dropped"]
            assert e["points"] <= n - e["readings_dropped"]
            # Removed in all (carving included) is at least what the filters removed.
            assert e["spurious_removed"] >= e["spurious_removed_by_filters"]
            assert e["direct_removed"] >= e["direct_removed_by_filters"]
        # Map filters act on the unfiltered global map: they can only take points away.
        for name in ("outliers", "max_error"):
            e = entries[name]
            assert e["readings_dropped"] == 0
            assert e["points_before_map_filter"] == none["points"]
            assert e["points"] <= none["points"]
            assert e["spurious_removed"] >= none["spurious_removed"]
            assert e["direct_removed"] >= none["direct_removed"]
        if label == "centerline":  # removes nothing itself: every filter only removes
            assert none["points"] == n
            assert all(e["points"] <= n for e in entries.values())


def test_reading_filter_counts_by_hand(quick: tuple[FiltersResult, Simulation]) -> None:
    res, sim = quick
    b = sim.readings
    spurious = sim.truth.kind != EchoKind.DIRECT
    far = b.range > MAX_RANGE
    # Jump filter, one reading at a time: compare with the same sensor's previous reading.
    previous: dict[int, float] = {}
    jumped = np.zeros(len(b), dtype=bool)
    for i, (sensor, r) in enumerate(zip(b.sensor.tolist(), b.range.tolist(), strict=True)):
        if sensor in previous and abs(r - previous[sensor]) > JUMP_THRESHOLD:
            jumped[i] = True
        previous[sensor] = r
    center = res.methods["centerline"]
    assert center["max_range"]["readings_dropped"] == int(far.sum())
    assert center["max_range"]["spurious_removed"] == pytest.approx(100.0 * far[spurious].mean())
    assert center["max_range"]["direct_removed"] == pytest.approx(100.0 * far[~spurious].mean())
    assert center["jump"]["readings_dropped"] == int(jumped.sum())
    assert center["max_range"]["spurious_points"] == pytest.approx(
        100.0 * spurious[~far].mean())


def test_outlier_test_by_hand(quick: tuple[FiltersResult, Simulation]) -> None:
    res, sim = quick
    b = sim.readings
    # Centerline points: on each reading's axis at its range (eq. 3.3 at the beam's centre).
    xy = np.column_stack((b.x + b.range * np.cos(b.theta), b.y + b.range * np.sin(b.theta)))
    d = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
    isolated = (d <= OUTLIER_RADIUS).sum(axis=1) - 1 < OUTLIER_NEIGHBOURS
    assert res.methods["centerline"]["outliers"]["points_dropped"] == int(isolated.sum())


def test_markdown_has_the_table(quick: tuple[FiltersResult, Simulation]) -> None:
    res, _ = quick
    page = Page({}, Settings.make(quick=True), {"filters": res})
    lines = [line for part in markdown(res, page) for line in part.lines]
    assert lines[0] == "### Appendix B: reading filters and map filters"
    rows = [line for line in lines if line.startswith(("| centerline", "| carving",
                                                       "| combined"))]
    assert len(rows) == len(METHODS) * len(VARIANTS)
    assert any("Paper, Appendix B" in line for line in lines)
