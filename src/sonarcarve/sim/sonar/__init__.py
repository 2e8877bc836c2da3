"""Ultrasonic sensor physics: what a sonar hears when it fires at a world of walls.

A firing is traced as a fan of rays across the beam (paper, section 2: the main lobe of width φ).
Each ray stops at the first wall it meets. Walls are smooth, so sound is reflected
*specularly*: a ray comes back to the sensor only when it meets the wall within the critical
angle of the wall's normal, or when it meets the wall near a corner or a free wall end (edges
and corners scatter in every direction). Time of flight measures the *first* echo, so the
nearest echoing ray wins and its hit point is the reading's true reflection point.

On top of that come the failures the paper met on its Scout2 (Appendix B), each with a rate:

* **crosstalk**: the late echo of a previous ping (another sensor's, typically off a wall
  beyond its maximum range) arrives while this sensor listens; the range is that echo's path
  length minus the time between the two firings, usually wrong;
* **floor bounce**: while the robot tilts (random episodes), sensors facing down the tilt hear
  the floor at about 0.6 m;
* **multipath**: a ray reflected specularly off one wall meets a second wall head-on and comes
  back the same way: the range is the length of the bounced path, too long.

Every echo carries its truth: its :class:`EchoKind` and, where there is one, its reflection
point (a wall point for direct echoes, the second wall point for multipath ones).

That is the ``"specular"`` echo model (:attr:`SonarPhysics.echo_model`, the default). The
``"amplitude"`` model (:mod:`sonarcarve.sim.amplitude`) replaces the critical angle and the
echo probabilities by received levels against a detection threshold: walls answer by their
mirror image (heard when their normal falls in the transducer's beam pattern, main lobe or side
lobes, loudly enough for the range), by diffuse scattering ray by ray, and corners and wall
ends by retro-reflection or diffraction; multipath and crosstalk paths are followed the same way
and heard when loud enough. Floor echoes keep their episodes and probability in both models.

With a :class:`~sonarcarve.sim.scene.Scene` (``fire_sonars(..., scene=)``), each firing is traced
against the walls plus the scene's obstacles present at its time, where they are at that time;
everything else is the same (and without a scene, bit for bit what it was).

The package, one module per concept (bottom to top):

* :mod:`~sonarcarve.sim.sonar.records`: :class:`Firings`, :class:`Echoes`, :class:`EchoKind`;
* :mod:`~sonarcarve.sim.sonar.physics`: :class:`SonarPhysics`, the echo models, the defaults;
* :mod:`~sonarcarve.sim.sonar.draws`: every random draw, made up front;
* :mod:`~sonarcarve.sim.sonar.wall_geometry` and :mod:`~sonarcarve.sim.sonar.scenery`: the
  walls (normals, corners) each firing meets, with or without a scene;
* :mod:`~sonarcarve.sim.sonar.tracing`: what both models' tracing shares (batches, ray casts);
* :mod:`~sonarcarve.sim.sonar.specular` and :mod:`~sonarcarve.sim.sonar.spurious`: the
  specular model's beams, corners and multipath; crosstalk and floor echoes;
* :mod:`~sonarcarve.sim.sonar.amplitude_hearing`, :mod:`~sonarcarve.sim.sonar.amplitude_candidates`,
  :mod:`~sonarcarve.sim.sonar.amplitude_paths` and :mod:`~sonarcarve.sim.sonar.amplitude_tracing`:
  the amplitude model's tracing (its sonar equations are :mod:`sonarcarve.sim.amplitude`);
* :mod:`~sonarcarve.sim.sonar.fire`: :func:`fire_sonars`, which runs them all.

Import the public names from :mod:`sonarcarve.sim.sonar` (or :mod:`sonarcarve.sim`).
"""

from sonarcarve.sim.amplitude import SonarPhysicsError
from sonarcarve.sim.sonar.fire import fire_sonars
from sonarcarve.sim.sonar.physics import (
    DEFAULT_PHYSICS,
    ECHO_MODELS,
    PHYSICS_NAMES,
    SonarPhysics,
    named_physics,
)
from sonarcarve.sim.sonar.records import NO_ECHO, Echoes, EchoKind, Firings

__all__ = [
    "DEFAULT_PHYSICS",
    "ECHO_MODELS",
    "NO_ECHO",
    "PHYSICS_NAMES",
    "EchoKind",
    "Echoes",
    "Firings",
    "SonarPhysics",
    "SonarPhysicsError",
    "fire_sonars",
    "named_physics",
]
