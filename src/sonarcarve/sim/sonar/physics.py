"""How the simulated sensors behave: :class:`SonarPhysics`, its echo models and defaults.

One frozen record of every parameter of both echo models (``"specular"`` and ``"amplitude"``,
:data:`ECHO_MODELS`), each effect switchable on its own; the amplitude model's own parameters
are an :class:`~sonarcarve.sim.amplitude.AmplitudeModel` inside it. Invalid values raise
:class:`~sonarcarve.sim.amplitude.SonarPhysicsError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from sonarcarve.sim.amplitude import AmplitudeModel, SonarPhysicsError

__all__ = [
    "DEFAULT_PHYSICS",
    "ECHO_MODELS",
    "PHYSICS_NAMES",
    "SonarPhysics",
    "named_physics",
]


#: The echo models :attr:`SonarPhysics.echo_model` accepts.
ECHO_MODELS = ("specular", "amplitude")


@dataclass(frozen=True)
class SonarPhysics:
    """How the simulated sensors behave; every effect can be switched off on its own.

    Attributes
    ----------
    rays_per_beam : int
        Rays traced evenly across the beam, edges included (odd: one on the axis). At 31
        rays a 22.5° beam has rays 0.75° apart, 8 cm apart at 6.5 m.
    specular : bool
        Smooth walls (True): a ray echoes only within ``critical_angle`` of the wall normal or
        near a corner. False: every wall echoes from any angle (the idealised "arc" sensor).
    critical_angle : float
        Largest incidence angle (between the ray and the wall normal), radians, at which a
        smooth wall still returns an echo. Default 17.5°: the middle of the 15-20° range
        commonly quoted for Polaroid transducers on smooth walls (assumed, not measured here).
    corner_radius : float
        Metres: a ray meeting a wall within this distance of a corner or a free wall end echoes
        whatever its incidence (edges and corners scatter sound back).
    corner_echoes : bool
        Corners and free wall ends inside the beam and in sight echo from the corner point
        itself (exactly, not only where a ray happens to land near them).
    range_noise : float
        Standard deviation of the Gaussian range noise, metres (default 1 cm).
    quantise : bool
        Round ranges to the robot's range resolution.
    crosstalk_probability : float
        Chance that a late echo of a recent ping, arriving while this sensor listens and from
        within ``crosstalk_acceptance`` of its axis, is loud enough to be heard. The default
        0.2 is a judgement (such echoes have travelled 14 m or more); on the office tour it
        makes about 5 % of scout2's readings crosstalk (``benchmarks/simulate_speed.py``).
    crosstalk_lookback : int
        How many previous firings can still be echoing (2: the last two pings).
    crosstalk_acceptance : float
        Half-angle, radians, about the sensor axis from which a sensor hears a stray echo
        (default 90°: the front half-plane; the robot body shadows the rest).
    floor_episode_rate : float
        Tilt episodes (bumps, ramps, door sills) per second of travel time.
    floor_episode_duration : float
        Mean length of a tilt episode, seconds (exponentially distributed).
    floor_probability : float
        Chance that a sensor facing down the tilt hears the floor during an episode.
    floor_range : float
        Mean range of a floor echo, metres: the paper's Scout2 sensors sit 10.25 in above the
        floor and hear it "at just over 2 feet" (Appendix B), so 0.62 m.
    floor_range_sd : float
        Standard deviation of the floor echo range, metres.
    floor_half_angle : float
        Sensors within this angle of the tilt direction, radians, see the floor.
    multipath_probability : float
        Chance that a bounced echo (specular off one wall, head-on at a second) is loud enough
        to be heard, when it arrives before any direct echo.
    sound_speed : float
        Speed of sound, m/s (343: dry air at 20 °C); converts firing gaps to ranges.
    echo_model : str
        ``"specular"`` (the default): rays across the beam, smooth walls echo within
        ``critical_angle``, spurious echoes by their probabilities. ``"amplitude"``: echo
        levels from the transducer's beam pattern, spreading, absorption and the walls'
        reflection against a noisy detection threshold, parameters in ``amplitude``
        (:mod:`sonarcarve.sim.amplitude`). The amplitude model ignores ``rays_per_beam``,
        ``specular``, ``critical_angle``, ``corner_radius`` and ``corner_echoes``, and uses
        ``crosstalk_probability`` and ``multipath_probability`` only as switches (0: off):
        loudness decides which of those echoes are heard.
    amplitude : AmplitudeModel
        Parameters of the amplitude model (unused by the specular one).
    """

    rays_per_beam: int = 31
    specular: bool = True
    critical_angle: float = math.radians(17.5)
    corner_radius: float = 0.05
    corner_echoes: bool = True
    range_noise: float = 0.01
    quantise: bool = True
    crosstalk_probability: float = 0.2
    crosstalk_lookback: int = 2
    crosstalk_acceptance: float = math.radians(90.0)
    floor_episode_rate: float = 1.0 / 30.0
    floor_episode_duration: float = 1.0
    floor_probability: float = 0.5
    floor_range: float = 0.62
    floor_range_sd: float = 0.05
    floor_half_angle: float = math.radians(60.0)
    multipath_probability: float = 0.5
    sound_speed: float = 343.0
    echo_model: str = "specular"
    amplitude: AmplitudeModel = field(default_factory=AmplitudeModel)

    def __post_init__(self) -> None:
        if self.echo_model not in ECHO_MODELS:
            choices = ", ".join(repr(name) for name in ECHO_MODELS)
            _bad("echo_model", self.echo_model, f"must be one of {choices}")
        if not isinstance(self.amplitude, AmplitudeModel):
            _bad("amplitude", self.amplitude, "must be an AmplitudeModel")
        if self.rays_per_beam < 1:
            _bad("rays_per_beam", self.rays_per_beam, "must be at least 1")
        if self.crosstalk_lookback < 0:
            _bad("crosstalk_lookback", self.crosstalk_lookback, "must be >= 0")
        if not 0.0 <= self.critical_angle <= math.pi / 2:
            _bad("critical_angle", self.critical_angle, "must lie in [0, π/2] radians")
        for name in ("crosstalk_probability", "floor_probability", "multipath_probability"):
            if not 0.0 <= getattr(self, name) <= 1.0:
                _bad(name, getattr(self, name), "must lie in [0, 1]")
        for name in ("corner_radius", "range_noise", "floor_episode_rate",
                     "floor_episode_duration", "floor_range", "floor_range_sd",
                     "floor_half_angle", "crosstalk_acceptance"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                _bad(name, value, "must be a finite number >= 0")
        if not (math.isfinite(self.sound_speed) and self.sound_speed > 0.0):
            _bad("sound_speed", self.sound_speed, "must be > 0")

    @classmethod
    def clean(cls) -> SonarPhysics:
        """Specular walls and corners only: no noise, no quantisation, no spurious echoes."""
        return cls(range_noise=0.0, quantise=False, crosstalk_probability=0.0,
                   floor_episode_rate=0.0, multipath_probability=0.0)

    @classmethod
    def ideal(cls) -> SonarPhysics:
        """The arc model's sensor: every wall in the beam echoes; nothing else goes wrong."""
        return replace(cls.clean(), specular=False)


#: The default sensor model (every effect on, at the documented defaults).
DEFAULT_PHYSICS = SonarPhysics()

#: The sensor models ``sonarcarve simulate --physics`` and the benchmarks choose by name: each
#: echo model, and ``"amplitude-thin"``, the amplitude model with small reflectors (legs and
#: columns echo as convex cylinders, :attr:`AmplitudeModel.small_reflectors`).
PHYSICS_NAMES = (*ECHO_MODELS, "amplitude-thin")


def named_physics(name: str, base: SonarPhysics = DEFAULT_PHYSICS) -> SonarPhysics:
    """``base`` (every other parameter) with the sensor model named ``name``, one of
    :data:`PHYSICS_NAMES`.

    Examples
    --------
    >>> named_physics("amplitude-thin").amplitude.small_reflectors
    True
    >>> named_physics("specular") is DEFAULT_PHYSICS
    True
    """
    if name not in PHYSICS_NAMES:
        choices = ", ".join(repr(n) for n in PHYSICS_NAMES)
        msg = f"unknown sensor model {name!r}; choose one of {choices}"
        raise SonarPhysicsError(msg)
    thin = name == "amplitude-thin"
    echo_model = "amplitude" if thin else name
    physics = base if echo_model == base.echo_model else replace(base, echo_model=echo_model)
    if physics.amplitude.small_reflectors != thin:  # "amplitude" from a thin base: off again
        physics = replace(physics, amplitude=replace(physics.amplitude, small_reflectors=thin))
    return physics


def _bad(name: str, value: object, problem: str) -> None:
    msg = f"SonarPhysics.{name} {problem}, got {value!r}"
    raise SonarPhysicsError(msg)
