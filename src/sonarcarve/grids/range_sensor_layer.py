"""ROS's ``range_sensor_layer`` re-implemented: the sonar map that ROS users actually get.

This is the costmap plugin ``RangeSensorLayer`` of ROS 1 (package ``range_sensor_layer``,
repository ros-planning/navigation_layers, formerly DLu/navigation_layers) and of ROS 2
(``nav2_costmap_2d::RangeSensorLayer``, ros-planning/navigation2), rewritten from its formulas
(no code copied). Sources read:

- ROS 2: ``nav2_costmap_2d/plugins/range_sensor_layer.cpp`` at navigation2 commit
  ``b6c36c3461d306095345ad33d3b9dd0a9ffffa1b`` (2024-07-02; the file last changed in
  ``bb0d177a8d739b3297126f14040e1a356ded9d94``, 2022-07-11), its header
  ``include/nav2_costmap_2d/range_sensor_layer.hpp`` (``to_prob``, ``to_cost``, ``area``,
  ``orient2d``) and ``src/costmap_2d.cpp`` (``worldToMap``, ``worldToMapNoBounds``,
  ``mapToWorld``, ``resetMaps``).
- ROS 1: ``range_sensor_layer/src/range_sensor_layer.cpp`` and ``cfg/RangeSensorLayer.cfg`` at
  DLu/navigation_layers commit ``b4e17b4aedf1b64c7b8c5691e8aef8f139311815`` (branch melodic,
  2021-01-07; noetic differs in whitespace only). The two versions compute the same map; they
  differ in plumbing (dynamic_reconfigure, an optional ``use_decay`` in ROS 1, how
  ``no_readings_timeout`` resets) and in one comparison noted below.

A baseline next to :mod:`sonarcarve.grids.elfes` (the Elfes/octomap log-odds grid, which only
borrows this layer's angular profile and distance fade): here is the layer itself, including its
quirks, so that a comparison with "what ROS does" is with what ROS does.

The model
---------
The layer keeps its own costmap of ``unsigned char`` costs ``c`` read as probabilities
``p = c / 254`` (``to_prob``) and written back as ``c = trunc(254 p)`` (``to_cost``). Every cell
starts at ``to_cost(0.5) = 127`` (the layer sets ``default_value_`` before ``matchSize()``), so
an unseen cell's prior is exactly 1/2 and the layer's own grid never holds ``NO_INFORMATION``
(255): the branch of ``updateCosts`` that skips 255 never fires for this layer.

A reading from origin ``o`` along ``θ`` with range ``r`` and field of view φ
(``max_angle = φ/2``) updates a cell whose centre lies at distance ``d`` (the source's ``phi``)
and off-axis angle ``α`` (``normalize_angle(atan2(...) - θ)``, in (-π, π]) with the *sensor
model* ``s(r, d, α)``:

- angular term ``γ(α) = 1 - (α / max_angle)²`` for ``|α| <= max_angle``, else 0;
- distance term ``δ(d) = 1 - (1 + tanh(2 (d - φ_v))) / 2 = 1 / (1 + exp(4 (d - φ_v)))``, with
  ``φ_v`` the parameter ``phi`` (1.2 by default);
- ``λ = δ(d) γ(α)``, and with the band fraction ``Δ`` equal to the costmap *resolution*
  (``double delta = resolution_``, a length used as a pure number):

  ============================  ============================================
  ``d < r - 2Δr``               ``s = (1 - λ) / 2``                  (free)
  ``r - 2Δr <= d < r - Δr``     ``s = λ/2 ((d - (r - 2Δr)) / (Δr))² + (1 - λ)/2``
  ``r - Δr <= d < r + Δr``      ``s = λ (1/2 - J²/2) + 1/2``, ``J = (r - d) / (Δr)``
  ``d >= r + Δr``               ``s = 1/2``                          (no information)
  ============================  ============================================

  so the occupied bump is ``2Δr`` wide: at 0.05 m cells and r = 2 m it spans r ± 0.1 m, and it
  grows with the range (the "band whose width is the resolution" is ``resolution × r``).
  ``s`` lies in [0, 1) and is exactly 1/2 wherever ``λ = 0`` (outside the beam).

The *update* (``update_cell``) is Bayes' rule with no clamp::

    p' = s p / (s p + (1 - s)(1 - p)),     p = c / 254,     c' = trunc(254 p')

A cleared cell (``clear_sensor_cone``) uses ``s = 0``, so ``p' = 0``: cost 0, and 0 is absorbing
(no later reading can raise it: ``s p = 0``).

Which cells a reading visits (``updateCostmap``): before anything else, the cell of the target
point ``o + r (cos θ, sin θ)`` is *set* to cost 233 if it lies in the map (its history is lost;
233/254 = 0.917 > the default mark threshold). Then the bounding box, in cell indices, of three
points: the origin ``O`` and the beam edges ``A``, ``B`` at ``1.2 r`` along ``θ ∓ max_angle``
(this 1.2 is a literal, not ``phi``), each converted with ``worldToMapNoBounds`` (truncation
toward zero, so -0.5 cells becomes 0), clipped to ``[0, size]``. With ``inflate_cone < 1``
only the cells ``P`` (integer indices) whose three edge functions ``orient2d(A, B, P)``,
``orient2d(B, O, P)``, ``orient2d(O, A, P)`` are all ``>= -inflate_cone · area(A, B, O)``
(a float32) are updated: 0 gives the integer triangle, 1 (the default) the whole box. Each
visited cell is updated at its centre (``mapToWorld``) if that centre is in the map
(``worldToMap``). With the default ``inflate_cone = 1`` a clearing reading therefore sets the
*whole box* to 0, cells behind and beside the beam included.

The *bounds* (``touch``) a reading adds to the layer's dirty rectangle: the origin, the target
(if in the map) and the two edge points ``A``, ``B`` (at 1.2 r).

*Range handling* (``processRangeMsg``, REP 117). A sensor with ``min_range == max_range`` is a
fixed-distance ranger (``input_sensor_type`` ALL; FIXED and VARIABLE force a path):

- fixed: only ±Inf is valid (anything else is logged and dropped). -Inf ("object detected")
  marks with ``r = min_range``; +Inf ("nothing detected") clears the cone at ``r = min_range``
  if ``clear_on_max_reading``, else is dropped;
- variable: a range below ``min_range`` or above ``max_range`` is dropped, so **-Inf and +Inf
  are both dropped** (REP 117's +Inf does not clear a variable-range sensor's cone). A range
  equal to ``max_range`` clears the cone if ``clear_on_max_reading`` (Nav2 tests
  ``>= max_range``, ROS 1 ``== max_range``: the same after the rejection above), else it is an
  ordinary reading that marks an arc at ``max_range``.

*Costs* (``updateCosts``), with ``mark = to_cost(mark_threshold)`` (203 by default) and
``clear = to_cost(clear_threshold)`` (50): a cell with cost ``c > mark`` becomes
``LETHAL_OBSTACLE`` (254), ``c < clear`` becomes ``FREE_SPACE`` (0), anything else leaves the
master costmap as it was. A master cell is overwritten when it is ``NO_INFORMATION`` or lower
than the new cost. :meth:`RangeSensorLayer.costs` is that, written into a master grid that holds
``NO_INFORMATION`` everywhere: 0, 254 or 255 per cell.

Defaults (ROS 1 ``RangeSensorLayer.cfg``; Nav2 ``onInitialize`` declares the same):
``phi = 1.2``, ``inflate_cone = 1.0`` (cfg range [0, 1]), ``no_readings_timeout = 0.0`` (off),
``clear_threshold = 0.2``, ``mark_threshold = 0.8`` (cfg ranges [0, 1]),
``clear_on_max_reading = false``, ``input_sensor_type = ALL``.

Deliberate differences
----------------------
1. *Geometry from the reading, not from tf.* ROS transforms the sensor frame's origin and the
   point ``(r, 0)`` and takes ``θ = atan2(...)``, ``d = |target - origin|``; here ``θ`` and ``r``
   come from the reading (equal up to float rounding). A reading's ``beam_width`` is the
   message's ``field_of_view``; NaN means :attr:`RangeSensorLayerParams.beam_width`.
2. *min_range / max_range are layer parameters* (one sensor model for every sensor), where ROS
   reads them from each message. Defaults: 0 and 6.477 m (the Scout2's 255-inch limit,
   ``robots/scout2.yaml``).
3. *NaN ranges are dropped* (REP 117: invalid). The layer does not test for NaN on the variable
   path (both range comparisons are false), so ROS goes on with undefined behaviour.
4. *No unsigned wrap-around.* When a beam's box lies entirely left of or below the map, ROS's
   loop ``for (unsigned x = 0; x <= (unsigned)bx1; ...)`` with ``bx1 < 0`` runs about 2³² empty
   iterations; here it runs none. The map is the same.
5. *A 0/0 update keeps the cell.* ``p = 1`` (cost 254) with ``s = 0`` is 0/0 in ROS (undefined
   conversion to ``unsigned char``); no ROS update reaches cost 254 (``s < 1`` and truncation),
   so this never happens with ``quantize=True``.
6. *No clock.* :meth:`RangeSensorLayer.is_current` implements ``no_readings_timeout`` against
   the readings' own times ``t`` (Nav2's rule; ROS 1 sets ``current_`` back to true in every
   ``updateCosts``, so its timeout is never seen); before the first reading the layer is
   current (ROS counts from the plugin's start). ROS 1's ``use_decay`` is not implemented.
7. *Stricter parameter checks* (:class:`RangeSensorLayerParams`): ``phi`` finite and > 0,
   ``clear_threshold <= mark_threshold``, ``0 <= min_range <= max_range``, finite values.
8. *Two opt-in extensions, off by default:* ``inf_is_max_reading`` turns +Inf from a
   variable-range sensor into a reading at ``max_range`` (what ROS sonar drivers commonly
   publish for "no echo", and what REP 117 means), instead of dropping it; ``quantize=False``
   keeps each cell's probability unrounded instead of ``trunc(254 p) / 254`` (costs in
   :meth:`~RangeSensorLayer.costs` are then compared unrounded with the same thresholds).
9. The state is a float64 array of costs (integral when ``quantize``), not ``unsigned char``;
   the arithmetic (``c / 254``, the Bayes quotient, ``trunc(254 p)``) is the layer's, in double
   precision, in the same order. Cells where ``s`` is exactly 1/2 (outside the beam, beyond
   ``r + Δr``) are skipped, which changes no cost: ``trunc(254 p')`` with ``s = 1/2`` gives back
   every cost 0..254 (checked in the tests against a line-by-line reference without the skip).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.grids.cells import CellGrid, GridError
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch
from sonarcarve.typing import BoolArray, FloatArray

__all__ = [
    "FREE_SPACE",
    "LETHAL_OBSTACLE",
    "MAX_LAYER_CELLS",
    "NO_INFORMATION",
    "ROS_EDGE_FACTOR",
    "ROS_TARGET_COST",
    "ROS_UNKNOWN_COST",
    "InputSensorType",
    "RangeSensorLayer",
    "RangeSensorLayerParams",
    "angular_term",
    "distance_term",
    "master_costs",
    "sensor_model",
]

CostArray = npt.NDArray[np.uint8]

#: costmap_2d's cost of a free cell.
FREE_SPACE = 0
#: costmap_2d's cost of an occupied cell; also the layer's probability scale (``p = c / 254``).
LETHAL_OBSTACLE = 254
#: costmap_2d's cost of an unknown cell.
NO_INFORMATION = 255
#: Cost the layer gives a cell at its start: ``to_cost(0.5) = trunc(0.5 · 254)``, p = 1/2.
ROS_UNKNOWN_COST = 127
#: Cost the layer *sets* the target cell to before each update (``setCost(aa, ab, 233)``).
ROS_TARGET_COST = 233
#: Distance of the beam-edge points that span a reading's box, in ranges (a literal in ROS).
ROS_EDGE_FACTOR = 1.2
#: Most cells a layer may have: 2**27 float64 cells are 1 GiB.
MAX_LAYER_CELLS = 2**27

#: The Scout2's range limit, metres (255 inches; ``robots/scout2.yaml``).
_DEFAULT_MAX_RANGE = 6.477
_SCALE = float(LETHAL_OBSTACLE)
_TWO_PI = 2.0 * math.pi


class InputSensorType(enum.Enum):
    """How the layer reads ``min_range`` and ``max_range`` (its ``input_sensor_type``)."""

    #: Fixed-distance ranger when ``min_range == max_range``, variable otherwise (the default).
    ALL = "all"
    #: Always a variable-range sensor.
    VARIABLE = "variable"
    #: Always a fixed-distance ranger (only ±Inf readings are valid).
    FIXED = "fixed"


def _check(ok: bool, name: str, rule: str, value: object) -> None:
    if not ok:
        msg = f"range sensor layer: {name} {rule}, got {value!r}"
        raise GridError(msg)


def _is_number(value: object) -> bool:
    return not isinstance(value, bool) and isinstance(value, int | float)


def _finite(value: object) -> bool:
    return _is_number(value) and math.isfinite(value)  # type: ignore[arg-type]


@dataclass(frozen=True)
class RangeSensorLayerParams:
    """The layer's parameters (ROS defaults) and the sensor's range limits.

    Attributes
    ----------
    phi : float
        ``φ_v``, metres > 0: centre of the distance term ``(1 - tanh(2 (d - φ_v))) / 2``
        (ROS ``phi``, 1.2).
    inflate_cone : float
        In [0, 1]: 0 updates only the beam's integer triangle, 1 its whole bounding box
        (ROS ``inflate_cone``, 1.0).
    no_readings_timeout : float
        Seconds >= 0; 0 switches it off (ROS ``no_readings_timeout``, 0.0).
    clear_threshold, mark_threshold : float
        Probabilities in [0, 1], ``clear <= mark``: a cell whose cost is below
        ``trunc(254 · clear)`` is free, above ``trunc(254 · mark)`` lethal
        (ROS ``clear_threshold`` 0.2, ``mark_threshold`` 0.8).
    clear_on_max_reading : bool
        A reading at ``max_range`` (fixed ranger: +Inf) clears the cone instead of marking
        (ROS ``clear_on_max_reading``, false).
    input_sensor_type : InputSensorType
        ROS ``input_sensor_type`` (ALL).
    min_range, max_range : float
        The sensor's limits, metres, ``0 <= min_range <= max_range``, ``max_range > 0`` (in ROS,
        fields of each ``sensor_msgs/Range``). Defaults 0 and 6.477 (Scout2).
    beam_width : float
        Field of view φ for readings whose beam width is NaN, radians in (0, π); 22.5°.
    inf_is_max_reading : bool
        Not in ROS (off): +Inf from a variable-range sensor becomes a reading at ``max_range``
        instead of being dropped.
    quantize : bool
        ROS's ``trunc(254 p)`` after every update (on); off keeps costs unrounded (not in ROS).

    Raises
    ------
    GridError
        A value out of its range (every check is listed above).
    """

    phi: float = 1.2
    inflate_cone: float = 1.0
    no_readings_timeout: float = 0.0
    clear_threshold: float = 0.2
    mark_threshold: float = 0.8
    clear_on_max_reading: bool = False
    input_sensor_type: InputSensorType = InputSensorType.ALL
    min_range: float = 0.0
    max_range: float = _DEFAULT_MAX_RANGE
    beam_width: float = DEFAULT_BEAM_WIDTH
    inf_is_max_reading: bool = False
    quantize: bool = True

    def __post_init__(self) -> None:
        _check(_finite(self.phi) and self.phi > 0.0, "phi", "must be a finite number > 0 metres",
               self.phi)
        _check(_finite(self.inflate_cone) and 0.0 <= self.inflate_cone <= 1.0, "inflate_cone",
               "must lie in [0, 1]", self.inflate_cone)
        _check(_finite(self.no_readings_timeout) and self.no_readings_timeout >= 0.0,
               "no_readings_timeout", "must be a finite number >= 0 seconds",
               self.no_readings_timeout)
        for name in ("clear_threshold", "mark_threshold"):
            value = getattr(self, name)
            _check(_finite(value) and 0.0 <= value <= 1.0, name, "must lie in [0, 1]", value)
        _check(self.clear_threshold <= self.mark_threshold, "clear_threshold",
               f"must not exceed mark_threshold ({self.mark_threshold!r})", self.clear_threshold)
        for name in ("clear_on_max_reading", "inf_is_max_reading", "quantize"):
            _check(isinstance(getattr(self, name), bool), name, "must be True or False",
                   getattr(self, name))
        _check(isinstance(self.input_sensor_type, InputSensorType), "input_sensor_type",
               "must be an InputSensorType", self.input_sensor_type)
        _check(_finite(self.min_range) and self.min_range >= 0.0, "min_range",
               "must be a finite number >= 0 metres", self.min_range)
        _check(_finite(self.max_range) and self.max_range > 0.0, "max_range",
               "must be a finite number > 0 metres", self.max_range)
        _check(self.min_range <= self.max_range, "min_range",
               f"must not exceed max_range ({self.max_range!r})", self.min_range)
        _check(_finite(self.beam_width) and 0.0 < self.beam_width < math.pi, "beam_width",
               "must lie in (0, pi) radians", self.beam_width)

    @property
    def fixed_ranger(self) -> bool:
        """Whether readings take the fixed-distance path (only ±Inf valid)."""
        if self.input_sensor_type is InputSensorType.ALL:
            return self.min_range == self.max_range
        return self.input_sensor_type is InputSensorType.FIXED

    @property
    def clear_cost(self) -> int:
        """``to_cost(clear_threshold)``: costs strictly below it are free (50 by default)."""
        return _to_cost(self.clear_threshold)

    @property
    def mark_cost(self) -> int:
        """``to_cost(mark_threshold)``: costs strictly above it are lethal (203 by default)."""
        return _to_cost(self.mark_threshold)


def _to_cost(p: float) -> int:
    """The layer's ``to_cost``: ``trunc(254 p)``."""
    return int(p * _SCALE)


# -- the sensor model ---------------------------------------------------------------------------

@compiled_inline
def angular_term(alpha: float, max_angle: float) -> float:
    """``γ(α) = 1 - (α / max_angle)²`` for ``|α| <= max_angle``, else 0 (ROS ``gamma``).

    ``alpha`` is the cell's angle off the beam's axis, radians; ``max_angle`` half the field of
    view.
    """
    if abs(alpha) > max_angle:
        return 0.0
    q = alpha / max_angle
    return 1.0 - q * q


@compiled_inline
def distance_term(d: float, phi: float) -> float:
    """``δ(d) = 1 - (1 + tanh(2 (d - φ_v))) / 2`` (ROS ``delta``), d and φ_v in metres."""
    return 1.0 - (1.0 + math.tanh(2.0 * (d - phi))) / 2.0


@compiled_inline
def sensor_model(r: float, d: float, alpha: float, max_angle: float, phi: float,
                 delta: float) -> float:
    """The layer's inverse sensor model ``s(r, d, α)`` (module docstring; ROS ``sensor_model``).

    Parameters
    ----------
    r : float
        The reading's range, metres.
    d : float
        Distance of the cell's centre from the sensor, metres (ROS's ``phi`` argument).
    alpha : float
        The cell's angle off the axis, radians.
    max_angle : float
        Half the field of view, radians.
    phi : float
        The distance term's centre ``φ_v``, metres (ROS parameter ``phi``).
    delta : float
        The band fraction Δ: ROS passes the costmap resolution (metres, used as a number).

    Returns
    -------
    float
        Probability of occupancy in [0, 1); 1/2 means no information.
    """
    lbda = distance_term(d, phi) * angular_term(alpha, max_angle)
    band = delta * r
    if 0.0 <= d < r - 2.0 * band:
        return (1.0 - lbda) * 0.5
    if d < r - band:
        q = (d - (r - 2.0 * band)) / band
        return lbda * 0.5 * q * q + (1.0 - lbda) * 0.5
    if d < r + band:
        j = (r - d) / band
        return lbda * ((1.0 - 0.5 * j * j) - 0.5) + 0.5
    return 0.5


@compiled_inline
def _normalize_angle(a: float) -> float:
    """ROS ``angles::normalize_angle``: the same angle in (-π, π]."""
    a = np.fmod(np.fmod(a, _TWO_PI) + _TWO_PI, _TWO_PI)
    if a > math.pi:
        a -= _TWO_PI
    return a


@compiled_inline
def _orient2d(ax: int, ay: int, bx: int, by: int, cx: int, cy: int) -> int:
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@compiled_inline
def _touch(box: FloatArray, x: float, y: float) -> None:
    box[0] = min(box[0], x)
    box[1] = min(box[1], y)
    box[2] = max(box[2], x)
    box[3] = max(box[3], y)


@compiled
def _update_kernel(cost: FloatArray, x0: float, y0: float, h: float, ox: FloatArray,
                   oy: FloatArray, theta: FloatArray, r: FloatArray, max_angle: FloatArray,
                   clear: BoolArray, phi: float, inflate_cone: float, quantize: bool,
                   box: FloatArray) -> None:
    """The layer's ``updateCostmap`` + ``update_cell`` for each reading in turn (module docstring).

    ``cost``, shape (ny, nx), is updated in place; ``box`` = (min_x, min_y, max_x, max_y)
    grows by every point the layer would ``touch``.
    """
    ny, nx = cost.shape
    for k in range(ox.shape[0]):
        oxk, oyk, rk, half = ox[k], oy[k], r[k], max_angle[k]
        th = _normalize_angle(theta[k])
        # The cone's three corners as cells: the sensor, and the beam's edges a little past
        # the range (worldToMapNoBounds: a C cast, truncation toward zero).
        Ox = int((oxk - x0) / h)
        Oy = int((oyk - y0) / h)
        _touch(box, oxk, oyk)
        _mark_target(cost, box, x0, y0, h, oxk, oyk, th, rk)
        reach = rk * ROS_EDGE_FACTOR
        Ax, Ay = _cone_corner(box, x0, y0, h, oxk, oyk, th - half, reach)
        Bx, By = _cone_corner(box, x0, y0, h, oxk, oyk, th + half, reach)
        bx0 = max(0, min(Ox, Ax, Bx))
        by0 = max(0, min(Oy, Ay, By))
        bx1 = min(nx, max(Ox, Ax, Bx))
        by1 = min(ny, max(Oy, Ay, By))
        # ROS stores -inflate_cone · area in a float.
        area = abs((Ax * (By - Oy) + Bx * (Oy - Ay) + Ox * (Ay - By)) / 2.0)
        threshold = float(np.float32(-inflate_cone * area))
        c, s, cos_half = math.cos(th), math.sin(th), math.cos(half)
        far = rk + h * rk  # r + Δr, as sensor_model computes it
        # With quantize, s = 1/2 exactly leaves every cost 0..254 unchanged (trunc(254 p') = c),
        # and s is exactly 1/2 beyond r + Δr and wherever γ = 0: such cells are skipped before
        # the costly atan2 and tanh. The bearing test keeps a margin (1e-9 in cosine, far above
        # atan2's rounding) so that only cells certainly outside the beam are skipped.
        skip_quiet = quantize and not clear[k]
        for mx in range(bx0, bx1 + 1):
            for my in range(by0, by1 + 1):
                if inflate_cone < 1.0:
                    w0 = _orient2d(Ax, Ay, Bx, By, mx, my)
                    w1 = _orient2d(Bx, By, Ox, Oy, mx, my)
                    w2 = _orient2d(Ox, Oy, Ax, Ay, mx, my)
                    if not (w0 >= threshold and w1 >= threshold and w2 >= threshold):
                        continue
                # mapToWorld, then worldToMap of that centre.
                wx = x0 + (mx + 0.5) * h
                wy = y0 + (my + 0.5) * h
                if wx < x0 or wy < y0:
                    continue
                cx = int((wx - x0) / h)
                cy = int((wy - y0) / h)
                if cx >= nx or cy >= ny:
                    continue
                dx = wx - oxk
                dy = wy - oyk
                d = math.sqrt(dx * dx + dy * dy)
                if skip_quiet and (d >= far or dx * c + dy * s < d * (cos_half - 1e-9)):
                    continue
                alpha = _normalize_angle(math.atan2(dy, dx) - th)
                sensor = 0.0 if clear[k] else sensor_model(rk, d, alpha, half, phi, h)
                _update_cell(cost, cx, cy, sensor, quantize)


@compiled_inline
def _mark_target(cost: FloatArray, box: FloatArray, x0: float, y0: float, h: float,
                 ox: float, oy: float, th: float, r: float) -> None:
    """The cell at the range on the axis set to the target cost, as ``updateCostmap`` does
    first, when it lies on the map (worldToMap)."""
    ny, nx = cost.shape
    tx = ox + math.cos(th) * r
    ty = oy + math.sin(th) * r
    if tx >= x0 and ty >= y0:
        tmx = int((tx - x0) / h)
        tmy = int((ty - y0) / h)
        if tmx < nx and tmy < ny:
            cost[tmy, tmx] = float(ROS_TARGET_COST)
            _touch(box, tx, ty)


@compiled_inline
def _cone_corner(box: FloatArray, x0: float, y0: float, h: float, ox: float, oy: float,
                 angle: float, reach: float) -> tuple[int, int]:
    """The cell of the cone's corner at ``angle`` and ``reach`` from the sensor
    (worldToMapNoBounds), the point touched."""
    x = ox + math.cos(angle) * reach
    y = oy + math.sin(angle) * reach
    _touch(box, x, y)
    return int((x - x0) / h), int((y - y0) / h)


@compiled_inline
def _update_cell(cost: FloatArray, cx: int, cy: int, sensor: float, quantize: bool) -> None:
    """ROS's ``update_cell``: Bayes' rule with the cell's cost as the prior, the sensor
    model's probability as the likelihood; truncated to whole costs with ``quantize``."""
    prior = cost[cy, cx] / 254.0
    prob_occ = sensor * prior
    prob_not = (1.0 - sensor) * (1.0 - prior)
    total = prob_occ + prob_not
    if total == 0.0:  # 0/0: prior 1 and a clearing reading (docstring, item 5)
        return
    updated = prob_occ / total * 254.0
    cost[cy, cx] = float(int(updated)) if quantize else updated


# -- costs --------------------------------------------------------------------------------------

def master_costs(layer_costs: npt.ArrayLike, clear_threshold: float = 0.2,
                 mark_threshold: float = 0.8) -> CostArray:
    """What the layer's ``updateCosts`` writes into a master costmap full of NO_INFORMATION.

    Parameters
    ----------
    layer_costs : array-like, shape (rows, columns)
        The layer's own costs (0..255; probabilities times 254).
    clear_threshold, mark_threshold : float
        The layer's thresholds, probabilities.

    Returns
    -------
    ndarray of uint8, shape (rows, columns)
        :data:`LETHAL_OBSTACLE` where ``c > trunc(254 · mark_threshold)``, :data:`FREE_SPACE`
        where ``c < trunc(254 · clear_threshold)``, :data:`NO_INFORMATION` elsewhere and where
        ``c`` is itself NO_INFORMATION.

    Examples
    --------
    >>> master_costs([[0, 49, 50, 127], [203, 204, 254, 255]]).tolist()
    [[0, 0, 255, 255], [255, 254, 254, 255]]
    """
    c = np.asarray(layer_costs, dtype=np.float64)
    out = np.full(c.shape, NO_INFORMATION, dtype=np.uint8)
    known = c != NO_INFORMATION
    out[known & (c > _to_cost(mark_threshold))] = LETHAL_OBSTACLE
    out[known & (c < _to_cost(clear_threshold))] = FREE_SPACE
    return out


# -- the layer ----------------------------------------------------------------------------------

class RangeSensorLayer(CellGrid):
    """ROS's ``RangeSensorLayer`` over a rectangle of the world (module docstring).

    Cell ``(i, j)`` (row ``i`` along y, column ``j`` along x; ROS's ``(mx, my) = (j, i)``) is
    the square of side ``resolution`` whose lower-left corner is
    ``(xmin + j h, ymin + i h)``: the costmap's origin is ``(xmin, ymin)``. The layer has
    ``ceil((xmax - xmin) / h)`` columns and ``ceil((ymax - ymin) / h)`` rows.

    Parameters
    ----------
    resolution : float
        Cell side h, metres (> 0). Also the sensor model's band fraction Δ, as in ROS.
    bounds : tuple of 4 floats
        ``(xmin, ymin, xmax, ymax)``, metres.
    params : RangeSensorLayerParams, optional
        Default: ROS's defaults.

    Attributes
    ----------
    readings : int
        Readings that reached the map (ROS ``buffered_readings_``, never reset here).
    dropped : int
        Readings the range checks dropped (out of range, NaN, a finite value from a fixed
        ranger, +Inf from a fixed ranger without ``clear_on_max_reading``).

    Raises
    ------
    GridError
        A resolution or bounds not finite, not positive, or needing more than
        :data:`MAX_LAYER_CELLS` cells.

    Examples
    --------
    >>> layer = RangeSensorLayer(0.1, (0.0, 0.0, 2.0, 1.0))
    >>> layer.shape
    (10, 20)
    >>> layer.add(Reading(t=0.0, sensor=0, x=0.05, y=0.55, theta=0.0, range=1.04))
    >>> c = layer.layer_costs()
    >>> int(c[5, 0]), int(c[5, 5]), int(c[5, 10]), int(c[5, 15])  # origin, free, target, beyond
    (1, 7, 248, 127)
    >>> layer.costs()[5, [0, 5, 10, 15]].tolist()  # free, free, lethal, unknown
    [0, 0, 254, 255]
    >>> layer.add_range(0.05, 0.55, 0.0, math.inf)  # +Inf from a variable sensor: dropped
    False
    """

    def __init__(self, resolution: float, bounds: tuple[float, float, float, float],
                 params: RangeSensorLayerParams | None = None) -> None:
        super().__init__("range sensor layer", resolution, bounds, MAX_LAYER_CELLS,
                         "MAX_LAYER_CELLS")
        ny, nx = self._shape
        self._params = params if params is not None else RangeSensorLayerParams()
        self._cost: FloatArray = np.full((ny, nx), float(ROS_UNKNOWN_COST))
        self._box = np.array([math.inf, math.inf, -math.inf, -math.inf])
        self._last_t = math.nan
        self.readings = 0
        self.dropped = 0

    def __repr__(self) -> str:
        ny, nx = self.shape
        return (f"RangeSensorLayer({self._resolution:g} m, {nx} x {ny} cells, "
                f"bounds={self._bounds}, {self.readings} readings)")

    @property
    def params(self) -> RangeSensorLayerParams:
        """The layer's parameters."""
        return self._params

    # -- updates -------------------------------------------------------------------------------

    def add(self, reading: Reading) -> None:
        """Fold one reading in (validated like a :class:`ReadingBatch` row)."""
        self.add_many(ReadingBatch.from_readings([reading]))

    def add_many(self, batch: ReadingBatch) -> None:
        """Fold every reading of ``batch`` in, in order (REP 117 handling: module docstring).

        A no-echo reading (``range`` = +inf) is handled as ROS handles +Inf: dropped by a
        variable-range sensor, unless :attr:`RangeSensorLayerParams.inf_is_max_reading`, which
        makes it a reading at the layer's ``max_range`` that clears the cone (no mark) when
        ``clear_on_max_reading`` is on. The reading's own ``max_range`` is not used: the layer's
        limits are its parameters (module docstring, item 2).
        """
        self._fold(batch.x, batch.y, batch.theta, batch.range, batch.beam_width, batch.t)

    def add_range(self, x: float, y: float, theta: float, range: float,
                  beam_width: float = math.nan, t: float = math.nan) -> bool:
        """Fold in one range as ROS receives it: ``range`` may be +Inf, -Inf or NaN (REP 117).

        Parameters
        ----------
        x, y, theta : float
            Sensor origin (metres) and axis (radians) in the world frame; finite.
        range : float
            Metres, or ±Inf / NaN.
        beam_width : float
            Field of view, radians in (0, π); NaN: :attr:`RangeSensorLayerParams.beam_width`.
        t : float
            Time of the reading, seconds, for :meth:`is_current`; NaN: not recorded.

        Returns
        -------
        bool
            Whether the reading reached the map (False: dropped by the range checks).

        Raises
        ------
        GridError
            A non-finite pose or a beam width outside (0, π).
        """
        for name, value in (("x", x), ("y", y), ("theta", theta)):
            _check(_finite(value), name, "must be a finite number", value)
        _check(_is_number(range), "range", "must be a number", range)
        _check(_is_number(beam_width) and (math.isnan(beam_width) or 0.0 < beam_width < math.pi),
               "beam_width", "must lie in (0, pi) radians or be NaN", beam_width)
        before = self.readings
        self._fold(np.array([x], dtype=np.float64), np.array([y], dtype=np.float64),
                   np.array([theta], dtype=np.float64), np.array([range], dtype=np.float64),
                   np.array([beam_width], dtype=np.float64), np.array([t], dtype=np.float64))
        return self.readings > before

    def _fold(self, x: FloatArray, y: FloatArray, theta: FloatArray, r: FloatArray,
              width: FloatArray, t: FloatArray) -> None:
        keep, r_used, clear = self._dispatch(r)
        self.dropped += int(np.count_nonzero(~keep))
        if not keep.any():
            return
        fov = np.where(np.isnan(width[keep]), self._params.beam_width, width[keep])
        p = self._params
        _update_kernel(self._cost, self._bounds[0], self._bounds[1], self._resolution,
                       np.ascontiguousarray(x[keep]), np.ascontiguousarray(y[keep]),
                       np.ascontiguousarray(theta[keep]), np.ascontiguousarray(r_used[keep]),
                       np.ascontiguousarray(0.5 * fov), np.ascontiguousarray(clear[keep]),
                       p.phi, p.inflate_cone, p.quantize, self._box)
        self.readings += int(np.count_nonzero(keep))
        times = t[keep]
        if not np.isnan(times[-1]):
            self._last_t = float(times[-1])

    def _dispatch(self, r: FloatArray) -> tuple[BoolArray, FloatArray, BoolArray]:
        """``processRangeMsg``: which readings reach the map, at what range, and which clear."""
        p = self._params
        if p.fixed_ranger:
            keep = np.isinf(r) & ((r < 0.0) | p.clear_on_max_reading)
            return keep, np.full(r.shape, p.min_range), keep & (r > 0.0)
        if p.inf_is_max_reading:
            r = np.where(r == math.inf, p.max_range, r)
        keep = (r >= p.min_range) & (r <= p.max_range)  # False for NaN (item 3)
        clear = keep & (r >= p.max_range) & p.clear_on_max_reading
        return keep, r, clear

    def reset(self) -> None:
        """Forget everything (ROS ``reset``): every cell back to cost 127, bounds emptied."""
        self._cost.fill(float(ROS_UNKNOWN_COST))
        self._box[:] = (math.inf, math.inf, -math.inf, -math.inf)
        self._last_t = math.nan
        self.readings = 0
        self.dropped = 0

    # -- the layer's outputs -------------------------------------------------------------------

    def take_touched_bounds(self) -> tuple[float, float, float, float] | None:
        """The world rectangle ``(min_x, min_y, max_x, max_y)`` the readings touched since the
        last call, then forget it (ROS ``updateBounds`` + ``resetRange``); None if none did."""
        box = self._box
        if not box[0] <= box[2]:
            return None
        out = (float(box[0]), float(box[1]), float(box[2]), float(box[3]))
        box[:] = (math.inf, math.inf, -math.inf, -math.inf)
        return out

    def is_current(self, now: float) -> bool:
        """Whether a reading reached the map within ``no_readings_timeout`` seconds before
        ``now`` (Nav2's rule; always True with a timeout of 0 or before the first reading)."""
        timeout = self._params.no_readings_timeout
        if timeout <= 0.0 or math.isnan(self._last_t):
            return True
        return now - self._last_t <= timeout

    def layer_costs(self) -> CostArray:
        """The layer's own costmap, shape :attr:`shape`: 0..254, 127 unseen (``trunc`` of the
        stored costs when ``quantize`` is off)."""
        return np.asarray(np.floor(self._cost), dtype=np.uint8)

    def probabilities(self) -> FloatArray:
        """Occupancy probability of every cell, ``c / 254``, shape :attr:`shape`."""
        return np.asarray(self._cost / _SCALE, dtype=np.float64)

    def costs(self) -> CostArray:
        """The trinary costmap the layer writes into an unknown master (:func:`master_costs`):
        FREE_SPACE 0, LETHAL_OBSTACLE 254, NO_INFORMATION 255; shape :attr:`shape`."""
        return master_costs(self._cost, self._params.clear_threshold,
                            self._params.mark_threshold)

    def occupied_mask(self, threshold: float | None = None) -> BoolArray:
        """Occupied cells, shape :attr:`shape`: with ``threshold`` None, those :meth:`costs`
        marks lethal; else those whose probability is strictly above ``threshold`` (in (0, 1))."""
        if threshold is None:
            return np.asarray(self.costs() == LETHAL_OBSTACLE)
        _check(_finite(threshold) and 0.0 < threshold < 1.0, "threshold", "must lie in (0, 1)",
               threshold)
        return np.asarray(self.probabilities() > threshold)

    def occupied_points(self, threshold: float | None = None) -> FloatArray:
        """Centres of the occupied cells (:meth:`occupied_mask`), shape (n, 2), metres.

        Row-major order (by y, then x), like
        :meth:`~sonarcarve.grids.elfes.OccupancyGrid.occupied_points`.
        """
        rows, cols = np.nonzero(self.occupied_mask(threshold))
        xs, ys = self.cell_centers()
        return np.column_stack((xs[cols], ys[rows])).astype(np.float64)
