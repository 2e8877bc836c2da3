"""The amplitude sonar model: echo levels from the transducer's beam pattern and the walls.

The second physics model of the simulator (``SonarPhysics(echo_model="amplitude")``). Instead
of a hard critical angle, every way sound can come back to the sensor is given a received
*level* by a sonar equation, and the sensor reports the first arrival (shortest range) whose
level, plus Gaussian amplitude noise, reaches a detection threshold.

Levels are in dB relative to the echo of a perfectly reflecting smooth wall met head-on at
1 m (that echo is 0 dB). With ``D(α)`` the one-way directivity of the transducer in dB
(:func:`directivity_db`), ``a`` the absorption in dB/m and path lengths in metres:

* **mirror echo** of a smooth wall (geometric acoustics: the sensor hears its own image in the
  wall, at the foot F of the perpendicular, range d = |F − o|, when F lies on the wall and in
  sight)::

      L = 2 D(β) − 20 log10(d) − 2 a (d − 1) + n · S

  where β is the angle between the sensor axis and the wall normal, ``S`` the loss of one
  specular reflection (:attr:`AmplitudeModel.specular_db`) and n the number of reflections on
  the way (1; 2 for a right-angle corner, which is a retro-reflector; 3 for the multipath
  "bounce off A, head-on at B and back"). A wall is an extended mirror, so its echo spreads as
  from an image source at twice the range: 20 log, not the 40 log of a small target. For a path
  between two different sensors (crosstalk) the two D terms are taken at the emitting and the
  receiving sensor and the spreading is that of half the path.
* **diffuse echo** of the rough part of a wall, traced ray by ray across the beam: a ray at
  off-axis angle α meeting the wall at range r and incidence γ (from the normal) returns::

      L = 2 D(α) − 40 log10(r) − 2 a (r − 1) + 6 + 10 log10(σ A)

  with Lambert's law for backscatter ``σ = ρ f cos²γ / π`` per square metre and steradian
  (ρ = reflectivity², f = :attr:`AmplitudeModel.diffuse_fraction`) and ``A`` the wall area
  that echoes at once: the vertical footprint of the beam ``r Ψ`` times the width along the
  wall, ``(r / cos γ) min(Ψ, cτ / (2 r tan γ))``: the beam's footprint at normal incidence,
  one pulse length's worth (cτ/2 of range) at oblique incidence. Ψ is the two-way equivalent
  beam width of the piston (:func:`equivalent_beam_width`); the 6 dB is the reference's
  −20 log10(2) (an image source at 2 m). Small targets spread as 40 log: they fade much faster
  with range than walls.
* **edge echo** of a corner or free wall end (diffraction: weak, from any angle)::

      L = 2 D(α) − 40 log10(r) − 2 a (r − 1) + E

  with E = :attr:`AmplitudeModel.edge_db`, the level of an edge on the axis at 1 m.

* **small reflectors** (opt-in, :attr:`AmplitudeModel.small_reflectors`): a convex cylinder
  of radius ρ (a table or chair leg, a column; in a world file a closed run of short walls
  turning by at most :attr:`AmplitudeModel.facet_turn` at each joint, seen from outside) is not
  an extended mirror. Geometric
  acoustics: along the cylinder's axis the surface is a plane mirror (the reflected wavefront
  leaves it with radius d and reaches the sensor with 2d); across it a convex mirror of focal
  length ρ/2, whose virtual image lies d' = 1 / (1/d + 2/ρ) behind the surface (the mirror
  equation), so the wavefront leaves with radius d' and arrives with d' + d. Along a ray tube
  the intensity goes as the inverse product of the wavefront's two principal radii (Pierce,
  *Acoustics*, ch. 8, ray acoustics): the echo is (d / 2d)(d' / (d' + d)) of the intensity at
  the surface, against (d / 2d)² for a plane, a ratio 2d' / (d' + d) = ρ / (ρ + d)::

      L_cyl = L_mirror(d) + 10 log10(ρ / (ρ + d))

  A leg of 2 cm radius answers 17.1 dB under a wall at 1 m and 21.8 dB under it at 3 m
  (−37.9 dB, still 14.5 dB above the threshold on the axis; it falls under it at about 5 m).
  For d ≫ ρ this is the target strength of a long cylinder, TS = 10 log10(a r / 4) with the
  echo −40 log r + TS: the finite cylinder's 10 log10(a L² / 2λ) (Urick, *Principles of
  Underwater Sound*, the table of target strengths of simple forms) with an effective length
  that answers at once, L² = λ r / 2 (the square of the first Fresnel zone's radius, not its
  length), which also turns the finite plate's (A/λ)² into the infinite plane's r²/4. The a
  r / 2 tabulated for an infinitely long cylinder is a plane wave's (no spreading on the way
  in along the axis), 3 dB above what a sensor's spherical wave gets back. The echo comes
  from the point of the circle nearest the sensor, wherever it falls (a facet's own foot of
  the perpendicular would leave gaps at the joints). The facet joints are not corners (no
  edge echo), a facet's diffuse area is at most the cylinder's width 2ρ along the surface,
  and facets are not the mirrors of multipath or crosstalk paths: a simplification, not a
  computed level (bounced off a convex mirror such a path spreads faster than off a wall,
  but a receiving sensor that hears no direct echo could still hear it).

The sensor hears an echo when ``L + noise_db · z ≥ threshold_db`` with z standard normal, one
draw per candidate echo; the probability is :func:`detection_probability`. The threshold is the
level of a perfectly reflecting smooth wall head-on at :attr:`AmplitudeModel.detection_range`.

What this sonar does that the specular one does not: the effective beam narrows with range
(a far wall is heard only with its normal near the axis, a near one also through the side
lobes, well outside the nominal beam); detection near the threshold is random; rough walls
answer at any incidence, weakly; edges fade fast with range.

Simplifications: walls are vertical and the sensors horizontal, so the 3-D beam is cut in its
horizontal plane (the vertical beam enters only the diffuse area); the Polaroid ranging
module's time-varying gain is folded into the single threshold; every wall has the same
surface (reflectivity and diffuse fraction). With ``small_reflectors`` a flat face narrower than
the Fresnel radius (√(λ d / 2), 6 cm at 1 m) still echoes like a whole wall: only curved runs
of facets are corrected; a leg is a vertical cylinder taller than the vertical Fresnel zone
(its top and bottom edges are not modelled). A closed run seen from inside (a round room)
echoes as a plane mirror for the direct path but is, like a leg, no mirror for multipath or
crosstalk; a disc that shares a vertex with a wall or another disc is not a closed run, so it
stays a polygon of plane faces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt
from scipy.special import j1, ndtr

from sonarcarve.errors import SonarcarveError
from sonarcarve.typing import FloatArray

__all__ = [
    "AmplitudeModel",
    "SonarPhysicsError",
    "convex_mirror_db",
    "detection_probability",
    "diffuse_echo_db",
    "directivity_db",
    "equivalent_beam_width",
    "mirror_echo_db",
    "path_echo_db",
    "point_echo_db",
]


class SonarPhysicsError(SonarcarveError, ValueError):
    """Sonar physics parameters out of their valid range (of either echo model).

    Defined here, the bottom of the sonar modules, and re-exported by
    :mod:`sonarcarve.sim.sonar`, which imports this module.
    """


@dataclass(frozen=True)
class AmplitudeModel:
    """Parameters of the amplitude sonar model (used when ``SonarPhysics.echo_model`` is
    ``"amplitude"``); levels in dB relative to a smooth wall head-on at 1 m.

    Attributes
    ----------
    frequency : float
        Hz. 49.4 kHz: the Polaroid (SensComp) 6500 ranging module drives the 600-series
        transducer with 16 cycles at 49.4 kHz (module datasheet).
    transducer_radius : float
        Metres. 0.0192: the 600-series transducer's 38.4 mm active face (datasheet), modelled as
        a circular piston. With the sound speed of :class:`~sonarcarve.sim.sonar.SonarPhysics`
        ka = 17.4 and the main lobe's first nulls fall 12.7° off the axis (25.5° null to null:
        the "22.5° beam" quoted for these sensors, a little wider), the first side lobes
        (−17.6 dB) at 17°, the second nulls at 23.8°.
    null_depth_db : float
        Floor of the one-way directivity, dB (< 0). A real membrane is not an ideal piston and
        the pulse is not one frequency, so its nulls are filled in; −30 dB is a judgement, near
        the bottom of the beam-pattern plots of the datasheet.
    pulse_cycles : float
        Cycles in the transmitted pulse (16, module datasheet): the pulse lasts 0.32 ms and
        resolves 5.6 cm of range, which sets the wall area that echoes diffusely at once.
    absorption_db_per_m : float
        Atmospheric absorption, dB per metre of path (counted both ways). 1.64: ISO 9613-1 at
        49.4 kHz, 20 °C, 50 % relative humidity, 101.325 kPa (1.25 at 30 %, 1.71 at 70 %).
    reflectivity : float
        Pressure reflection coefficient of a wall at normal incidence, in [0, 1]. Air against
        plaster, wood, glass or concrete is a huge impedance mismatch (413 rayl against
        10⁶–10⁷), so 1.0; soft furnishings (curtains, foam) reflect less (a judgement per case).
    diffuse_fraction : float
        Share of the reflected energy that a wall scatters diffusely (Lambert's law) instead of
        specularly, in [0, 1]. By the Rayleigh criterion a surface with rms height h scatters
        about 1 − exp(−(2kh)²) of it (k = 2π f / c = 905 /m): 0.02 is h ≈ 0.08 mm, painted
        plaster or wood (a judgement for "smooth" office walls); brick or rough concrete
        (h ≈ 1 mm) are 0.5 or more.
    edge_db : float
        Echo level of a corner or a free wall end on the axis at 1 m, dB. −10 dB is a
        judgement: edges diffract weakly, so on the axis they are heard to about 5 m where a
        smooth wall head-on is heard to ``detection_range``.
    right_corner_tolerance : float
        Radians: a concave corner whose angle is within this of 90° acts as a retro-reflector
        (two specular reflections send the sound straight back), heard like a wall at the
        corner's distance. 2° is a judgement: a corner 90° + δ deflects the return by 2δ.
    detection_range : float
        Metres: a perfectly reflecting smooth wall met head-on is heard out to here (half the
        time: the noise is symmetric); the detection threshold is the level of that echo
        (:attr:`threshold_db`). 10.7 m (35 ft) is the 6500 module's
        specified maximum range. The Scout2 reports at most 255 inches (6.48 m), but that is
        its one-byte range field, not the transducer's sensitivity: the late echoes the paper
        saw (crosstalk) travel 14 m or more and must still be loud enough to be heard.
    noise_db : float
        Standard deviation of the Gaussian amplitude noise on the threshold test, dB (air
        turbulence, temperature gradients and electrical noise make echo levels fluctuate from
        ping to ping). 2 dB is a judgement.
    fan_half_angle : float
        Radians: the diffuse echoes are traced by rays out to this angle either side of the
        axis (30°: the main lobe and the first two side lobes; beyond, two-way directivity is
        at least 48 dB down). Mirror, corner and edge echoes are found exactly at any angle
        within 90° of the axis.
    fan_rays : int
        Rays across the fan, edges included (odd: one on the axis); 61 rays are 1° apart.
    small_reflectors : bool
        Off (the default): every wall, however short, echoes as an extended plane mirror, so a
        leg drawn as a polygon answers like a wall face. On: closed runs of short walls that
        bend by at most ``facet_turn`` at each joint are convex cylinders whose mirror echo spreads
        faster, by ``10 log10(ρ / (ρ + d))`` (:func:`convex_mirror_db`, module docstring), and
        whose joints are not corners.
    facet_turn : float
        Radians, in (0, π/2]: the largest turn at a joint of two walls (and only two) that
        makes them facets of one convex curve, when ``small_reflectors`` is on. 30°: polygons
        of 12 or more sides stand for discs (world files draw them as 24-gons, 15° turns); a
        box's 90° corners stay corners.
    """

    frequency: float = 49_400.0
    transducer_radius: float = 0.0192
    null_depth_db: float = -30.0
    pulse_cycles: float = 16.0
    absorption_db_per_m: float = 1.64
    reflectivity: float = 1.0
    diffuse_fraction: float = 0.02
    edge_db: float = -10.0
    right_corner_tolerance: float = math.radians(2.0)
    detection_range: float = 10.7
    noise_db: float = 2.0
    fan_half_angle: float = math.radians(30.0)
    fan_rays: int = 61
    small_reflectors: bool = False
    facet_turn: float = math.radians(30.0)

    def __post_init__(self) -> None:
        positive = ("frequency", "transducer_radius", "pulse_cycles", "detection_range")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                _bad(name, value, "must be a finite number > 0")
        for name in ("absorption_db_per_m", "noise_db", "right_corner_tolerance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                _bad(name, value, "must be a finite number >= 0")
        for name in ("reflectivity", "diffuse_fraction"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                _bad(name, getattr(self, name), "must lie in [0, 1]")
        if not (math.isfinite(self.null_depth_db) and self.null_depth_db < 0.0):
            _bad("null_depth_db", self.null_depth_db, "must be a finite number < 0")
        if not math.isfinite(self.edge_db):
            _bad("edge_db", self.edge_db, "must be finite")
        if not 0.0 <= self.fan_half_angle <= math.pi / 2:
            _bad("fan_half_angle", self.fan_half_angle, "must lie in [0, π/2] radians")
        if self.fan_rays < 1:
            _bad("fan_rays", self.fan_rays, "must be at least 1")
        if not 0.0 < self.facet_turn <= math.pi / 2:
            _bad("facet_turn", self.facet_turn, "must lie in (0, π/2] radians")
        if not isinstance(self.small_reflectors, bool):  # "no" would turn it on
            _bad("small_reflectors", self.small_reflectors, "must be True or False")

    @property
    def specular_db(self) -> float:
        """Level change of one specular reflection, dB: 10 log10(ρ² (1 − f)) (−inf: none)."""
        keep = self.reflectivity**2 * (1.0 - self.diffuse_fraction)
        return 10.0 * math.log10(keep) if keep > 0.0 else -math.inf

    @property
    def threshold_db(self) -> float:
        """Detection threshold, dB: the level of a perfectly reflecting smooth wall head-on at
        ``detection_range``, −20 log10 R − 2 a (R − 1). A property of the sensor, not of the
        walls: rougher walls answer less loudly, not to a lower threshold."""
        r = self.detection_range
        return float(-20.0 * math.log10(r) - 2.0 * self.absorption_db_per_m * (r - 1.0))

    def ka(self, sound_speed: float) -> float:
        """The piston's size in wavelengths: k a = 2π f a / c (dimensionless)."""
        return 2.0 * math.pi * self.frequency * self.transducer_radius / sound_speed

    def pulse_depth(self, sound_speed: float) -> float:
        """Range resolved by one pulse, c τ / 2, metres (τ = cycles / frequency)."""
        return sound_speed * self.pulse_cycles / self.frequency / 2.0


def directivity_db(model: AmplitudeModel, off_axis: npt.ArrayLike,
                   sound_speed: float = 343.0) -> FloatArray:
    """One-way directivity of the circular piston, dB (0 on the axis, <= 0 elsewhere).

    ``20 log10 |2 J1(x) / x|`` with ``x = k a sin α`` (Kinsler et al., *Fundamentals of
    Acoustics*, the baffled circular piston), floored at ``model.null_depth_db``; angles beyond
    90° (behind the sensor) get the floor.

    Parameters
    ----------
    model : AmplitudeModel
    off_axis : array-like
        Angles from the sensor axis, radians (any shape; sign ignored).
    sound_speed : float
        m/s.

    Examples
    --------
    >>> m = AmplitudeModel()
    >>> directivity_db(m, [0.0, math.radians(90.0)]).round(1).tolist()
    [0.0, -30.0]
    """
    alpha = np.abs(np.asarray(off_axis, dtype=np.float64))
    x = model.ka(sound_speed) * np.sin(np.minimum(alpha, math.pi / 2))
    safe = np.where(x < 1e-8, 1.0, x)
    ratio = np.where(x < 1e-8, 1.0, np.abs(2.0 * j1(safe) / safe))
    with np.errstate(divide="ignore"):
        level = 20.0 * np.log10(ratio)
    level = np.maximum(level, model.null_depth_db)
    return np.asarray(np.where(alpha > math.pi / 2, model.null_depth_db, level))


def equivalent_beam_width(model: AmplitudeModel, sound_speed: float = 343.0) -> float:
    """Two-way equivalent beam width Ψ = ∫ b(ψ)⁴ dψ of the piston, radians (b: one-way
    pressure directivity): the angle of an ideal beam that hears an extended diffuse surface
    as loudly. About 0.14 rad (8°) for the default transducer."""
    return _beam_integral(round(model.ka(sound_speed), 12), model.null_depth_db)


@lru_cache(maxsize=16)
def _beam_integral(ka: float, floor_db: float) -> float:
    psi = np.linspace(-math.pi / 2, math.pi / 2, 20_001)
    x = ka * np.sin(psi)
    safe = np.where(np.abs(x) < 1e-8, 1.0, x)
    b = np.where(np.abs(x) < 1e-8, 1.0, np.abs(2.0 * j1(safe) / safe))
    b = np.maximum(b, 10.0 ** (floor_db / 20.0))
    return float(np.trapezoid(b**4, psi))


def path_echo_db(model: AmplitudeModel, path_length: npt.ArrayLike, emit_angle: npt.ArrayLike,
                 receive_angle: npt.ArrayLike, reflections: npt.ArrayLike = 1,
                 sound_speed: float = 343.0) -> FloatArray:
    """Level of sound reflected specularly along a path of the given length, dB.

    ``D(emit) + D(receive) − 20 log10(P / 2) − a (P − 2) + n S``: spherical spreading from the
    image source at distance P (a mirror path), absorption over the path, n specular
    reflections. Relative to a smooth wall head-on at 1 m (P = 2 m, one reflection of a
    perfect reflector): 0 dB there.

    Parameters
    ----------
    path_length : array-like
        Total path, sensor to sensor, metres (> 0).
    emit_angle, receive_angle : array-like
        Off-axis angles of the path at the emitting and the receiving sensor, radians.
    reflections : array-like of int
        Specular reflections on the path.
    """
    p = np.asarray(path_length, dtype=np.float64)
    loss = model.specular_db * np.asarray(reflections, dtype=np.float64)
    return np.asarray(directivity_db(model, emit_angle, sound_speed)
                      + directivity_db(model, receive_angle, sound_speed)
                      - 20.0 * np.log10(p / 2.0) - model.absorption_db_per_m * (p - 2.0)
                      + np.nan_to_num(loss, nan=0.0, neginf=-np.inf))


def mirror_echo_db(model: AmplitudeModel, distance: npt.ArrayLike, off_axis: npt.ArrayLike,
                   reflections: npt.ArrayLike = 1, sound_speed: float = 343.0) -> FloatArray:
    """Level of a wall's mirror echo at perpendicular distance ``distance`` (m), its normal
    ``off_axis`` radians from the sensor axis: 2 D(β) − 20 log10 d − 2 a (d − 1) + n S, dB.

    Examples
    --------
    >>> m = AmplitudeModel(diffuse_fraction=0.0)
    >>> float(mirror_echo_db(m, 1.0, 0.0))
    0.0
    >>> round(float(mirror_echo_db(m, 2.0, 0.0)), 2)  # -6.02 spreading, -3.28 absorption
    -9.3
    """
    d = np.asarray(distance, dtype=np.float64)
    return path_echo_db(model, 2.0 * d, off_axis, off_axis, reflections, sound_speed)


def convex_mirror_db(radius: npt.ArrayLike, distance: npt.ArrayLike) -> FloatArray:
    """Level of a convex cylinder's mirror echo relative to a plane wall's at the same
    distance, dB: ``10 log10(ρ / (ρ + d))`` (module docstring, small reflectors).

    Parameters
    ----------
    radius : array-like
        The cylinder's radius ρ, metres (> 0; inf: a plane, 0 dB).
    distance : array-like
        Sensor to the nearest point of the surface, metres (>= 0).

    Examples
    --------
    >>> convex_mirror_db([0.02, 0.2, np.inf], 1.0).round(2).tolist()  # a leg, a column, a wall
    [-17.08, -7.78, 0.0]
    """
    rho = np.asarray(radius, dtype=np.float64)
    d = np.asarray(distance, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        ratio = np.where(np.isinf(rho), 1.0, rho / (rho + d))
    return np.asarray(10.0 * np.log10(ratio))


def point_echo_db(model: AmplitudeModel, distance: npt.ArrayLike, off_axis: npt.ArrayLike,
                  strength_db: npt.ArrayLike, sound_speed: float = 343.0) -> FloatArray:
    """Level of a small target: 2 D(α) − 40 log10 r − 2 a (r − 1) + strength, dB.

    ``strength_db`` is the target's level on the axis at 1 m (for an edge,
    :attr:`AmplitudeModel.edge_db`).
    """
    r = np.asarray(distance, dtype=np.float64)
    return np.asarray(2.0 * directivity_db(model, off_axis, sound_speed) - 40.0 * np.log10(r)
                      - 2.0 * model.absorption_db_per_m * (r - 1.0)
                      + np.asarray(strength_db, dtype=np.float64))


def diffuse_echo_db(model: AmplitudeModel, distance: npt.ArrayLike, off_axis: npt.ArrayLike,
                    incidence: npt.ArrayLike, sound_speed: float = 343.0,
                    width: npt.ArrayLike = math.inf) -> FloatArray:
    """Level of the diffuse (Lambertian) echo of the wall patch a ray meets, dB (−inf: none).

    A point target (40 log spreading) of strength ``6 + 10 log10(σ A)`` with
    ``σ = ρ² f cos²γ / π`` and ``A = r Ψ (r / cos γ) min(Ψ, cτ / (2 r tan γ), w cos γ / r)``
    (module docstring; ``w`` the widest the surface is, along it, inf for a wall).

    Parameters
    ----------
    distance : array-like
        Range of the patch, metres (> 0).
    off_axis : array-like
        Angle of the ray from the sensor axis, radians.
    incidence : array-like
        Angle between the ray and the wall normal, radians, in [0, π/2].
    width : array-like
        Metres: the surface's extent along it that can echo at once (a cylinder's 2ρ with
        ``small_reflectors``); inf (the default) for a wall wider than the beam.
    """
    r = np.asarray(distance, dtype=np.float64)
    gamma = np.minimum(np.abs(np.asarray(incidence, dtype=np.float64)), math.pi / 2)
    psi = equivalent_beam_width(model, sound_speed)
    cos_g = np.cos(gamma)
    tan_g = np.maximum(np.tan(np.minimum(gamma, math.pi / 2 - 1e-9)), 1e-12)
    across = np.minimum(psi, model.pulse_depth(sound_speed) / (r * tan_g))
    w = np.asarray(width, dtype=np.float64)
    if np.any(np.isfinite(w)):  # skipped for walls: the default stays bit for bit
        across = np.minimum(across, w * cos_g / r)
    area = r * psi * r / np.maximum(cos_g, 1e-12) * across
    sigma = model.reflectivity**2 * model.diffuse_fraction * cos_g**2 / math.pi
    with np.errstate(divide="ignore"):
        strength = 6.0 + 10.0 * np.log10(sigma * area)
    return point_echo_db(model, r, off_axis, strength, sound_speed)


def detection_probability(model: AmplitudeModel, level_db: npt.ArrayLike) -> FloatArray:
    """Chance that an echo of level ``level_db`` is heard: P(L + σ z >= threshold).

    Examples
    --------
    >>> m = AmplitudeModel()
    >>> float(detection_probability(m, m.threshold_db))
    0.5
    """
    margin = np.asarray(level_db, dtype=np.float64) - model.threshold_db
    if model.noise_db == 0.0:
        return np.asarray((margin >= 0.0).astype(np.float64))
    return np.asarray(ndtr(margin / model.noise_db))


def _bad(name: str, value: object, problem: str) -> None:
    msg = f"AmplitudeModel.{name} {problem}, got {value!r}"
    raise SonarPhysicsError(msg)
