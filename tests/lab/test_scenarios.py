"""Scenarios: cutting a path to a length."""

from __future__ import annotations

import numpy as np

from sonarcarve.lab.scenarios import cut_polyline


def test_cut_polyline_by_hand() -> None:
    path = [[0.0, 0.0], [3.0, 0.0], [3.0, 4.0]]
    np.testing.assert_allclose(cut_polyline(path, 1.0), [[0, 0], [1, 0]])
    np.testing.assert_allclose(cut_polyline(path, 3.0), [[0, 0], [3, 0]])
    np.testing.assert_allclose(cut_polyline(path, 5.5), [[0, 0], [3, 0], [3, 2.5]])
    np.testing.assert_allclose(cut_polyline(path, 100.0), path)
    np.testing.assert_allclose(cut_polyline(path, None), path)
