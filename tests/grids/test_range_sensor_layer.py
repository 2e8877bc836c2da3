"""Tests of the ``range_sensor_layer`` re-implementation against values worked out by hand.

Every expected value comes from the layer's formulas (module docstring of
:mod:`sonarcarve.grids.range_sensor_layer`), written out here with the arithmetic in comments;
none is read back from the code under test. Shorthands: ``δ(d) = 1 / (1 + exp(4 (d - φ_v)))``
(the distance term; ``(1 - tanh x) / 2 = 1 / (1 + e^{2x})``), ``γ(α) = 1 - (α / m)²``, ``λ = δγ``,
band ``Δr`` with Δ the resolution, Bayes ``p' = s p / (s p + (1 - s)(1 - p))``, cost
``trunc(254 p)``.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest

from sonarcarve.errors import SonarcarveError
from sonarcarve.grids import (
    FREE_SPACE,
    LETHAL_OBSTACLE,
    NO_INFORMATION,
    GridError,
    InputSensorType,
    RangeSensorLayer,
    RangeSensorLayerParams,
    angular_term,
    distance_term,
    master_costs,
    sensor_model,
)
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch

#: Half of the default 22.5° beam: 11.25° = π/16 rad.
M = math.pi / 16


def logistic(d: float, phi: float = 1.2) -> float:
    """δ(d) written as the logistic it equals: 1 / (1 + e^{4 (d - φ_v)})."""
    return 1.0 / (1.0 + math.exp(4.0 * (d - phi)))


def bayes(s: float, p: float) -> float:
    return s * p / (s * p + (1.0 - s) * (1.0 - p))


def cost(p: float) -> int:
    return math.floor(254.0 * p)


# -- the sensor model --------------------------------------------------------------------------

def test_distance_term_is_one_half_at_phi_and_a_logistic_around_it() -> None:
    # 1 - (1 + tanh 0) / 2 = 1/2.
    assert distance_term(1.2, 1.2) == 0.5
    # d = 0.7: tanh(2 · (0.7 - 1.2)) = tanh(-1) = -0.76159416; 1 - (1 - 0.76159416)/2 = 0.88079708,
    # = 1 / (1 + e^-2) = 1 / 1.13533528.
    assert distance_term(0.7, 1.2) == pytest.approx(0.8807970779778823, rel=1e-12)
    # d = 2.2: 1 / (1 + e^4) = 1 / 55.59815 = 0.01798621.
    assert distance_term(2.2, 1.2) == pytest.approx(0.01798620996209156, rel=1e-12)


def test_angular_term_is_one_on_the_axis_and_zero_at_and_beyond_the_edge() -> None:
    assert angular_term(0.0, M) == 1.0
    assert angular_term(M / 2, M) == pytest.approx(0.75, rel=1e-15)  # 1 - (1/2)²
    assert angular_term(-M / 2, M) == pytest.approx(0.75, rel=1e-15)
    assert angular_term(M, M) == 0.0  # 1 - 1², the beam's edge
    assert angular_term(-M, M) == 0.0
    assert angular_term(1.01 * M, M) == 0.0  # outside: 0, not 1 - 1.01² < 0


@pytest.mark.parametrize(
    ("d", "alpha", "expected"),
    [
        # r = 1, Δ = 0.1: free d < 0.8, ramp [0.8, 0.9), bump [0.9, 1.1), then 1/2.
        # φ_v = d in every row so that δ(d) = 1/2 exactly; γ(0) = 1, so λ = 1/2 on the axis.
        (0.5, 0.0, 0.25),  # free: (1 - λ)/2 = 0.25
        (0.85, 0.0, 0.3125),  # ramp: λ/2 · ((0.85 - 0.8)/0.1)² + (1 - λ)/2 = 0.25·0.25 + 0.25
        (1.0, 0.0, 0.75),  # bump, J = 0: λ (1 - 0 - 1/2) + 1/2 = 0.25 + 0.5
        (1.05, 0.0, 0.6875),  # J = -0.5: 0.5 · (1 - 0.125 - 0.5) + 0.5 = 0.1875 + 0.5
        (1.3, 0.0, 0.5),  # beyond r + Δr
        (1.0, M / 2, 0.6875),  # γ = 0.75, λ = 0.375: 0.375 · 0.5 + 0.5
        (0.5, 1.5 * M, 0.5),  # outside the beam λ = 0: (1 - 0)/2 in the free zone
        (1.0, 1.5 * M, 0.5),  # and λ·(...) + 1/2 = 1/2 in the bump
    ],
)
def test_sensor_model_in_each_zone(d: float, alpha: float, expected: float) -> None:
    assert sensor_model(1.0, d, alpha, M, d, 0.1) == pytest.approx(expected, rel=1e-12)


def test_band_is_resolution_times_range_either_side_of_the_range() -> None:
    # Δ = 0.05 (a 5 cm costmap), r = 2: the bump spans 2 ± 0.1 m and the ramp 1.8 .. 1.9 m.
    r, delta, phi = 2.0, 0.05, 1.2
    lam = logistic(2.09)  # λ at d = 2.09 (on the axis)
    j = (2.0 - 2.09) / 0.1  # -0.9
    assert sensor_model(r, 2.09, 0.0, M, phi, delta) == pytest.approx(
        lam * (0.5 - 0.5 * j * j) + 0.5, rel=1e-12)
    assert sensor_model(r, 2.11, 0.0, M, phi, delta) == 0.5
    # Ramp at 1.85: λ/2 · ((1.85 - 1.8)/0.1)² + (1 - λ)/2.
    lam = logistic(1.85)
    assert sensor_model(r, 1.85, 0.0, M, phi, delta) == pytest.approx(
        lam / 2 * 0.25 + (1 - lam) / 2, rel=1e-12)
    # Free below 1.8 m.
    lam = logistic(1.79)
    assert sensor_model(r, 1.79, 0.0, M, phi, delta) == pytest.approx((1 - lam) / 2, rel=1e-12)
    # The same distances at r = 1 (band 1 ± 0.05): 1.06 is past it.
    assert sensor_model(1.0, 1.06, 0.0, M, phi, delta) == 0.5


# -- one reading, cell by cell -------------------------------------------------------------------
# Cells of 0.1 m over (0, 0, 2, 1); the sensor sits on the centre of cell (row 5, column 0) at
# (0.05, 0.55), looks along +x with the default 22.5° beam, r = 1.04. Cell (5, j) is at
# d = 0.1 j on the axis. Band: Δr = 0.104, free d < 0.832, ramp [0.832, 0.936),
# bump [0.936, 1.144). The target (1.09, 0.55) lies in cell (5, 10).

H = 0.1
BOUNDS = (0.0, 0.0, 2.0, 1.0)
X0, Y0, R = 0.05, 0.55, 1.04


def one_reading(**params: object) -> RangeSensorLayer:
    layer = RangeSensorLayer(H, BOUNDS, RangeSensorLayerParams(**params))  # type: ignore[arg-type]
    layer.add(Reading(0.0, 0, X0, Y0, 0.0, R))
    return layer


def test_fresh_layer_holds_cost_127_probability_one_half_and_no_information() -> None:
    layer = RangeSensorLayer(H, BOUNDS)
    assert layer.shape == (10, 20)
    assert (layer.layer_costs() == 127).all()  # to_cost(0.5) = trunc(127.0)
    assert (layer.probabilities() == 0.5).all()  # 127 / 254
    assert (layer.costs() == NO_INFORMATION).all()
    assert layer.take_touched_bounds() is None


def test_one_reading_updates_cells_as_computed_by_hand() -> None:
    c = one_reading().layer_costs()
    # Prior 1/2 everywhere except the target, so p' = s.
    # (5, 5), d = 0.5, free: λ = 1/(1 + e^{4(0.5-1.2)}) = 1/(1 + e^-2.8) = 1/1.06081006
    # = 0.94267582; s = (1 - λ)/2 = 0.02866209; 254 s = 7.280 -> 7.
    assert c[5, 5] == 7
    # (5, 0), the sensor's own cell, d = 0 (atan2(0, 0) = 0, on the axis):
    # λ = 1/(1 + e^-4.8) = 0.99183743; s = 0.00408128; 254 s = 1.037 -> 1.
    assert c[5, 0] == 1
    # (5, 9), d = 0.9, ramp: λ = 1/(1 + e^-1.2) = 0.76852478; q = (0.9 - 0.832)/0.104 = 0.65384615;
    # s = λ/2 q² + (1 - λ)/2 = 0.38426239 · 0.42751479 + 0.11573761 = 0.28001583; 254 s = 71.12.
    lam = logistic(0.9)
    q = (0.9 - (1.04 - 2 * 0.104)) / 0.104
    assert c[5, 9] == cost(lam / 2 * q * q + (1 - lam) / 2) == 71
    # (5, 11), d = 1.1, bump: λ = 1/(1 + e^-0.4) = 0.59868766; J = (1.04 - 1.1)/0.104 = -0.5769231;
    # s = λ (1 - J²/2 - 1/2) + 1/2 = 0.59868766 · 0.33357988 + 0.5 = 0.69971; 254 s = 177.73.
    lam = logistic(1.1)
    j = (1.04 - 1.1) / 0.104
    assert c[5, 11] == cost(lam * ((1 - 0.5 * j * j) - 0.5) + 0.5) == 177
    # (5, 12), d = 1.2 >= 1.144: s = 1/2, unchanged.
    assert c[5, 12] == 127
    # (4, 10), centre (1.05, 0.45): dx = 1, dy = -0.1, α = -atan(0.1) = -0.09966865,
    # γ = 1 - (0.09966865 / 0.19634954)² = 0.74233; d = √1.01 = 1.00498756,
    # δ = 1/(1 + e^{4(1.00498756 - 1.2)}) = 0.68569; λ = 0.50901; J = (1.04 - d)/0.104 = 0.33666;
    # s = λ (1/2 - J²/2) + 1/2 = 0.72566; 254 s = 184.3.
    alpha, d = math.atan(0.1), math.sqrt(1.01)
    lam = logistic(d) * (1 - (alpha / M) ** 2)
    j = (1.04 - d) / 0.104
    assert c[4, 10] == c[6, 10] == cost(lam * (0.5 - 0.5 * j * j) + 0.5) == 184
    # (3, 5), centre (0.55, 0.35): α = atan(0.2 / 0.5) = 21.8° > 11.25°: in the box, outside
    # the beam, s = 1/2 exactly, unchanged.
    assert c[3, 5] == 127


def test_the_target_cell_is_set_to_233_before_every_update() -> None:
    # (5, 10), d = 1.0: prior 233/254 = 0.91732283, not 1/2. λ = 1/(1 + e^-0.8) = 0.68997448;
    # J = 0.04/0.104 = 0.38461538; s = λ (1/2 - J²/2) + 1/2 = 0.79395; p' = s p / (s p + (1-s)(1-p))
    # = 0.72831 / (0.72831 + 0.01704) = 0.97714; 254 p' = 248.2 -> 248.
    lam = logistic(1.0)
    j = 0.04 / 0.104
    s = lam * (0.5 - 0.5 * j * j) + 0.5
    assert cost(bayes(s, 233 / 254)) == 248
    layer = one_reading()
    assert layer.layer_costs()[5, 10] == 248
    # A second identical reading resets the cell to 233 first: 248 again, no accumulation,
    # while its neighbour (5, 11) accumulates: prior 177/254, s = 0.69971 as above,
    # p' = 0.48759 / (0.48759 + 0.09103) = 0.84267; 254 p' = 214.04 -> 214.
    layer.add(Reading(1.0, 0, X0, Y0, 0.0, R))
    c = layer.layer_costs()
    assert c[5, 10] == 248
    lam = logistic(1.1)
    j = (1.04 - 1.1) / 0.104
    s11 = lam * ((1 - 0.5 * j * j) - 0.5) + 0.5
    assert c[5, 11] == cost(bayes(s11, 177 / 254)) == 214


def test_costs_are_truncated_after_every_update_unless_quantize_is_off() -> None:
    # (5, 5): s = 0.02866209 twice. Quantized: prior 7/254 on the second reading,
    # p'' = 0.02866·7 / (0.02866·7 + 0.97134·247) = 0.0008356; 254 p'' = 0.21 -> 0.
    s = (1 - logistic(0.5)) / 2
    quantized = one_reading()
    quantized.add(Reading(1.0, 0, X0, Y0, 0.0, R))
    assert quantized.layer_costs()[5, 5] == cost(bayes(s, 7 / 254)) == 0
    assert quantized.probabilities()[5, 5] == 0.0
    # Unquantized: p' = s, p'' = s² / (s² + (1 - s)²) = 0.00082153 / 0.94433 = 0.00086995.
    exact = one_reading(quantize=False)
    assert exact.probabilities()[5, 5] == pytest.approx(s, rel=1e-12)
    exact.add(Reading(1.0, 0, X0, Y0, 0.0, R))
    assert exact.probabilities()[5, 5] == pytest.approx(s * s / (s * s + (1 - s) ** 2),
                                                        rel=1e-9)


def test_bounds_are_the_origin_the_target_and_the_edges_at_1_2_r() -> None:
    layer = one_reading()
    # A, B = (0.05, 0.55) + 1.2 · 1.04 · (cos ∓11.25°, sin ∓11.25°)
    #      = (0.05 + 1.248 · 0.98078528, 0.55 ∓ 1.248 · 0.19509032) = (1.27402, 0.55 ∓ 0.24347).
    bounds = layer.take_touched_bounds()
    assert bounds == pytest.approx((0.05, 0.55 - 1.248 * math.sin(M),
                                    0.05 + 1.248 * math.cos(M), 0.55 + 1.248 * math.sin(M)),
                                   rel=1e-12)
    assert layer.take_touched_bounds() is None  # updateBounds resets the range


def test_a_wider_beam_reaches_cells_the_default_one_does_not() -> None:
    # (3, 5) lies 21.8° off the axis: a 60° beam (m = 30°) covers it.
    # α = atan(0.4) = 0.38050638, γ = 1 - (0.38050638 / 0.52359878)² = 0.47188;
    # d = √0.29 = 0.53851648, free (< 0.832): λ = δ(d) γ = 0.93392 · 0.47188 = 0.44070;
    # s = (1 - λ)/2 = 0.27965; 254 s = 71.03 -> 71.
    layer = RangeSensorLayer(H, BOUNDS)
    layer.add(Reading(0.0, 0, X0, Y0, 0.0, R, math.radians(60.0)))
    alpha, d, m = math.atan(0.4), math.sqrt(0.29), math.radians(30.0)
    lam = logistic(d) * (1 - (alpha / m) ** 2)
    assert layer.layer_costs()[3, 5] == cost((1 - lam) / 2) == 71


# -- costs ---------------------------------------------------------------------------------------

def test_thresholds_compare_truncated_costs_strictly() -> None:
    # clear = trunc(254 · 0.2) = trunc(50.8) = 50; mark = trunc(254 · 0.8) = trunc(203.2) = 203.
    params = RangeSensorLayerParams()
    assert (params.clear_cost, params.mark_cost) == (50, 203)
    got = master_costs([0, 49, 50, 127, 203, 204, 254, 255])
    assert got.tolist() == [FREE_SPACE, FREE_SPACE, NO_INFORMATION, NO_INFORMATION,
                            NO_INFORMATION, LETHAL_OBSTACLE, LETHAL_OBSTACLE, NO_INFORMATION]
    # clear = mark = 0.5 -> 127: 126 free, 127 unknown, 128 lethal.
    assert master_costs([126, 127, 128], 0.5, 0.5).tolist() == [0, 255, 254]


def test_costs_of_one_reading() -> None:
    layer = one_reading()
    row = layer.costs()[5]
    # Costs 1, 7 (< 50): free; 71 (between): unknown; 248 (> 203): lethal; 127: unknown.
    assert row[[0, 5, 9, 10, 12]].tolist() == [0, 0, 255, 254, 255]
    # Only the target cell is lethal; the cells at 184/254 = 0.724 pass a threshold of 0.7.
    np.testing.assert_allclose(layer.occupied_points(), [[1.05, 0.55]], rtol=1e-12)
    np.testing.assert_allclose(layer.occupied_points(0.7),
                               [[1.05, 0.45], [1.05, 0.55], [1.05, 0.65]], rtol=1e-12)
    # A higher mark threshold, 0.98 -> trunc(248.92) = 248: 248 is no longer above it.
    assert one_reading(mark_threshold=0.98).costs()[5, 10] == NO_INFORMATION


# -- clearing and the cone's triangle -------------------------------------------------------------
# Cells of 0.1 m over (0, 0, 3, 1.2) (30 x 12); sensor at (0.05, 0.55) along +x, a variable
# sensor with max_range 2 and clear_on_max_reading: a 2 m reading clears. The edge points at
# 1.2 · 2 = 2.4 m: A = (0.05 + 2.4 cos 11.25°, 0.55 - 2.4 sin 11.25°) = (2.40388, 0.08178), cell
# (24, 0); B = (2.40388, 1.01822), cell (24, 10); O = cell (0, 5). Box: columns 0..24, rows 0..10.
# Edge functions of a cell P = (px, py) (integers):
#   w0 = orient2d(A, B, P) = (Bx-Ax)(py-Ay) - (By-Ay)(px-Ax) = -10 (px - 24)
#   w1 = orient2d(B, O, P) = (Ox-Bx)(py-By) - (Oy-By)(px-Bx) = -24 (py - 10) + 5 (px - 24)
#   w2 = orient2d(O, A, P) = (Ax-Ox)(py-Oy) - (Ay-Oy)(px-Ox) = 24 (py - 5) + 5 px
# area(A, B, O) = |24 (10 - 5) + 24 (5 - 0) + 0| / 2 = 120.

WIDE = (0.0, 0.0, 3.0, 1.2)


def cleared(inflate_cone: float) -> npt.NDArray[np.bool_]:
    params = RangeSensorLayerParams(max_range=2.0, min_range=0.1, clear_on_max_reading=True,
                                    inflate_cone=inflate_cone)
    layer = RangeSensorLayer(H, WIDE, params)
    assert layer.add_range(0.05, 0.55, 0.0, 2.0)
    c = layer.layer_costs()
    assert set(np.unique(c).tolist()) <= {0, 127}  # s = 0: every visited cell to 0
    return np.asarray(c == 0)


def expected_triangle(threshold: float) -> npt.NDArray[np.bool_]:
    py, px = np.mgrid[0:12, 0:30]
    w0 = -10 * (px - 24)
    w1 = -24 * (py - 10) + 5 * (px - 24)
    w2 = 24 * (py - 5) + 5 * px
    in_box = (px <= 24) & (py <= 10)
    return np.asarray(in_box & (w0 >= threshold) & (w1 >= threshold) & (w2 >= threshold))


def test_inflate_cone_zero_updates_only_the_integer_triangle() -> None:
    mask = cleared(0.0)
    np.testing.assert_array_equal(mask, expected_triangle(0.0))
    # Spot checks of that rule: column 0 only row 5; column 12 rows 3..7 (|py - 5| <= 2.5).
    assert np.flatnonzero(mask[:, 0]).tolist() == [5]
    assert np.flatnonzero(mask[:, 12]).tolist() == [3, 4, 5, 6, 7]
    assert mask[5, 20]  # the target cell, set to 233 first, then cleared


def test_inflate_cone_one_updates_the_whole_box() -> None:
    mask = cleared(1.0)
    expected = np.zeros((12, 30), dtype=bool)
    expected[0:11, 0:25] = True  # rows 0..10, columns 0..24, behind and beside the beam too
    np.testing.assert_array_equal(mask, expected)


def test_inflate_cone_one_half_widens_the_triangle_by_half_its_area() -> None:
    # Threshold -0.5 · 120 = -60: (12, 2): w2 = -72 + 60 = -12 >= -60, in; (0, 0): w2 = -120, out;
    # (0, 3): w2 = -48, w1 = 48, w0 = 240, in.
    mask = cleared(0.5)
    np.testing.assert_array_equal(mask, expected_triangle(-60.0))
    assert mask[2, 12]
    assert mask[3, 0]
    assert not mask[0, 0]


def test_a_max_reading_without_clear_on_max_reading_marks_an_arc_at_max_range() -> None:
    params = RangeSensorLayerParams(max_range=2.0, min_range=0.1)
    layer = RangeSensorLayer(H, WIDE, params)
    assert layer.add_range(0.05, 0.55, 0.0, 2.0)
    # Target cell (5, 20), d = 2.0: prior 233/254; λ = 1/(1 + e^3.2) = 0.03916572; J = 0
    # (Δr = 0.2): s = λ/2 + 1/2 = 0.51958; p' = 0.47662 / (0.47662 + 0.03975) = 0.92302 -> 234.
    s = logistic(2.0) / 2 + 0.5
    assert layer.layer_costs()[5, 20] == cost(bayes(s, 233 / 254)) == 234
    assert layer.costs()[5, 20] == LETHAL_OBSTACLE


# -- REP 117 -------------------------------------------------------------------------------------

def variable_layer(**params: object) -> RangeSensorLayer:
    p = RangeSensorLayerParams(min_range=0.2, max_range=2.0, **params)  # type: ignore[arg-type]
    return RangeSensorLayer(H, WIDE, p)


@pytest.mark.parametrize("clear_on_max", [False, True])
@pytest.mark.parametrize("r", [math.inf, -math.inf, math.nan, 0.19, 2.01])
def test_variable_sensor_drops_inf_nan_and_out_of_range(r: float, clear_on_max: bool) -> None:
    # min_range 0.2 <= r <= max_range 2 or nothing: +Inf > 2 and -Inf < 0.2 are dropped whatever
    # clear_on_max_reading says (REP 117's +Inf does not clear a variable-range sensor's cone).
    layer = variable_layer(clear_on_max_reading=clear_on_max)
    assert not layer.add_range(0.05, 0.55, 0.0, r)
    assert (layer.layer_costs() == 127).all()
    assert (layer.readings, layer.dropped) == (0, 1)
    assert layer.take_touched_bounds() is None


def test_variable_sensor_keeps_the_range_limits_themselves() -> None:
    layer = variable_layer()
    assert layer.add_range(0.05, 0.55, 0.0, 0.2)
    assert layer.add_range(0.05, 0.55, 0.0, 2.0)
    assert (layer.readings, layer.dropped) == (2, 0)


def test_inf_is_max_reading_turns_plus_inf_into_a_max_range_reading() -> None:
    # Clearing: every cell of the box to 0, as a 2.0 m reading with clear_on_max_reading.
    layer = variable_layer(clear_on_max_reading=True, inf_is_max_reading=True)
    assert layer.add_range(0.05, 0.55, 0.0, math.inf)
    np.testing.assert_array_equal(layer.layer_costs() == 0, cleared(1.0))
    # Without clear_on_max_reading it marks at max_range: 234 at the target, as computed above.
    layer = variable_layer(inf_is_max_reading=True)
    assert layer.add_range(0.05, 0.55, 0.0, math.inf)
    assert layer.layer_costs()[5, 20] == 234
    # -Inf stays dropped.
    assert not variable_layer(inf_is_max_reading=True).add_range(0.05, 0.55, 0.0, -math.inf)


def fixed_layer(**params: object) -> RangeSensorLayer:
    p = RangeSensorLayerParams(min_range=0.5, max_range=0.5, **params)  # type: ignore[arg-type]
    return RangeSensorLayer(H, WIDE, p)


def test_fixed_ranger_marks_minus_inf_at_its_range() -> None:
    layer = fixed_layer()
    assert layer.params.fixed_ranger
    assert layer.add_range(0.05, 0.55, 0.0, -math.inf)
    # r = 0.5: target (0.55, 0.55) in cell (5, 5), d = 0.5, prior 233/254; Δr = 0.05;
    # λ = 1/(1 + e^-2.8) = 0.94267582; J = 0: s = λ/2 + 1/2 = 0.97133791;
    # p' = 0.89103 / (0.89103 + 0.00237) = 0.99735; 254 p' = 253.33 -> 253.
    s = logistic(0.5) / 2 + 0.5
    assert layer.layer_costs()[5, 5] == cost(bayes(s, 233 / 254)) == 253
    # (5, 3), d = 0.3 < 0.5 - 0.1: free, s = (1 - λ)/2 with λ = 1/(1 + e^-3.6) = 0.97340301.
    assert layer.layer_costs()[5, 3] == cost((1 - logistic(0.3)) / 2) == 3


def test_fixed_ranger_clears_on_plus_inf_only_with_clear_on_max_reading() -> None:
    assert not fixed_layer().add_range(0.05, 0.55, 0.0, math.inf)
    layer = fixed_layer(clear_on_max_reading=True)
    assert layer.add_range(0.05, 0.55, 0.0, math.inf)
    # Box of O = (0, 5) and the edges at 0.6 m: (0.05 + 0.58847, 0.55 ∓ 0.11705) -> (6, 4), (6, 6).
    expected = np.zeros((12, 30), dtype=bool)
    expected[4:7, 0:7] = True
    np.testing.assert_array_equal(layer.layer_costs() == 0, expected)


@pytest.mark.parametrize("r", [0.5, 0.3, math.nan])
def test_fixed_ranger_drops_anything_but_inf(r: float) -> None:
    layer = fixed_layer(clear_on_max_reading=True)
    assert not layer.add_range(0.05, 0.55, 0.0, r)
    assert (layer.layer_costs() == 127).all()


def test_input_sensor_type_forces_a_path() -> None:
    # FIXED with min != max: -Inf marks at min_range (0.5 here), a finite range is dropped.
    p = RangeSensorLayerParams(min_range=0.5, max_range=2.0,
                               input_sensor_type=InputSensorType.FIXED)
    layer = RangeSensorLayer(H, WIDE, p)
    assert not layer.add_range(0.05, 0.55, 0.0, 1.0)
    assert layer.add_range(0.05, 0.55, 0.0, -math.inf)
    assert layer.layer_costs()[5, 5] == 253  # as in the fixed ranger test
    # VARIABLE with min == max: the one valid range is an ordinary reading.
    p = RangeSensorLayerParams(min_range=0.5, max_range=0.5,
                               input_sensor_type=InputSensorType.VARIABLE)
    layer = RangeSensorLayer(H, WIDE, p)
    assert not layer.add_range(0.05, 0.55, 0.0, -math.inf)
    assert layer.add_range(0.05, 0.55, 0.0, 0.5)
    assert layer.layer_costs()[5, 5] == 253


# -- batches, time, edges -------------------------------------------------------------------------

def test_add_many_equals_add_range_one_by_one() -> None:
    rng = np.random.default_rng(7)
    n = 40
    batch = ReadingBatch.from_arrays(
        t=np.arange(n, dtype=float), sensor=np.zeros(n, dtype=int),
        x=rng.uniform(0.0, 3.0, n), y=rng.uniform(0.0, 1.2, n),
        theta=rng.uniform(-4.0, 4.0, n), range=rng.uniform(0.1, 2.5, n),
        beam_width=np.where(rng.random(n) < 0.5, math.nan, 0.6))
    params = RangeSensorLayerParams(max_range=2.0, clear_on_max_reading=True, inflate_cone=0.3)
    together = RangeSensorLayer(H, WIDE, params)
    together.add_many(batch)
    alone = RangeSensorLayer(H, WIDE, params)
    for reading in batch:
        alone.add_range(reading.x, reading.y, reading.theta, reading.range, reading.beam_width)
    np.testing.assert_array_equal(together.layer_costs(), alone.layer_costs())
    assert together.readings == alone.readings == int((batch.range <= 2.0).sum())
    assert not np.array_equal(together.layer_costs(), RangeSensorLayer(H, WIDE).layer_costs())


def reference_layer(costs: npt.NDArray[np.float64], x0: float, y0: float, h: float, ox: float,
                    oy: float, theta: float, r: float, fov: float, clear: bool, phi: float,
                    inflate_cone: float) -> None:
    """ROS's ``updateCostmap`` + ``update_cell`` for one reading, line by line in plain Python
    (no shortcuts), written from the C++ independently of the module: the brute-force check."""
    ny, nx = costs.shape
    m = fov / 2

    def sensor(d: float, a: float) -> float:
        lam = (1 - (1 + math.tanh(2 * (d - phi))) / 2) * (0.0 if abs(a) > m else 1 - (a / m) ** 2)
        if 0.0 <= d < r - 2 * h * r:
            return (1 - lam) * 0.5
        if d < r - h * r:
            return lam * 0.5 * ((d - (r - 2 * h * r)) / (h * r)) ** 2 + (1 - lam) * 0.5
        if d < r + h * r:
            return lam * ((1 - 0.5 * ((r - d) / (h * r)) ** 2) - 0.5) + 0.5
        return 0.5

    def cell(wx: float, wy: float) -> tuple[int, int]:  # worldToMapNoBounds: C truncation
        return int((wx - x0) / h), int((wy - y0) / h)

    th = math.atan2(math.sin(theta), math.cos(theta))
    tx, ty = ox + r * math.cos(th), oy + r * math.sin(th)
    if tx >= x0 and ty >= y0 and cell(tx, ty)[0] < nx and cell(tx, ty)[1] < ny:
        costs[cell(tx, ty)[1], cell(tx, ty)[0]] = 233
    (Ox, Oy), (Ax, Ay), (Bx, By) = (
        cell(ox, oy), cell(ox + math.cos(th - m) * r * 1.2, oy + math.sin(th - m) * r * 1.2),
        cell(ox + math.cos(th + m) * r * 1.2, oy + math.sin(th + m) * r * 1.2))
    area = abs((Ax * (By - Oy) + Bx * (Oy - Ay) + Ox * (Ay - By)) / 2.0)
    for px in range(max(0, min(Ox, Ax, Bx)), min(nx, max(Ox, Ax, Bx)) + 1):
        for py in range(max(0, min(Oy, Ay, By)), min(ny, max(Oy, Ay, By)) + 1):
            if inflate_cone < 1.0:
                w = ((Bx - Ax) * (py - Ay) - (By - Ay) * (px - Ax),
                     (Ox - Bx) * (py - By) - (Oy - By) * (px - Bx),
                     (Ax - Ox) * (py - Oy) - (Ay - Oy) * (px - Ox))
                if min(w) < -inflate_cone * area:
                    continue
            if px >= nx or py >= ny:
                continue
            dx, dy = x0 + (px + 0.5) * h - ox, y0 + (py + 0.5) * h - oy
            a = math.remainder(math.atan2(dy, dx) - th, 2 * math.pi)
            s = 0.0 if clear else sensor(math.sqrt(dx * dx + dy * dy), a)
            p = costs[py, px] / 254
            costs[py, px] = math.floor(s * p / (s * p + (1 - s) * (1 - p)) * 254)


@pytest.mark.parametrize("inflate_cone", [1.0, 0.4, 0.0])
def test_matches_a_line_by_line_reference(inflate_cone: float) -> None:
    rng = np.random.default_rng(11)
    n = 60
    x, y = rng.uniform(-0.5, 3.5, n), rng.uniform(-0.5, 1.7, n)
    theta, r = rng.uniform(-4.0, 4.0, n), rng.uniform(0.15, 2.2, n)
    r[::25] = 2.0  # max readings: cleared (rarely: a clear empties its whole box for good)
    fov = rng.uniform(0.1, 1.5, n)
    params = RangeSensorLayerParams(max_range=2.0, clear_on_max_reading=True,
                                    inflate_cone=inflate_cone, phi=1.0)
    layer = RangeSensorLayer(H, WIDE, params)
    expected = np.full((12, 30), 127.0)
    for k in range(n):
        if layer.add_range(x[k], y[k], theta[k], r[k], fov[k]):
            reference_layer(expected, 0.0, 0.0, H, x[k], y[k], theta[k], r[k], fov[k],
                            r[k] == 2.0, 1.0, inflate_cone)
    assert layer.readings == int((r <= 2.0).sum())
    np.testing.assert_array_equal(layer.layer_costs(), expected)
    assert len(np.unique(expected)) > 10  # a varied map, not a trivial one


def test_a_beam_outside_the_map_changes_nothing() -> None:
    layer = RangeSensorLayer(H, WIDE)
    assert layer.add_range(-5.0, 0.5, math.pi, 1.0)  # box entirely at negative x
    assert layer.add_range(5.0, 5.0, 0.0, 1.0)  # beyond the far corner
    assert (layer.layer_costs() == 127).all()
    assert layer.take_touched_bounds() is not None  # the points are touched all the same


def test_no_readings_timeout() -> None:
    layer = RangeSensorLayer(H, WIDE, RangeSensorLayerParams(no_readings_timeout=1.0))
    assert layer.is_current(100.0)  # before any reading
    layer.add(Reading(10.0, 0, 0.05, 0.55, 0.0, 1.0))
    assert layer.is_current(10.9)
    assert not layer.is_current(11.1)
    layer.add_range(0.05, 0.55, 0.0, math.inf, t=11.0)  # dropped: does not count
    assert not layer.is_current(11.1)
    assert RangeSensorLayer(H, WIDE).is_current(1e9)  # timeout 0: off


def test_reset_forgets_everything() -> None:
    layer = one_reading()
    layer.reset()
    assert (layer.layer_costs() == 127).all()
    assert layer.readings == 0
    assert layer.take_touched_bounds() is None


# -- parameters ----------------------------------------------------------------------------------

def test_defaults_are_ros_defaults() -> None:
    p = RangeSensorLayerParams()
    assert (p.phi, p.inflate_cone, p.no_readings_timeout, p.clear_threshold, p.mark_threshold,
            p.clear_on_max_reading, p.input_sensor_type) == (
        1.2, 1.0, 0.0, 0.2, 0.8, False, InputSensorType.ALL)
    assert p.beam_width == DEFAULT_BEAM_WIDTH
    assert (p.inf_is_max_reading, p.quantize) == (False, True)
    assert not p.fixed_ranger


@pytest.mark.parametrize(
    "bad",
    [
        {"phi": 0.0}, {"phi": math.inf}, {"phi": math.nan},
        {"inflate_cone": -0.1}, {"inflate_cone": 1.5}, {"inflate_cone": math.nan},
        {"no_readings_timeout": -1.0}, {"no_readings_timeout": math.inf},
        {"clear_threshold": -0.1}, {"mark_threshold": 1.1}, {"mark_threshold": math.nan},
        {"clear_threshold": 0.9, "mark_threshold": 0.8},
        {"clear_on_max_reading": 1}, {"quantize": "yes"}, {"inf_is_max_reading": None},
        {"input_sensor_type": "ALL"},
        {"min_range": -0.1}, {"max_range": 0.0}, {"max_range": math.inf},
        {"min_range": 3.0, "max_range": 2.0},
        {"beam_width": 0.0}, {"beam_width": math.pi}, {"beam_width": math.nan},
    ],
)
def test_bad_parameters_raise(bad: dict[str, object]) -> None:
    with pytest.raises(GridError, match="range sensor layer: ") as info:
        RangeSensorLayerParams(**bad)  # type: ignore[arg-type]
    assert isinstance(info.value, SonarcarveError)
    assert isinstance(info.value, ValueError)


@pytest.mark.parametrize(
    ("resolution", "bounds"),
    [(0.0, WIDE), (math.nan, WIDE), (True, WIDE), (0.1, (0.0, 0.0, 0.0, 1.0)),
     (0.1, (0.0, 0.0, math.inf, 1.0)), (0.1, (0.0, 0.0, 1.0)), (1e-6, (0.0, 0.0, 100.0, 100.0))],
)
def test_bad_grids_raise(resolution: float, bounds: tuple[float, float, float, float]) -> None:
    with pytest.raises(GridError):
        RangeSensorLayer(resolution, bounds)


@pytest.mark.parametrize(
    "call",
    [
        {"x": math.nan}, {"theta": math.inf}, {"beam_width": 0.0}, {"beam_width": 4.0},
        {"range": "far"},
    ],
)
def test_bad_add_range_arguments_raise(call: dict[str, object]) -> None:
    args: dict[str, object] = {"x": 0.05, "y": 0.55, "theta": 0.0, "range": 1.0}
    layer = RangeSensorLayer(H, WIDE)
    with pytest.raises(GridError):
        layer.add_range(**{**args, **call})  # type: ignore[arg-type]


def test_bad_threshold_raises() -> None:
    with pytest.raises(GridError):
        RangeSensorLayer(H, WIDE).occupied_points(1.0)
