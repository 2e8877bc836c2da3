"""The scans both grids share (``sonarcarve.grids.scan``), against sampled oracles: a sector's
bounding box with an inner radius, and the row-by-row ring columns, which must hold every cell
whose centre lies in the ring."""

from __future__ import annotations

import numpy as np

from sonarcarve.grids.scan import cell_range, ring_columns, sector_box


def test_the_box_of_an_annular_sector_is_its_sampled_extent() -> None:
    rng = np.random.default_rng(5)
    for _ in range(300):
        x, y = rng.uniform(-3, 3, 2)
        theta, phi = rng.uniform(-4 * np.pi, 4 * np.pi), rng.uniform(0.01, 3.1)
        r_in = rng.uniform(0.0, 2.0)
        r_out = r_in + rng.uniform(0.01, 2.0)
        tau = np.linspace(theta - phi / 2, theta + phi / 2, 20001)
        # The extremes lie on the two circles or on the two straight edges; the edges' extremes
        # are their ends, which are on the circles.
        px = np.concatenate((x + r_in * np.cos(tau), x + r_out * np.cos(tau)))
        py = np.concatenate((y + r_in * np.sin(tau), y + r_out * np.sin(tau)))
        expected = (px.min(), py.min(), px.max(), py.max())
        box = sector_box(float(x), float(y), float(theta - phi / 2), float(theta + phi / 2),
                         float(r_in), float(r_out))
        # Sampled every 0.16 mrad: the true extremes lie at most 1e-8 m beyond the samples.
        np.testing.assert_allclose(box, expected, atol=1e-7)


def test_cell_range_holds_every_cell_whose_centre_lies_in_the_span() -> None:
    rng = np.random.default_rng(6)
    h, origin, n = 0.1, -2.0, 40
    centres = origin + (np.arange(n) + 0.5) * h
    for _ in range(500):
        lo = rng.uniform(-3.0, 3.0)
        hi = lo + rng.uniform(0.0, 1.0)
        k0, k1 = cell_range(lo, hi, origin, h, n)
        inside = np.flatnonzero((centres >= lo) & (centres <= hi))
        assert k0 >= 0
        assert k1 <= n - 1
        if len(inside):
            assert k0 <= inside[0]
            assert inside[-1] <= k1
        assert k1 - k0 + 1 <= len(inside) + 4  # at most one cell of slack each side, rounded


def test_ring_columns_hold_every_cell_of_the_row_inside_the_ring() -> None:
    rng = np.random.default_rng(7)
    h, xmin, nx = 0.05, -1.0, 80
    centres = xmin + (np.arange(nx) + 0.5) * h
    for _ in range(2000):
        x = rng.uniform(-1.5, 3.5)
        dy = rng.uniform(-2.0, 2.0)
        r_in = rng.uniform(0.0, 1.5)
        r_out = r_in + rng.uniform(0.0, 1.0)
        j0, j1 = sorted(rng.integers(0, nx, 2).tolist())
        a0, a1, b0, b1 = ring_columns(dy, r_in, r_out, x, xmin, h, nx, j0, j1)
        listed = set(range(a0, a1 + 1)) | set(range(b0, b1 + 1))
        assert a1 < b0 or b0 > b1 or a0 > a1  # disjoint (or one of them empty)
        d = np.hypot(centres - x, dy)
        for j in np.flatnonzero((d >= r_in) & (d <= r_out)):
            if j0 <= j <= j1:
                assert int(j) in listed, (x, dy, r_in, r_out, j)
        assert all(j0 <= j <= j1 for j in listed)


def test_a_row_beyond_the_outer_circle_has_no_columns() -> None:
    a0, a1, b0, b1 = ring_columns(1.5, 0.5, 1.0, 0.0, -2.0, 0.1, 40, 0, 39)
    assert a0 > a1
    assert b0 > b1
