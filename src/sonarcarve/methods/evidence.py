"""Evidence carving: carving by accumulated free-space evidence, with ATM and confidence.

Beyond the paper, following its section 6 (future work): ATM and carving integrated, certainty
values per point, noise in range. The geometry and the sensor model are in
:mod:`sonarcarve.geometry.evidence`; this module keeps the per-arc state over a shared
:class:`~sonarcarve.history.SonarHistory` and turns it into points.

Per arc (the equations: the geometry package and ``docs/evidence-carving.md``):

* a profile of ``K`` bins across the full beam, each with evidence that it is empty (log-odds
  of misses of newer readings, weighted by how likely each was to hear a surface there) and
  support (newer echo circles through it); a bin is carved at ``T = -log(1 - P_carve)``;
* occlusion: bins of a new arc behind a surface the history holds with confidence are carved
  (multipath echoes read too long, behind walls the beam met at a glancing angle);
* transmission: a newer beam that passed a bin obliquely and whose echo beyond it is confirmed
  by other sensors says the sound went through (times ``cos γ``, so a beam running along a
  wall does not carve it);
* split arcs are kept: the surviving run with the most localised support (support times the
  sine of the angle at which the echo circles meet: tangent repeats of one range say nothing of
  the bearing) and ATM crossings, its bound covering every surviving run (honest: the echo may
  lie in any of them);
* once evidence has cut the beam, the point at the median of a posterior over the kept run's
  bins: each bin's chance that every newer reading that looked there missed a surface there
  (``exp(-F)``, its free evidence F) times its localised support (equal weights: the run's
  middle, eq. 3.6; :func:`~sonarcarve.geometry.evidence.evidence_estimates`), the bound
  measured from there; a beam nothing has cut keeps its middle (its crossings may be ghosts:
  two jambs' circles meet in the doorway; :attr:`EvidenceOptions.uncut_posterior` places it
  too);
* ATM crossings counted only inside the kept run; a crossing confirms the run, and from
  ``min_atm_crossings`` (3) crossings in it their median places the point when its bound
  (eq. 5.4) is the smaller (``source = atm``; section 4's rule);
* a confidence per point: a logistic model of the evidence the arc has gathered (support,
  support from distinct viewpoints and from other sensors, crossings, free and looked-through
  evidence, runs, occlusion, the support of the surface the beam passed, range, width,
  whether the sensor heard the point again as it drove at it: a repeat,
  :mod:`~sonarcarve.geometry.repeats`; how far the echo lies behind surfaces the arcs after it
  confirm, judged as it leaves the history, :mod:`~sonarcarve.geometry.evidence.behind`;
  whether no other sensor's beam ever held it, :mod:`~sonarcarve.geometry.evidence.watch`;
  :class:`ConfidenceModel`), its weights fitted on the
  simulator's truth of one world (``benchmarks/fit_confidence.py``); points below
  ``min_confidence`` are left out of the maps (the default map), so "removed" means: not in
  the map the method outputs.

``processed`` (Table I) is: received evidence (free, support or occlusion) or has a crossing.

A no-echo reading adds its free-space evidence up to ``max_range - ε``
(:func:`~sonarcarve.geometry.evidence.evidence_free`) and no arc.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from numbers import Integral, Real
from typing import Any

import numpy as np
import numpy.typing as npt

from sonarcarve.constants import DEFAULT_BEAM_WIDTH, POLAROID_RANGE_RESOLUTION
from sonarcarve.errors import ConfigError
from sonarcarve.geometry._compiled import compiled, compiled_inline
from sonarcarve.geometry.evidence import (
    EVIDENCE_ALIVE,
    EstimateRules,
    EvidenceParams,
    PieceEstimates,
    SilentReading,
    evidence_add_many,
    evidence_estimates,
    evidence_free,
    evidence_threshold,
    mark_watch,
    mark_watched_by_silence,
)
from sonarcarve.geometry.evidence.arrays import (
    AddScratch,
    ArcEvidence,
    ArcShapes,
    BinEvidence,
    PlainBundle,
    plain,
)
from sonarcarve.geometry.fate import FULLY_CARVED, UNCHANGED
from sonarcarve.geometry.repeats import mark_repeats
from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.maps import (
    SOURCE_ATM,
    SOURCE_CARVED,
    SOURCE_CENTERLINE,
    GlobalMap,
)
from sonarcarve.methods.atm import CrossingStore, atm_error_bound
from sonarcarve.methods.base import (
    ArcModel,
    Estimates,
    Measures,
    SonarMethod,
    arc_point,
    slot_indices,
)
from sonarcarve.methods.config import (
    DEFAULT_CARVE_PROBABILITY,
    DEFAULT_EVIDENCE_BINS,
    DEFAULT_MIN_CONFIDENCE,
    DEFAULT_MIN_TRANSVERSAL,
    DEFAULT_RANGE_TOLERANCE,
    MethodConfig,
)
from sonarcarve.readings import Reading
from sonarcarve.typing import BoolArray, FloatArray, Int8Array, SlotArray

__all__ = ["CONFIDENCE_FEATURES", "ConfidenceModel", "EvidenceMethod", "EvidenceModel",
           "EvidenceOptions", "SensorModel"]


#: A field's rule: what a valid value satisfies, and how the error message says it.
_Rule = tuple[Callable[[float], bool], str]


def _check_fields(owner: object, rules: dict[str, _Rule]) -> None:
    """:class:`~sonarcarve.errors.ConfigError` for the first field of ``owner`` that is no
    real number or breaks its rule (NaN breaks every rule: comparisons with it are false)."""
    for name, (ok, rule) in rules.items():
        value = getattr(owner, name)
        if isinstance(value, bool) or not isinstance(value, Real) or not ok(float(value)):
            msg = f"{type(owner).__name__}.{name} must {rule}, got {value!r}"
            raise ConfigError(msg)


def _check_min_atm_crossings(value: object) -> None:
    """ConfigError unless ``value`` is an int >= 1 (0 would let an arc with no crossing take
    ATM's median of nothing)."""
    if isinstance(value, bool) or not isinstance(value, Integral) or value < 1:
        msg = f"min_atm_crossings must be an int >= 1, got {value!r}"
        raise ConfigError(msg)


def _fraction(v: float) -> bool:
    return 0.0 <= v <= 1.0


def _finite_at_least_zero(v: float) -> bool:
    return 0.0 <= v < math.inf


@dataclass(frozen=True)
class SensorModel:
    """How likely a reading was to hear a surface (:mod:`sonarcarve.geometry.evidence`).

    Defaults are judgements from what is quoted for Polaroid-class sensors on indoor walls, not
    fitted to the simulator (no source beyond those named here was checked). The main lobe falls
    to about half its sensitivity at the nominal beam edge (``edge_gain``): a 38.4 mm piston at
    49.4 kHz has its first nulls 12.7° off the axis, just past the 11.25° half-beam
    (:class:`~sonarcarve.sim.amplitude.AmplitudeModel`, from the 600-series datasheet). Smooth
    walls return echoes within the 15-20° of the normal commonly quoted for these transducers
    (as :class:`~sonarcarve.sim.sonar.SonarPhysics`'s ``critical_angle``, also assumed), so
    the gain is full below 10° and nothing but roughness above 30°, wider on both sides to
    leave room for rough walls. 5 % of glancing looks still hear rough walls, edges and corners
    (``rough``), and detection halves at 20 m (``range_scale``): both judgements.

    ``support_tolerance`` (ε_s, metres: a newer echo within ε_s of a point's distance supports
    it) stays 5 cm when a user widens the range tolerance ε: measured
    (``benchmarks/sonar_conditions.py``, range noise σ 5 cm, ε 10 cm; ``pose_error.py``, poses
    off by 5 cm, ε 15 cm), ε_s = ε keeps about 5 points more of the direct echoes but removes
    4-5 points fewer of the spurious ones over four worlds (about 16 fewer on the doorway under
    pose noise): a wide band lets nearby echoes support a phantom.
    """

    edge_gain: float = 0.5
    incidence_full: float = math.radians(10.0)
    incidence_zero: float = math.radians(30.0)
    rough: float = 0.05
    max_detect: float = 0.95
    range_scale: float = 20.0
    support_tolerance: float = 0.05
    establish: float = 1.0
    protect: float = 0.5
    viewpoint_spacing: float = 0.25
    transmit: float = 1.0
    confirm: float = 1.0

    def __post_init__(self) -> None:
        """Refuse values the equations cannot take (ranges of
        :class:`~sonarcarve.geometry.evidence.EvidenceParams`) with ConfigError."""
        right = 0.5 * math.pi
        _check_fields(self, {
            "edge_gain": (lambda v: 0.0 < v <= 1.0, "lie in (0, 1]"),
            "incidence_full": (lambda v: 0.0 <= v < right, "lie in [0, pi/2) radians"),
            # The gain falls linearly between the two: they must differ (no division by 0).
            "incidence_zero": (lambda v: self.incidence_full < v <= right,
                               "lie above incidence_full and at most pi/2 radians"),
            "rough": (_fraction, "lie in [0, 1]"),
            # 1 would make one miss infinite evidence (-log(1 - P)).
            "max_detect": (lambda v: 0.0 < v < 1.0, "lie in (0, 1)"),
            "range_scale": (lambda v: v > 0.0, "be > 0 metres (inf: no fall with range)"),
            "support_tolerance": (_finite_at_least_zero, "be finite and >= 0 metres"),
            "establish": (lambda v: v > 0.0, "be > 0 (inf: no bin is ever established)"),
            "protect": (_fraction, "lie in [0, 1]"),
            "viewpoint_spacing": (_finite_at_least_zero, "be finite and >= 0 metres"),
            "transmit": (_fraction, "lie in [0, 1]"),
            "confirm": (lambda v: 0.0 < v < math.inf, "be finite and > 0"),
        })

    def params(self, range_tolerance: float, threshold: float, min_transversal: float, *,
               with_occlusion: bool = True, with_transmission: bool = True) -> EvidenceParams:
        """The kernels' :class:`~sonarcarve.geometry.evidence.EvidenceParams` of this sensor
        with ε = ``range_tolerance`` metres, the carving ``threshold`` (evidence) and ATM's ψ
        = ``min_transversal`` radians; ``with_occlusion=False`` never establishes a bin
        (``establish`` = inf), ``with_transmission=False`` weighs no transmission evidence."""
        return EvidenceParams(
            tolerance=range_tolerance, support_tolerance=self.support_tolerance,
            edge_gain=self.edge_gain, incidence_full=self.incidence_full,
            incidence_zero=self.incidence_zero, rough=self.rough,
            max_detect=self.max_detect, range_scale=self.range_scale,
            threshold=threshold,
            establish=self.establish if with_occlusion else math.inf,
            cos_psi=math.cos(min_transversal), protect=self.protect,
            viewpoint_spacing=self.viewpoint_spacing,
            transmit=self.transmit if with_transmission else 0.0,
            confirm=self.confirm,
        )


@dataclass(frozen=True)
class EvidenceOptions:
    """The switches of evidence carving: parts to switch off (ablation) and the placement
    rules, passed unchanged from :class:`EvidenceMethod` to :class:`EvidenceModel`.

    Attributes
    ----------
    atm : bool
        Find and use ATM crossings.
    occlusion : bool
        Carve bins behind established surfaces (the multipath rule).
    transmission : bool
        Transmission evidence (a newer echo confirmed by other sensors behind a bin).
    located_placement : bool
        Place the point by the evidence instead of at the kept run's middle (eq. 3.6): with
        ``posterior_placement``, at the median of the posterior over the run's bins
        (:func:`~sonarcarve.geometry.evidence.evidence_estimates`); without it (the placement
        before issue 9's point accuracy work), once evidence has cut the beam, at the median
        of the run's localised support.
    posterior_placement : bool
        See ``located_placement`` (off, the placement before issue 9's point accuracy work
        also needs ``min_atm_crossings=1``).
    uncut_posterior : bool
        With ``posterior_placement``, place the point of a beam nothing has cut by the
        posterior too (``exp(-F)`` times its localised support: no bin of an uncut beam
        reached the threshold, so the support mostly decides); off (the default): its middle,
        eq. 3.6.
    min_atm_crossings : int
        ATM's median inside the kept run places the point only when the run holds at least
        this many crossings (>= 1; and its bound, eq. 5.4, is the smaller): with fewer, the
        median is one or two crossings themselves, which a single ghost moves (1: any
        crossing, the rule before issue 9's point accuracy work).
    keep_split : bool
        Keep a piece of an arc the evidence splits into several runs, with a bound over every
        run (issue 9, part 3); off, such an arc leaves the maps, as the paper drops an arc
        that carving splits (the ablation's row for this part alone).

    Examples
    --------
    >>> EvidenceOptions(atm=False).min_atm_crossings
    3
    """

    atm: bool = True
    occlusion: bool = True
    transmission: bool = True
    located_placement: bool = True
    posterior_placement: bool = True
    uncut_posterior: bool = False
    min_atm_crossings: int = 3
    keep_split: bool = True

    def __post_init__(self) -> None:
        _check_min_atm_crossings(self.min_atm_crossings)


#: The confidence's features, in the order of :meth:`ConfidenceModel.weights` (module
#: docstring): each is known when the arc is committed, and for the local map at any time
#: (``behind`` is 0 until the arc leaves the history).
CONFIDENCE_FEATURES = ("support", "viewpoints", "crossings", "free", "looked", "split",
                       "occluded", "unheard", "range", "width", "others", "through",
                       "repeated", "behind", "alone")


@dataclass(frozen=True)
class ConfidenceModel:
    """Logistic confidence of a point: ``σ(fresh + m (intercept + Σ w_f x_f - fresh))``, ``m``
    the maturity.

    The features (:data:`CONFIDENCE_FEATURES`, see :meth:`EvidenceMethod.features`) are the
    evidence an arc has gathered: ``support`` (largest bin support in the kept run, capped at
    3), ``viewpoints`` (support from distinct viewpoints, capped at 3), ``crossings`` (ATM
    crossings in the kept run, capped at 3), ``free`` (mean free evidence over the kept run in
    units of T), ``looked`` (looked-through evidence from distinct viewpoints in units of T,
    capped at 3), ``split`` (surviving runs - 1, capped at 3), ``occluded`` (share of the beam
    carved by occlusion), ``unheard`` (never supported, times the maturity), ``range``
    (metres), ``width`` (kept run over the full beam), ``others`` (support from other
    sensors per ``looks_per_support`` of their looks, capped at 1: a sensor's own repeated
    echoes can repeat one systematic error, so they confirm less than another transducer does;
    see "Other rings" below), ``through`` (support of the surface
    the echo's beam passed on its way, capped at 3: multipath echoes read from behind walls)
    and ``repeated`` (1 if another echo of the arc's sensor in the history is a *repeat* of it,
    :mod:`sonarcarve.geometry.repeats`: internally tangent circles, the touch point inside
    both beams, origins more than 2ε apart; the sensor drove at what it hears. Direct echoes
    heard by one sensor alone, which ``others`` cannot confirm, often have one; spurious
    echoes almost never do: ``benchmarks/repeat_echoes.py``) and ``behind`` (metres, capped
    at 3: ``r - d``, ``d`` the distance from the arc's origin to the nearest axis point inside
    its beam nearer than ``r - 2ε`` among the 64 arcs after it that are alive and heard from
    distinct viewpoints; 0 if none; :mod:`~sonarcarve.geometry.evidence.behind`) and
    ``alone`` (1 if no other sensor's beam held the arc's axis point, at any angle and range,
    in the history: :mod:`~sonarcarve.geometry.evidence.watch`, "Covered"). Paper, section 6:
    certainty values per point.

    ``alone`` is counted within the history, so it depends on ``history_size``: with a short
    history fewer arcs are covered. On a robot with one sonar, or sonars that never share a
    point, every arc is alone and the feature is a constant +0.674 on every logit, a shift of
    the intercept. Measured on one forward sonar and on a front/back pair (RESULTS, "The
    ``others`` feature on other rings"): it keeps 3-5 points more direct echoes under specular
    physics and removes at most 2 points fewer spurious ones, all crosstalk; a confidence
    fitted on such a robot would be the principled fix.

    Other rings: ``others`` was fitted on a ring whose beams just meet; it fails both ways on
    others (``docs/RESULTS.md``, "The ``others`` feature on other rings", where both fixes
    below are measured). Where beams do not overlap (15° beams 22.5° apart) a wall one sensor
    faces gets no support from another, and the fitted weight (3.3) reads it as a phantom:
    ``alone`` says that no other sensor's beam held the arc at all. Only its weight was fitted
    (``benchmarks/fit_confidence.py --only alone``, the other weights held, with
    ``looks_per_support`` inf): 0.674, a fifth of the missing ``others``. Where beams overlap
    (45° beams 22.5° apart) a neighbour's echo circle crosses a phantom inside the shared part
    of the beams and "confirms" it. ``looks_per_support`` ``k`` counts the support per ``k``
    looks of other sensors (``covering``: readings of another sensor whose beam held the arc's
    axis point, at any range), ``min(others / max(covering / k, 1), 1)``; the default, inf,
    leaves ``others`` as fitted. ``k`` = 16 (the smallest of 4, 8, 12, 16, 24 and 32 costing at
    most 0.5 points of direct echoes on each development world and physics; no fit: refitting
    ``others`` with it gives a worse log-loss on the training runs at every value tried)
    removes 6 more points of the 45° amplitude ring's spurious echoes, but costs the car
    park's amplitude sonars 4-6 points of direct echoes and the Pioneer's front ring 1-2: not
    kept.

    ``behind`` is judged only when the arc leaves the history, so it is 0 for every arc in the
    history, and for the arcs still there when a log ends (committed unjudged): the live map
    does not depend on it. Only its weight was fitted (``benchmarks/fit_confidence.py --only
    behind``, the other weights held): with 0 the confidence of an arc in the history is
    exactly what it was before the feature, so the live map is the same bit for bit and only
    the arcs that leave the history, judged, can score lower. A multipath echo reads too long,
    behind a wall the ring hears directly, mostly *after* the echo arrived (the occlusion rule,
    which looks on arrival, misses it); a door jamb's echo has nothing nearer inside its beam.
    Measured in one run against the weight 0: held-out floors, specular physics, direct kept /
    spurious removed 96.1 / 79.8 → 95.9 / 82.2 % (multipath 74.8 → 79.4), rough 90.1 / 78.0 →
    89.9 / 80.3, brick 90.6 / 85.2 → 90.1 / 85.2; office / specular removed 86.0 → 88.5,
    t-junction / specular 68.2 → 70.4, the other development pairs unchanged but for 0.1 of
    kept. Taken on arrival too and all weights refitted (reverted commits 8f1edc4, 9f7da7a), it made
    the live map keep a person who had left for seconds, and the refit weighed ``range`` up
    (``docs/evidence-carving.md``, "Behind").

    Maturity: the features are fitted on arcs as they leave the history, when the ring has
    looked again many times; a fresh arc has had no chance to be supported or seen through. So
    the logit moves from ``fresh`` (the log-odds of the share of direct echoes among the
    training arcs: what is known of an arc before any evidence) to the fitted one as the arc
    ages, linearly over ``maturity_time`` seconds: a fresh point is shown at once, so no
    latency is added. The time is fitted too, on the same runs: of a grid of times, the one
    whose confidence has the smallest log-loss over the arcs of the local map, sampled every 20
    readings. It is 2 s. The earlier guess, 1 s (one cycle of a Scout-class ring), moved the
    logit before the support had come: in the office, 9 % of the direct echoes 0.5-0.75 s old
    fell below 0.5 and left the local map for a while (1.7 % of those older than 5 s); with
    2 s, none under 0.75 s old do. The price: young spurious echoes stay in the local map
    longer (of those under 2 s old, 44 % are hidden instead of 67 %).

    Watched (``unwatched_prior``): an arc that no distinct reading (another sensor, or its own
    from at least ``viewpoint_spacing`` away) looked at squarely, from within the sensor
    model's ``incidence_zero`` (30°) of its own direction
    (:mod:`~sonarcarve.geometry.evidence.watch`), but that something supported (its own
    sensor heard it again, mostly), never matures: its confidence stays the prior, ``σ(fresh)``
    (0.92), because nothing could have confirmed it, while the fitted weights would read the
    missing confirmation as a spurious echo's (``others`` most of all, 3.3). One never
    supported is judged as before: a surface is heard again by its own sensor a ring cycle
    later, a one-off crosstalk or floor echo often is not (on the rings measured, 94-100 % of
    the unwatched direct echoes had support, 33-62 % of the unwatched spurious ones). Almost
    no arc of a 16-sonar ring is unwatched (0.2 % in the office); a Pioneer's 8 front sonars
    leave 25 % of their arcs so, most of them side walls only one sensor faces. Nothing about
    it is fitted. False matures every arc with age alone (the model before it). Measured in
    ``docs/RESULTS.md`` ("Another ring"). Looks are counted within the history, so with a
    short one (a few ring cycles) most arcs stay unwatched and the fitted model is all but
    off; an arc watched late goes from the prior to its age's maturity at once.

    The default weights were fitted by logistic regression on the simulator's truth (direct
    echo or spurious) of the arcs with a surviving piece when they left the history, on ONE
    world and physics (office tour, specular physics, seeds 0-2, library defaults otherwise)::

        .venv/bin/python benchmarks/fit_confidence.py

    and are checked on the other worlds and on the amplitude physics by
    ``benchmarks/evidence.py``.
    """

    # Fitted (see above): office tour, specular physics, seeds 0-2, 38,459 arcs (refitted with
    # ``repeated``; the weights before it are benchmarks/evidence.py's WITHOUT_REPEATS).
    intercept: float = -3.543
    support: float = 0.289
    viewpoints: float = 0.921
    crossings: float = 0.680
    free: float = -0.370
    looked: float = 0.299
    split: float = -0.538
    occluded: float = -0.375
    unheard: float = 0.017
    range: float = -0.128
    width: float = 0.545
    others: float = 3.299
    through: float = 0.293
    repeated: float = 1.205
    # Fitted alone, the weights above held (``benchmarks/fit_confidence.py --only behind``),
    # same runs: a metre of depth behind confirmed surfaces.
    behind: float = -0.406
    # Fitted alone, the weights above held (``benchmarks/fit_confidence.py --only alone``), same
    # runs: no other sensor's beam held the arc's axis point.
    alone: float = 0.674
    fresh: float = 2.453  # log-odds of the 92.1 % direct share of the training arcs
    # Looks by other sensors one unit of their support answers for (``others`` above); inf (the
    # default): not normalised. 16 was measured and not kept ("Other rings" above).
    looks_per_support: float = math.inf
    maturity_time: float = 2.0  # fitted: local-map log-loss on the training runs
    unwatched_prior: bool = True  # see "Watched" above; False: every arc matures with age

    def __post_init__(self) -> None:
        """Refuse a weight that is not finite and a maturity time that is not finite and > 0
        (0 would divide by zero, a negative time leave every arc fresh) with ConfigError."""
        finite: _Rule = (math.isfinite, "be finite")
        rules = dict.fromkeys(("intercept", *CONFIDENCE_FEATURES, "fresh"), finite)
        rules["maturity_time"] = (lambda v: 0.0 < v < math.inf, "be finite and > 0 seconds")
        rules["looks_per_support"] = (lambda v: v > 0.0, "be > 0 (inf: support not normalised)")
        _check_fields(self, rules)
        if not isinstance(self.unwatched_prior, bool):  # a JSON "false" would read as on
            msg = f"unwatched_prior must be True or False, got {self.unwatched_prior!r}"
            raise ConfigError(msg)

    def weights(self) -> np.ndarray:
        """The weights in :data:`CONFIDENCE_FEATURES` order, shape (F,)."""
        return np.array([getattr(self, name) for name in CONFIDENCE_FEATURES])

    @classmethod
    def from_weights(cls, intercept: float, weights: np.ndarray, fresh: float,
                     maturity_time: float | None = None) -> ConfidenceModel:
        """The model with ``weights`` (shape (F,), :data:`CONFIDENCE_FEATURES` order);
        ``maturity_time`` defaults to the class's (None: the field's default)."""
        named: dict[str, Any] = {name: float(w)
                                 for name, w in zip(CONFIDENCE_FEATURES, weights, strict=True)}
        if maturity_time is not None:
            named["maturity_time"] = maturity_time
        return cls(intercept=float(intercept), fresh=float(fresh), **named)

    def maturity(self, age: np.ndarray, judged: np.ndarray | None = None) -> np.ndarray:
        """``clip(age / maturity_time, 0, 1)``, ``age`` in seconds; with ``unwatched_prior``,
        0 where ``judged`` (given) is False: an arc no distinct reading looked at squarely
        (:mod:`~sonarcarve.geometry.evidence.watch`) that something supported ("Watched"
        above)."""
        maturity = np.clip(age / self.maturity_time, 0.0, 1.0)
        if judged is not None and self.unwatched_prior:
            maturity = np.where(judged, maturity, 0.0)
        return np.asarray(maturity)

    def confidence(self, features: np.ndarray, maturity: np.ndarray | float = 1.0,
                   ) -> np.ndarray:
        """Probability that each point is a real surface; ``features`` shape (n, F),
        ``maturity`` in [0, 1] (:meth:`maturity`)."""
        # One column at a time, not ``features @ weights``: BLAS sums a row in an order that
        # depends on how many rows there are, so a point's confidence would change in its last
        # digits with the size of the block it was committed in (and the map with when
        # measures() was called). Elementwise products and sums are the same for any length.
        # (_logits adds them the same way, a compiled row at a time: the same operations in the
        # same order as numpy's columns, without a numpy call per feature.)
        table = np.ascontiguousarray(features, dtype=np.float64)
        weights = self.weights()
        if table.ndim != 2 or table.shape[1] != len(weights):
            msg = f"features must have shape (n, {len(weights)}), got {table.shape}"
            raise ConfigError(msg)  # a wrong argument to the model: a ValueError too
        n = len(table)
        ages = np.ascontiguousarray(np.broadcast_to(np.asarray(maturity, dtype=np.float64), (n,)))
        logit = np.empty(n)
        _logits(table, weights, self.intercept, self.fresh, ages, logit)
        return np.asarray(1.0 / (1.0 + np.exp(-logit)))


@compiled
def _logits(features: FloatArray, weights: FloatArray, intercept: float, fresh: float,
            maturity: FloatArray, out: FloatArray) -> None:
    """``out[q] = fresh + m_q (intercept + Σ_f w_f x_qf - fresh)`` (:class:`ConfidenceModel`),
    the sum taken in feature order: each row gets exactly the operations a numpy column at a
    time gives it, whatever the number of rows."""
    for q in range(features.shape[0]):
        fitted = intercept
        for f in range(weights.shape[0]):
            fitted = fitted + features[q, f] * weights[f]
        out[q] = fresh + maturity[q] * (fitted - fresh)


@compiled_inline
def _at_most(value: float, cap: float) -> float:
    """``np.minimum(value, cap)`` of one number (NaN stays NaN)."""
    return cap if value > cap else value


@compiled
def _fill_features(out: FloatArray, slots: SlotArray, support: FloatArray,
                   crossings: FloatArray, free: FloatArray, runs: FloatArray, width: FloatArray,
                   maturity: FloatArray, viewpoints: FloatArray, looked: FloatArray,
                   occluded: FloatArray, r: FloatArray, beam_width: FloatArray,
                   others: FloatArray, through: FloatArray, repeated: FloatArray,
                   behind: FloatArray, covering: FloatArray, looks_per_support: float,
                   threshold: float) -> None:
    """The rows of :meth:`EvidenceMethod.features` (:data:`CONFIDENCE_FEATURES` order) for
    ``slots``: the per-slot arrays (``support`` .. ``width``, ``maturity``) from
    :meth:`EvidenceModel.raw`, the per-arc ones indexed by slot. One compiled pass instead of
    two dozen numpy calls per block of arcs; each value is the same elementwise operation."""
    for q in range(slots.shape[0]):
        s = slots[q]
        out[q, 0] = _at_most(support[q], 3.0)
        out[q, 1] = _at_most(viewpoints[s], 3.0)
        out[q, 2] = _at_most(crossings[q], 3.0)
        out[q, 3] = free[q]
        out[q, 4] = _at_most(looked[s] / threshold, 3.0)
        extra_runs = runs[q] - 1.0
        out[q, 5] = _at_most(0.0 if extra_runs < 0.0 else extra_runs, 3.0)
        out[q, 6] = occluded[s]
        out[q, 7] = (1.0 if support[q] <= 0.0 else 0.0) * maturity[q]  # unheard
        out[q, 8] = r[s]
        out[q, 9] = width[q] / beam_width[s]
        # Support from other sensors per looks_per_support of their looks (at least 1).
        looks = covering[s] / looks_per_support
        out[q, 10] = _at_most(others[s] / (looks if looks > 1.0 else 1.0), 1.0)
        out[q, 11] = _at_most(through[s], 3.0)
        out[q, 12] = repeated[s]
        out[q, 13] = _at_most(behind[s], 3.0)  # metres; 0 while the arc is in the history
        out[q, 14] = 1.0 if covering[s] == 0.0 else 0.0  # alone: no other sensor's beam held it


#: Older arcs whose bins to weigh the weighing kernel gathers before it weighs them at once
#: (:func:`~sonarcarve.geometry.evidence.evidence_add`, pass 2): 65 arcs a reading pass its
#: cull at history 1,000, 20 at 250; the scratch is 11 rows of this many arcs' bins.
_GROUP_ARCS = 64



@compiled
def _fill_codes(slots: SlotArray, has: BoolArray, is_atm: BoolArray, width: FloatArray,
                beam_width: FloatArray, touched: BoolArray, counts: npt.NDArray[np.int32],
                status: Int8Array, processed: BoolArray, source: Int8Array,
                fate: Int8Array) -> None:
    """Per slot of :meth:`EvidenceModel.estimates`: processed (Table I: evidence, a crossing or
    carved), the point's source (ATM median, carved where the kept run is narrower than the
    beam, else the centreline) and its fate (alive or fully carved), in one compiled pass."""
    for q in range(slots.shape[0]):
        s = slots[q]
        processed[q] = touched[s] or counts[s] > 0 or status[s] != EVIDENCE_ALIVE
        if is_atm[q]:
            source[q] = SOURCE_ATM
        elif width[q] < beam_width[s] - 1e-12:
            source[q] = SOURCE_CARVED
        else:
            source[q] = SOURCE_CENTERLINE
        fate[q] = UNCHANGED if has[q] else FULLY_CARVED


class EvidenceModel(ArcModel):
    """Evidence profiles, occlusion and ATM crossings over a shared history.

    :meth:`on_add_many` runs a block of stored arcs in one compiled call.

    Memory: the per-arc state is fixed by the history (about 4 kB an arc with K = 24); the
    ATM crossing store grows on demand as ATM's does (:class:`~sonarcarve.methods.atm.AtmModel`):
    it starts at :data:`~sonarcarve.methods.atm.INITIAL_COLUMNS` columns and doubles when an
    arc's crossings do not fit (the kernel stops after that arc, its crossings wait in
    ``spill`` and move to their rows once the store is wider, so the store holds what one wide
    enough from the start would). The store is bounded by
    :data:`~sonarcarve.methods.atm.MAX_ATM_STATE_BYTES`; a growth past it raises
    :class:`~sonarcarve.methods.atm.CrossingStoreError`, and then every later reading does
    (crossings were lost). Measured on ``benchmarks/synthetic.py``'s corridor stream: 512
    columns (39 MiB) at a history of 10,000 arcs, 1,024 (781 MiB) at 100,000 arcs after
    60,000 readings.

    Parameters
    ----------
    history : SonarHistory
        The shared history.
    bins : int
        K, bins across each beam.
    range_tolerance : float
        ε, metres.
    carve_probability : float
        P_carve: a bin is carved when the evidence equals one reading with this ``P_detect``.
    min_transversal, range_resolution : float
        ATM's ψ (radians) and δ (metres); ψ also picks the crossings.
    options : EvidenceOptions, optional
        The switches; default ``EvidenceOptions()``: every part, the measured placement.
    sensor : SensorModel
        The detection model.
    """

    def __init__(self, history: SonarHistory, bins: int, range_tolerance: float,
                 carve_probability: float, min_transversal: float, range_resolution: float,
                 *, options: EvidenceOptions | None = None,
                 sensor: SensorModel | None = None) -> None:
        super().__init__(history)
        options = EvidenceOptions() if options is None else options
        sensor = SensorModel() if sensor is None else sensor
        self.bins = bins
        self.threshold = evidence_threshold(carve_probability)
        self.options = options
        self.atm_bound = atm_error_bound(min_transversal, range_resolution)
        self.params = sensor.params(range_tolerance, self.threshold, min_transversal,
                                    with_occlusion=options.occlusion,
                                    with_transmission=options.transmission)
        self.range_tolerance = range_tolerance
        self._plain_rules = plain(EstimateRules(
            threshold=self.threshold, atm_bound=self.atm_bound, with_atm=options.atm,
            place_located=options.located_placement, posterior=options.posterior_placement,
            posterior_uncut=options.uncut_posterior, min_crossings=options.min_atm_crossings,
        ))
        self._allocate(history, bins, options.atm)
        self._fully = 0
        self._crossings = 0
        self._occluded_bins = 0

    def _allocate(self, history: SonarHistory, bins: int, with_atm: bool) -> None:
        """The per-arc state (rows of ``history.storage_size``, ``bins`` wide where it is per
        bin), the scratch of the kernels and ATM's crossing store, all empty."""
        size = history.storage_size
        # Crossings an arc can have: 2 with each of capacity - 1 older and as many newer arcs.
        most = max(1, 4 * (history.capacity - 1))
        self.bx = np.zeros((size, bins))
        self.by = np.zeros((size, bins))
        self.ex = np.zeros((size, bins))
        self.ey = np.zeros((size, bins))
        self.free = np.zeros((size, bins))
        self.support = np.zeros((size, bins))
        self.located = np.zeros((size, bins))
        self.circle = np.zeros((3, size))  # rows: centre x, centre y, radius
        # A circle containing each arc's live bins and their count, redrawn as it loses bins
        # (geometry/evidence/beam.py, draw_live_circle); infinite until first drawn.
        self.live_circle = np.zeros((4, size))
        self.live_circle[2] = np.inf
        self.cos_axis = np.zeros(size)
        self.sin_axis = np.zeros(size)
        self.cos_half = np.zeros(size)
        self.status = np.zeros(size, dtype=np.int8)
        self.touched = np.zeros(size, dtype=bool)
        self.occluded = np.zeros(size)
        self.viewpoints = np.zeros(size)
        self.looked = np.zeros(size)
        self.others = np.zeros(size)
        self.through = np.zeros(size)
        # How far each arc's echo lies behind surfaces the arcs after it confirm, metres
        # (geometry/evidence/behind.py): 0 on arrival, set as the arc leaves the history.
        self.behind = np.zeros(size)
        self.behind_scratch = np.zeros(size)  # scratch of the depth behind the newer arcs
        # 1 where the arc has a repeat (geometry/repeats.py) among its sensor's other echoes
        # in the history, else 0.
        self.repeated = np.zeros(size)
        # Whether a distinct reading looked squarely at the arc (geometry/evidence/watch.py).
        self.watched = np.zeros(size, dtype=bool)
        # How many readings of other sensors held the arc's axis point in their beams
        # (geometry/evidence/watch.py).
        self.covering = np.zeros(size)
        # Scratch for the transmission pass: every older bin at most once (the kernel would
        # skip what did not fit, withholding evidence; a cap of 65,536 rows did from a
        # history of about 1,366 arcs). 11 MB at a history of 10,000 arcs (K = 24).
        self.passed = np.zeros((max(1, (history.capacity - 1) * bins), 6))
        # Scratch of evidence_add: support per bin, the sines of the bin edges and the beam
        # width they were computed for (NaN: none yet), the bin guess's scale.
        self.trans = np.zeros(2 * bins + 3)
        self.trans[2 * bins + 1] = np.nan
        # Scratch of evidence_add: the bins to weigh of a group of older arcs (at most
        # _GROUP_ARCS), their offsets from the new reading and what it computes of them; the
        # bins to weigh of one arc; the entries' bins and the group's arcs' counts; which
        # rows pass the cull.
        entries = bins * min(_GROUP_ARCS, max(1, history.capacity - 1))
        self.scratch = np.zeros((11, entries))
        self.in_beam = np.zeros(bins, dtype=bool)
        self.bin_index = np.zeros((4, entries), dtype=np.int64)
        self.near = np.zeros(size, dtype=np.int64)
        self.near_flags = np.zeros(size, dtype=bool)
        # ATM's crossing store grows on demand, as ATM's does: it starts narrow and widens
        # when an arc's crossings do not fit (they wait in ``spill``, room for every crossing
        # one new arc can make: 4 (capacity - 1) rows of (row, bearing) float64, 0.64 MB at
        # a history of 10,000 arcs).
        self.store = CrossingStore(size, most if with_atm else 1, "evidence carving's")
        self.spill = np.zeros((most if with_atm else 1, 2))
        self._bundle()

    def _bundle(self) -> None:
        """The per-arc arrays and the work arrays of the weighing kernels as their bundles
        (:mod:`~sonarcarve.geometry.evidence.arrays`, where each array is described): the
        same arrays as the attributes, bundled once."""
        shapes = ArcShapes(cos_axis=self.cos_axis, sin_axis=self.sin_axis,
                           cos_half=self.cos_half, circle=self.circle, bx=self.bx, by=self.by,
                           ex=self.ex, ey=self.ey)
        evidence = BinEvidence(free=self.free, support=self.support, located=self.located)
        arcs = ArcEvidence(status=self.status, touched=self.touched, viewpoints=self.viewpoints,
                           looked=self.looked, others=self.others, occluded=self.occluded,
                           through=self.through, behind=self.behind,
                           live_circle=self.live_circle)
        scratch = AddScratch(passed=self.passed, trans=self.trans, entries=self.scratch,
                             in_beam=self.in_beam, bin_index=self.bin_index, near=self.near,
                             near_flags=self.near_flags, depth=self.behind_scratch)
        self._plain_parts = plain((shapes, evidence, arcs))
        self._plain_scratch = plain(scratch)

    @property
    def bearings(self) -> np.ndarray:
        """The crossing store's bearings (:class:`~sonarcarve.methods.atm.CrossingStore`);
        replaced when it grows."""
        return self.store.bearings

    @bearings.setter
    def bearings(self, value: np.ndarray) -> None:
        self.store.bearings = value

    @property
    def counts(self) -> np.ndarray:
        """Crossings stored per row (:class:`~sonarcarve.methods.atm.CrossingStore`)."""
        return self.store.counts

    def _bundles(self) -> tuple[PlainBundle, PlainBundle, EvidenceParams, bool]:
        """The weighing kernels' arguments after the sequence numbers
        (:func:`~sonarcarve.geometry.evidence.evidence_add_many`): the state and the work
        arrays (as :func:`~sonarcarve.geometry.evidence.arrays.plain` tuples, which numba
        types faster at the call), the sensor model and whether to find ATM crossings."""
        return self._state(), self._plain_scratch, self.params, self.options.atm

    def _state(self) -> PlainBundle:
        """The model's :class:`~sonarcarve.geometry.evidence.arrays.EvidenceState`, plain.
        The history's rows and the crossing store are bundled afresh each call (the store's
        bearings are replaced when it grows), as tuples in their bundles' field order
        (:class:`~sonarcarve.geometry.evidence.arrays.ReadingRows`,
        :class:`~sonarcarve.geometry.evidence.arrays.CrossingArrays`: building those and
        unnaming them cost 1 µs a call); the per-arc arrays were bundled once
        (:meth:`_bundle`)."""
        h = self.history
        readings = (h.x, h.y, h.r, h.theta, h.beam_width, h.sensor)
        crossings = (self.bearings, self.counts, self.spill)
        return (readings, *self._plain_parts, crossings)

    def _count(self, counts: tuple[int, int, int]) -> None:
        fully, crossings, occluding = counts
        self._fully += fully
        self._crossings += crossings
        self._occluded_bins += occluding

    def on_add_many(self, first: int, count: int) -> None:
        """Initialise the profile of each new arc ``first .. first + count - 1`` and weigh its
        reading against the older arcs, in one compiled call (more when the crossing store has
        to grow on the way), then mark the arcs distinct readings looked at squarely
        (:meth:`mark_watch`)."""
        self.check_usable()
        end = first + count
        self.mark_repeats(first, count)
        while first < end:
            fully, crossings, occluding, first, spilled = evidence_add_many(
                first, end - first, self.history.capacity, *self._bundles())
            self._count((fully, crossings, occluding))
            if spilled:
                self._take_spill(spilled)
        self.mark_watch(end - count, count)  # after the weighing, which sets the axes it reads

    def mark_watch(self, first: int, count: int) -> None:
        """Mark in :attr:`watched` the arcs ``first .. first + count - 1`` and the arcs before
        them that a distinct reading looked at squarely, within the sensor model's
        ``incidence_zero`` (:func:`~sonarcarve.geometry.evidence.mark_watch`; the new arcs' axes
        must be set, as weighing them does). Each pair is judged when its newer arc arrives,
        from the two readings alone: the same flags whatever the blocks."""
        h = self.history
        mark_watch(first, count, h.capacity, h.x, h.y, h.r, self.cos_axis, self.sin_axis,
                   self.cos_half, h.sensor, self.watched, self.covering,
                   self.params.viewpoint_spacing, self.params.incidence_zero)

    def mark_repeats(self, first: int, count: int) -> int:
        """Mark the repeats (:func:`~sonarcarve.geometry.repeats.mark_repeats`, ε the range
        tolerance) of arcs ``first .. first + count - 1`` in :attr:`repeated`; the number of
        pairs found. Each pair is judged when its newer arc arrives, from the two readings
        alone: the same marks whatever the blocks (and whatever the crossing store's growth
        in :meth:`on_add_many`)."""
        h = self.history
        return int(mark_repeats(first, count, h.capacity, h.x, h.y, h.r, h.theta,
                                h.beam_width, h.sensor, self.repeated, self.range_tolerance))

    def _take_spill(self, spilled: int) -> None:
        """Widen the crossing store for the ``spilled`` crossings in :attr:`spill` and move
        them to the ends of their rows (:func:`~sonarcarve.geometry.evidence.evidence_add`).
        If it cannot grow (:class:`~sonarcarve.methods.atm.CrossingStoreError`), the method
        stops for good: the spilled crossings are lost, so its maps would be wrong."""
        rows = self.spill[:spilled, 0].astype(np.int64)
        values = self.spill[:spilled, 1]
        self.store.grow(int(self.counts[rows].max()))
        bearings = self.bearings
        # A row's spilled crossings are its last ones, in the order found (_store_crossing).
        spilled_in_row = np.bincount(rows, minlength=len(self.counts))
        first_spilled = self.counts - spilled_in_row
        for row, value in zip(rows.tolist(), values.tolist(), strict=True):
            bearings[row, first_spilled[row]] = value
            first_spilled[row] += 1

    def check_usable(self) -> None:
        """Raise the :class:`~sonarcarve.methods.atm.CrossingStoreError` that stopped the model,
        if one did."""
        self.store.check_usable()

    def on_no_echo(self, reading: Reading, beam_width: float) -> None:
        """Add the no-echo reading's free-space evidence to the live arcs (no arc of its own),
        and mark those it looked at squarely as watched
        (:func:`~sonarcarve.geometry.evidence.mark_watched_by_silence`)."""
        self.check_usable()
        h = self.history
        slots = np.ascontiguousarray(h.slots())
        silent = SilentReading(x=reading.x, y=reading.y, max_range=reading.max_range,
                               theta=reading.theta, beam_width=beam_width, sensor=reading.sensor)
        # Plain tuples: numba types them faster at the call (arrays.plain).
        self._fully += evidence_free(tuple(silent), slots, self._state(), self.params)
        mark_watched_by_silence(slots, h.x, h.y, h.r, self.cos_axis, self.sin_axis, h.sensor,
                                reading.x, reading.y, reading.theta, beam_width,
                                reading.max_range, reading.sensor, self.watched,
                                self.covering, self.params.viewpoint_spacing,
                                self.params.incidence_zero)

    def raw(self, slots: SlotArray) -> PieceEstimates:
        """:func:`~sonarcarve.geometry.evidence.evidence_estimates` for ``slots`` (refused once
        the model has stopped: :meth:`check_usable`)."""
        self.check_usable()
        readings, _, evidence, _, crossings = self._state()  # EvidenceState's parts, plain
        return evidence_estimates(slot_indices(slots), readings, evidence, self.status,
                                  crossings, self._plain_rules)

    def estimates(self, slots: SlotArray) -> Estimates:
        """Points of the kept runs; ``alive`` where a bin survives (confidence applied by the
        method). ``confidence`` is left to the method."""
        return self.estimates_from_raw(slots, self.raw(slots))

    def estimates_from_raw(self, slots: SlotArray, raw: PieceEstimates) -> Estimates:
        """:meth:`estimates` from an already computed :meth:`raw`."""
        h = self.history
        n = len(slots)
        processed = np.empty(n, dtype=np.bool_)
        source = np.empty(n, dtype=np.int8)
        fate = np.empty(n, dtype=np.int8)
        _fill_codes(np.ascontiguousarray(slots, dtype=np.int64), raw.has_piece, raw.is_atm,
                    raw.width, h.beam_width, self.touched, self.counts, self.status, processed,
                    source, fate)
        return Estimates(
            alive=raw.has_piece, processed=processed, xy=arc_point(h, slots, raw.bearing),
            width=raw.width, max_error=raw.max_error, source=source, fate=fate,
        )

    def counters(self) -> dict[str, int]:
        """``fully_carved``, ``atm_crossings`` and ``occluded_bins`` since the start."""
        return {"fully_carved": self._fully, "atm_crossings": self._crossings,
                "occluded_bins": self._occluded_bins}


class EvidenceMethod(SonarMethod):
    """Evidence carving with integrated ATM and per-point confidence (beyond the paper).

    Parameters
    ----------
    history_size, beam_width
        As for :class:`~sonarcarve.methods.base.SonarMethod`.
    range_tolerance : float
        ε, metres.
    min_transversal, range_resolution : float
        ATM's ψ (radians) and δ (metres).
    evidence_bins : int
        K, bins per beam.
    carve_probability : float
        P_carve in (0, 1).
    min_confidence : float
        Points below this confidence are left out of the maps, in [0, 1] (0: keep every
        point with a surviving bin).
    stamp_error : float
        Upper bound on the position-stamping error of a reading, metres (Appendix A), added to
        every point's bound.
    stamp_heading_error : float
        Upper bound on the heading-stamping error of a reading, radians (Appendix A): a point
        ``r`` from its sensor moves at most ``2 r sin(δ/2)`` (the chord of eq. 5.3), added to
        its bound.
    options : EvidenceOptions, optional
        The switches (ablation, placement rules), passed to :class:`EvidenceModel` as they
        are; default ``EvidenceOptions()``.
    sensor : SensorModel, optional
        The detection model.
    confidence_model : ConfidenceModel, optional
        The confidence model.
    """

    name = "evidence"

    def __init__(
        self,
        history_size: int = DEFAULT_HISTORY_SIZE,
        beam_width: float = DEFAULT_BEAM_WIDTH,
        range_tolerance: float = DEFAULT_RANGE_TOLERANCE,
        min_transversal: float = DEFAULT_MIN_TRANSVERSAL,
        range_resolution: float = POLAROID_RANGE_RESOLUTION,
        evidence_bins: int = DEFAULT_EVIDENCE_BINS,
        carve_probability: float = DEFAULT_CARVE_PROBABILITY,
        min_confidence: float = DEFAULT_MIN_CONFIDENCE,
        stamp_error: float = 0.0,
        stamp_heading_error: float = 0.0,
        *,
        options: EvidenceOptions | None = None,
        sensor: SensorModel | None = None,
        confidence_model: ConfidenceModel | None = None,
    ) -> None:
        self.config = MethodConfig(
            history_size=history_size, beam_width=beam_width, range_tolerance=range_tolerance,
            min_transversal=min_transversal, range_resolution=range_resolution,
            evidence_bins=evidence_bins, carve_probability=carve_probability,
            min_confidence=min_confidence, stamp_error=stamp_error,
            stamp_heading_error=stamp_heading_error,
        )
        self.options = EvidenceOptions() if options is None else options
        self.sensor = SensorModel() if sensor is None else sensor
        self.confidence_model = ConfidenceModel() if confidence_model is None else confidence_model
        self._removed_committed = 0
        super().__init__(history_size, beam_width)

    def _make_models(self) -> tuple[EvidenceModel]:
        c = self.config
        return (EvidenceModel(self.history, c.evidence_bins, c.range_tolerance,
                              c.carve_probability, c.min_transversal, c.range_resolution,
                              options=self.options, sensor=self.sensor),)

    def features(self, slots: SlotArray, raw: PieceEstimates | None = None,
                 maturity: np.ndarray | None = None) -> np.ndarray:
        """The confidence's features of ``slots`` now, shape (n, F) (:class:`ConfidenceModel`);
        ``raw`` (:meth:`EvidenceModel.raw`) and ``maturity`` (:meth:`maturity`) of the same
        slots, when the caller has them already."""
        model = self.models[0]
        assert isinstance(model, EvidenceModel)
        raw = model.raw(slots) if raw is None else raw
        maturity = self.maturity(slots, raw) if maturity is None else maturity
        h = self.history
        out = np.empty((len(slots), len(CONFIDENCE_FEATURES)))
        _fill_features(out, np.ascontiguousarray(slots, dtype=np.int64), raw.piece_support,
                       raw.piece_crossings, raw.piece_free, raw.runs, raw.width,
                       np.ascontiguousarray(maturity, dtype=np.float64),
                       model.viewpoints, model.looked, model.occluded, h.r, h.beam_width,
                       model.others, model.through, model.repeated, model.behind,
                       model.covering, self.confidence_model.looks_per_support,
                       model.threshold)
        return out

    def maturity(self, slots: SlotArray,
                 raw: PieceEstimates | None = None) -> np.ndarray:
        """:meth:`ConfidenceModel.maturity` of ``slots`` now, shape (n,); ``raw``
        (:meth:`EvidenceModel.raw` of the same slots) when the caller has it already.

        "Now" is the time of the last reading added; inside a block of
        :meth:`~sonarcarve.methods.base.SonarMethod.add_many` (arcs committed between blocks,
        before the method's clock moves at the end of the batch) it is the newest stored arc's
        time, which is what one :meth:`add` per reading would have seen then. An arc is judged
        by the fitted model once a distinct reading looked at it squarely, or while nothing
        has supported it (:class:`ConfidenceModel`, "Watched").
        """
        h = self.history
        if h.appended == 0:
            return np.zeros(len(slots))
        newest = float(h.t[(h.appended - 1) % h.storage_size])
        now = max(self._last_t, newest)
        model = self.models[0]
        assert isinstance(model, EvidenceModel)
        raw = model.raw(slots) if raw is None else raw
        judged = model.watched[slots] | (raw.piece_support <= 0.0)
        return self.confidence_model.maturity(now - h.t[slots], judged)

    def _estimates(self, slots: SlotArray) -> Estimates:
        """The model's points with their confidence; low-confidence points are not alive."""
        model = self.models[0]
        assert isinstance(model, EvidenceModel)
        raw = model.raw(slots)
        has = raw.has_piece
        base = model.estimates_from_raw(slots, raw)
        maturity = self.maturity(slots, raw)
        confidence = self.confidence_model.confidence(self.features(slots, raw, maturity),
                                                      maturity)
        alive = has & (confidence >= self.config.min_confidence)
        if not self.options.keep_split:  # the paper's rule: a split arc is dropped
            alive &= raw.runs <= 1
        return Estimates(
            alive=alive, processed=base.processed, xy=base.xy, width=base.width,
            max_error=base.max_error + self._stamp_bound(slots), source=base.source,
            fate=base.fate, confidence=np.where(has, confidence, 0.0),
        )

    def _stamp_bound(self, slots: SlotArray) -> FloatArray | float:
        """What a wrong stamp adds to each point's bound (Appendix A, section 6's certainty):
        the origin's position error, plus the chord ``2 r sin(δ/2)`` a heading error δ swings
        a point ``r`` from its sensor through (the arc's own range: its point lies on it)."""
        config = self.config
        if config.stamp_heading_error == 0.0:  # the default: no chord, no array per read
            return config.stamp_error
        chord = 2.0 * self.history.r[slots] * math.sin(0.5 * config.stamp_heading_error)
        return config.stamp_error + chord

    def _commit(self, slots: SlotArray) -> None:
        est = self.estimates(slots)
        self._removed_committed += int(np.count_nonzero(~est.alive))
        for listener in self._listeners:
            listener(self.history, slots, est)
        self._global.commit(self._points(slots, GlobalMap, est))

    def measures(self) -> Measures:
        """As :meth:`SonarMethod.measures`; ``fully_carved`` counts every arc the evidence
        removed (no bin left, or confidence below ``min_confidence``; with
        ``EvidenceOptions.keep_split`` off, a split arc too), committed or still in the
        history; ``split`` is 0 (split arcs keep a piece, or are counted above)."""
        self.history.flush_retired()  # count retired rows as committed (as global_map does)
        base = super().measures()
        slots = self.history.slots()
        live_removed = int(np.count_nonzero(~self.estimates(slots).alive)) if len(slots) else 0
        return replace(base, fully_carved=self._removed_committed + live_removed, split=0)
