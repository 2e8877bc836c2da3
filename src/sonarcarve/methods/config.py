"""One set of named, validated parameters for every method, for the CLI and experiments.

Every parameter has one rule, checked in one place: :class:`MethodConfig` runs the ``check_*``
functions below in ``__post_init__``, and the method and model constructors call the same
functions, so the API and the CLI report a bad value with the same one-line
:class:`~sonarcarve.errors.ConfigError`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from numbers import Real

from sonarcarve.constants import DEFAULT_BEAM_WIDTH, MIN_BEAM_WIDTH, POLAROID_RANGE_RESOLUTION
from sonarcarve.errors import ConfigError
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.history import DEFAULT_HISTORY_SIZE, MAX_HISTORY_SIZE, check_history_size
from sonarcarve.readings import MAX_READING_RANGE

__all__ = [
    "DEFAULT_CARVE_PROBABILITY",
    "DEFAULT_EVIDENCE_BINS",
    "DEFAULT_MIN_CONFIDENCE",
    "DEFAULT_MIN_TRANSVERSAL",
    "DEFAULT_RANGE_TOLERANCE",
    "MAX_HISTORY_SIZE",
    "MAX_RANGE_TOLERANCE",
    "MethodConfig",
    "check_beam_width",
    "check_carve_probability",
    "check_degrees",
    "check_evidence_bins",
    "check_history_size",
    "check_max_incidence",
    "check_min_confidence",
    "check_min_transversal",
    "check_range_resolution",
    "check_range_tolerance",
    "check_stamp_error",
    "check_stamp_heading_error",
]

#: Default range tolerance ε, metres: a newer reading's freespace ends ε short of its echo.
#: Chosen by measurement (``benchmarks/range_tolerance.py``, ring corridor, 20,000 readings,
#: 1-inch quantisation, 5 % spurious echoes): with ε = 0, rounding and noise let a newer reading's
#: freespace reach past true echoes, and 15 % (σ = 0), 31 % (σ = 1 cm) and 39 % (σ = 2.5 cm) of
#: true echoes were fully carved; with ε = 5 cm 0 %, 0.1 % and 8.5 %, while the median distance
#: of map points to the walls stayed within 2.5 mm of the best ε (1.6-2.5 cm; centerline 12 cm)
#: and 93-94 % of spurious echoes were still removed. ε = 10 cm costs accuracy (3.7-4 cm).
DEFAULT_RANGE_TOLERANCE = 0.05

#: Largest range tolerance ε accepted, metres. Beyond it ε is no longer a tolerance: a newer
#: reading's freespace would stop a metre or more short of its echo, so carving and the grids'
#: free space would all but stop, silently. The widest ε any benchmark found useful is 0.15 m
#: (the 5 cm default plus twice a 5 cm pose error, ``benchmarks/pose_error.py``); a 2 % range
#: error at a Polaroid's 10.7 m limit is 0.2 m.
MAX_RANGE_TOLERANCE = 1.0

#: Default minimum transversal angle ψ of ATM, radians (20°; see :class:`MethodConfig`).
DEFAULT_MIN_TRANSVERSAL = math.radians(20.0)

#: Default bins per beam of evidence carving (K; 24 bins: 0.94° each for a 22.5° beam).
DEFAULT_EVIDENCE_BINS = 24

#: Most bins per beam (memory grows as history x bins).
MAX_EVIDENCE_BINS = 256

#: Default P_carve of evidence carving: a bin is carved on the evidence of one reading that
#: would have heard a surface there with probability 0.8, or of several weaker ones.
DEFAULT_CARVE_PROBABILITY = 0.8

#: Default confidence below which evidence carving leaves a point out of its maps: 0.5, the
#: decision of a calibrated probability (keep a point more likely real than not). The rule "the
#: largest threshold keeping ≥ 90 % of the training data's direct echoes" gives 0.9
#: (``.venv/bin/python benchmarks/fit_confidence.py``); it removes more spurious echoes on every
#: held-out world but keeps only 75 % of the direct echoes of the doorway under the amplitude
#: physics, so it is not the default.
DEFAULT_MIN_CONFIDENCE = 0.5


def _number(name: str, value: object, rule: str) -> float:
    """``value`` as a float if it is a real number (not a bool), else the rule's error."""
    if isinstance(value, bool) or not isinstance(value, Real):
        msg = f"{name} must be a number and {rule}, got {value!r}"
        raise ConfigError(msg)
    return float(value)


def _refuse(name: str, rule: str, value: object) -> None:
    msg = f"{name} must {rule}, got {value!r}"
    raise ConfigError(msg)


def check_beam_width(value: object, name: str = "beam_width") -> float:
    """φ in radians, in [:data:`~sonarcarve.constants.MIN_BEAM_WIDTH`, π); the value as a
    float, else ConfigError."""
    rule = f"lie in [{MIN_BEAM_WIDTH:g}, pi) radians"
    width = _number(name, value, rule)
    if not MIN_BEAM_WIDTH <= width < math.pi:
        _refuse(name, rule, value)
    return width


def _metres_at_least_zero(name: str, value: object) -> float:
    rule = "be finite and >= 0 metres"
    metres = _number(name, value, rule)
    if not (math.isfinite(metres) and metres >= 0.0):
        _refuse(name, rule, value)
    return metres


def _angle_up_to_right(name: str, value: object) -> float:
    rule = "lie in [0, pi/2] radians"
    angle = _number(name, value, rule)
    if not 0.0 <= angle <= NO_INCIDENCE_LIMIT:
        _refuse(name, rule, value)
    return angle


def _metres_up_to(name: str, value: object, most: float) -> float:
    rule = f"lie in [0, {most:g}] metres"
    metres = _number(name, value, rule)
    if not 0.0 <= metres <= most:
        _refuse(name, rule, value)
    return metres


def check_range_tolerance(value: object, name: str = "range_tolerance") -> float:
    """ε in metres, in [0, :data:`MAX_RANGE_TOLERANCE`]."""
    return _metres_up_to(name, value, MAX_RANGE_TOLERANCE)


def check_min_transversal(value: object, name: str = "min_transversal") -> float:
    """ψ in radians, in (0, π/2]: ψ = 0 would give every ATM point an infinite error bound
    (``δ (1/sin ψ + 1/tan ψ)``), so ATM would never win in ``combined`` and ``--max-error``
    would drop all its points."""
    rule = "lie in (0, pi/2] radians"
    angle = _number(name, value, rule)
    if not 0.0 < angle <= NO_INCIDENCE_LIMIT:
        _refuse(name, rule, value)
    return angle


def check_range_resolution(value: object, name: str = "range_resolution") -> float:
    """δ in metres, finite and ≥ 0."""
    return _metres_at_least_zero(name, value)


def check_max_incidence(value: object, name: str = "max_incidence") -> float:
    """β in radians, in [0, π/2] (π/2: specular-aware carving off, the paper)."""
    return _angle_up_to_right(name, value)


#: The angle fields a user gives in degrees (command line, sweep files): field -> (its rule on
#: degrees, the interval as written). The same intervals as the radians checks above; a value
#: is judged as typed, so that an error quotes the user's number, not its conversion.
_DEGREE_RULES: dict[str, tuple[Callable[[float], bool], str]] = {
    "beam_width": (lambda d: math.radians(d) >= MIN_BEAM_WIDTH and d < 180.0, "(0, 180)"),
    "min_transversal": (lambda d: 0.0 < d <= 90.0, "(0, 90]"),
    "max_incidence": (lambda d: 0.0 <= d <= 90.0, "[0, 90]"),
    "stamp_heading_error": (lambda d: 0.0 <= d <= 90.0, "[0, 90]"),
}


def check_degrees(field: str, degrees: float, label: str) -> None:
    """Refuse the angle field ``field`` given as ``degrees`` outside its interval (NaN and
    infinities included), as ``"{label} must lie in (0, 90] degrees, got 0"``."""
    rule, interval = _DEGREE_RULES[field]
    if not rule(degrees):
        msg = f"{label} must lie in {interval} degrees, got {degrees:g}"
        raise ConfigError(msg)


def check_evidence_bins(value: object, name: str = "evidence_bins") -> int:
    """K, a whole number in [1, 256]."""
    rule = f"be a whole number in [1, {MAX_EVIDENCE_BINS}]"
    if isinstance(value, bool) or not isinstance(value, int):
        _refuse(name, rule, value)
        return 0  # unreachable: _refuse raises
    if not 1 <= value <= MAX_EVIDENCE_BINS:
        _refuse(name, rule, value)
    return value


def check_carve_probability(value: object, name: str = "carve_probability") -> float:
    """P_carve, in the open interval (0, 1)."""
    rule = "lie in (0, 1)"
    p = _number(name, value, rule)
    if not 0.0 < p < 1.0:
        _refuse(name, rule, value)
    return p


def check_min_confidence(value: object, name: str = "min_confidence") -> float:
    """A confidence threshold in [0, 1]."""
    rule = "lie in [0, 1]"
    p = _number(name, value, rule)
    if not 0.0 <= p <= 1.0:
        _refuse(name, rule, value)
    return p


def check_stamp_error(value: object, name: str = "stamp_error") -> float:
    """Position-stamping error bound in metres, in [0, 10 km] (longer than any sonar reading:
    a bigger bound says nothing, and would overflow the float32 of a bag's local map)."""
    return _metres_up_to(name, value, MAX_READING_RANGE)


def check_stamp_heading_error(value: object, name: str = "stamp_heading_error") -> float:
    """Heading-stamping error bound in radians, in [0, π/2]: a reading stamped with a heading
    more than a right angle off is not a stamping error."""
    return _angle_up_to_right(name, value)


@dataclass(frozen=True)
class MethodConfig:
    """Parameters shared by the sonar methods; each method reads the ones it needs.

    Every field is checked when the config is made; a bad one raises
    :class:`~sonarcarve.errors.ConfigError` with one line naming the field, for example
    ``beam_width must lie in [1e-06, pi) radians, got 4.0``. SI units: metres and radians.

    Parameters
    ----------
    history_size : int, default 250
        Arcs kept in the history (paper, section 5-C: 250); a whole number in
        [1, :data:`~sonarcarve.history.MAX_HISTORY_SIZE`] (100,000; the history grows
        linearly with it, see there).
    beam_width : float, default 22.5° (0.3927 rad)
        Default beam width φ, radians in (0, π), for readings that carry none (paper: 22.5°).
    range_tolerance : float, default 0.05 m
        ε, metres, finite and ≥ 0: a newer reading's freespace ends at ``r - ε`` (0 is the
        paper exactly). Default 5 cm, measured with ``benchmarks/range_tolerance.py`` (1-inch
        quantised ranges, noise σ ≤ 2.5 cm): ε = 0 fully carved 15-39 % of true echoes, 5 cm at
        most 8.5 %, at a median point error within 2.5 mm of the best ε (see
        :data:`DEFAULT_RANGE_TOLERANCE`).
    min_transversal : float, default 20° (0.349 rad)
        ψ, radians in (0, π/2] (0 would give every ATM point an infinite bound): ATM's
        minimum transversal angle (eq. 2.2, 5.4). Default 20°,
        measured with ``benchmarks/min_transversal.py``: against 30° it needs a third less
        travel per crossing (eq. 2.2) and, being below φ, lets two readings of one sensor cross;
        ATM's unprocessed share fell from 29 % to 22 % at equal point error (see
        :mod:`sonarcarve.methods.atm`).
    range_resolution : float, default 0.0254 m
        δ, metres, finite and ≥ 0: range quantum of the sensors (paper: one inch); scales ATM's
        error bound (eq. 5.4).
    max_incidence : float, default π/2 (off)
        β, radians in [0, π/2]: specular-aware carving (beyond the paper), where a newer
        reading does not carve the points of an older arc whose implied surface it would see
        at an incidence above β (see :mod:`sonarcarve.geometry.specular`). π/2
        (:data:`~sonarcarve.geometry.NO_INCIDENCE_LIMIT`): off, the paper.
    evidence_bins : int, default 24
        K, bins per beam of evidence carving (``evidence``; beyond the paper): a carved
        interval is exact to half a bin, which the bound includes.
    carve_probability : float, default 0.8
        P_carve in (0, 1) of evidence carving: a bin is carved on evidence equal to one reading
        that would have heard a surface there with this probability (or several weaker ones).
    min_confidence : float, default 0.5
        In [0, 1]: evidence carving leaves points below this confidence out of its maps.
    stamp_error : float, default 0 m
        Upper bound on a reading's position-stamping error, metres, finite and ≥ 0 (Appendix A,
        where stamps are inferred): added to evidence carving's error bounds.
    stamp_heading_error : float, default 0 rad
        Upper bound on a reading's heading-stamping error, radians in [0, π/2] (Appendix A: the
        robot turned while the stamp was off): a point ``r`` from its sensor moves at most
        ``2 r sin(δ/2)``, added to evidence carving's error bounds. Both bounds from a poller's
        stamp bound: :func:`~sonarcarve.polling.position_error_bound` and
        :func:`~sonarcarve.polling.heading_error_bound`.

    Examples
    --------
    >>> MethodConfig(history_size=100).history_size
    100
    >>> MethodConfig(beam_width=4.0)
    Traceback (most recent call last):
    ...
    sonarcarve.errors.ConfigError: beam_width must lie in [1e-06, pi) radians, got 4.0
    """

    history_size: int = DEFAULT_HISTORY_SIZE
    beam_width: float = DEFAULT_BEAM_WIDTH
    range_tolerance: float = DEFAULT_RANGE_TOLERANCE
    min_transversal: float = DEFAULT_MIN_TRANSVERSAL
    range_resolution: float = POLAROID_RANGE_RESOLUTION
    max_incidence: float = NO_INCIDENCE_LIMIT
    evidence_bins: int = DEFAULT_EVIDENCE_BINS
    carve_probability: float = DEFAULT_CARVE_PROBABILITY
    min_confidence: float = DEFAULT_MIN_CONFIDENCE
    stamp_error: float = 0.0
    stamp_heading_error: float = 0.0

    def __post_init__(self) -> None:
        check_history_size(self.history_size)
        check_beam_width(self.beam_width)
        check_range_tolerance(self.range_tolerance)
        check_min_transversal(self.min_transversal)
        check_range_resolution(self.range_resolution)
        check_max_incidence(self.max_incidence)
        check_evidence_bins(self.evidence_bins)
        check_carve_probability(self.carve_probability)
        check_min_confidence(self.min_confidence)
        check_stamp_error(self.stamp_error)
        check_stamp_heading_error(self.stamp_heading_error)
