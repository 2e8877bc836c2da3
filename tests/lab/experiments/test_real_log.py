"""The real roboND log: the sharpness measure, the reference picture, the experiment."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.io.roboND import read_robond
from sonarcarve.lab.experiments.appendix_base import AppendixError, AppendixSettings
from sonarcarve.lab.experiments.real_log import (
    line_spread,
    real_log_experiment,
    reference_picture,
)


def test_points_on_a_line_have_no_spread() -> None:
    s = np.linspace(0.0, 5.0, 200)
    angle = 0.7
    xy = np.column_stack((30.0 + s * math.cos(angle), -12.0 + s * math.sin(angle)))
    spread = line_spread(xy, radius=0.2, min_points=5)
    assert np.all(np.isfinite(spread.spread))
    np.testing.assert_allclose(spread.spread, 0.0, atol=1e-7)


def test_noisy_line_spread_is_sigma() -> None:
    rng = np.random.default_rng(3)
    sigma = 0.02
    s = np.linspace(0.0, 20.0, 4000)
    angle = -0.4
    normal = np.array([-math.sin(angle), math.cos(angle)])
    xy = np.column_stack((s * math.cos(angle), s * math.sin(angle)))
    xy += rng.normal(0.0, sigma, s.shape)[:, None] * normal
    spread = line_spread(xy, radius=0.25, min_points=5)
    assert float(np.median(spread.spread)) == pytest.approx(sigma, rel=0.1)


def test_line_spread_matches_a_slow_eigen_reference() -> None:
    rng = np.random.default_rng(8)
    xy = rng.uniform(0.0, 2.0, (150, 2))
    radius, k = 0.3, 4
    fast = line_spread(xy, radius, k)
    for i in range(len(xy)):
        near = xy[np.hypot(*(xy - xy[i]).T) <= radius]
        assert fast.neighbours[i] == len(near)
        if len(near) < k:
            assert math.isnan(fast.spread[i])
            continue
        centred = near - near.mean(axis=0)
        smallest = np.linalg.eigvalsh(centred.T @ centred)[0]
        assert fast.spread[i] == pytest.approx(math.sqrt(max(smallest, 0.0) / (len(near) - 2)),
                                               rel=1e-6, abs=1e-9)


def test_line_spread_rejects_bad_parameters() -> None:
    with pytest.raises(AppendixError, match="radius"):
        line_spread(np.zeros((3, 2)), radius=0.0)
    assert line_spread(np.zeros((0, 2)), radius=1.0).spread.shape == (0,)


def test_reference_picture_is_registered_with_the_log() -> None:
    picture = reference_picture()
    assert picture.extent == pytest.approx((-5.95, 24.05, -10.05, 4.95))
    h, w = picture.image.shape[:2]
    left, right, bottom, top = picture.extent
    batch = read_robond().batch
    # origin="lower": row 0 is at the bottom of the extent.
    col = ((batch.x - left) / (right - left) * w).astype(int)
    row = ((batch.y - bottom) / (top - bottom) * h).astype(int)
    rgb = picture.image[row, col, :3]
    free = (rgb[:, 0] > 0.8) & (rgb[:, 1] < 0.2) & (rgb[:, 2] < 0.2)  # red: free cells
    assert np.mean(free) > 0.95
    assert len(picture.occupied) > 1000


def test_every_method_maps_the_log_and_removed_shares_add_up() -> None:
    res, artifacts = real_log_experiment(AppendixSettings.make(quick=True))
    readings = res.log["readings"]
    assert set(res.methods) == {"centerline", "carving", "atm", "combined"}
    for m in res.methods.values():
        assert m["points"] + round(m["removed_percent"] / 100 * readings) == readings
        assert m["spread"]["defined"] <= m["points"]
    assert res.methods["centerline"]["removed_percent"] == 0.0
    assert res.methods["carving"]["removed_percent"] > 0.0
    for label, kept in res.thresholded.items():  # thresholding only removes points
        assert kept["points"] <= res.methods[label]["points"]
    assert set(artifacts["maps"]) == set(res.methods)
