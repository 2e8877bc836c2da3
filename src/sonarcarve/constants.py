"""Physical constants and the paper's sensor figures, named once.

Everything in memory is SI (metres, radians, seconds); these are the few numbers the paper and
its sensors give in other units.
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_BEAM_WIDTH", "INCH", "MIN_BEAM_WIDTH", "POLAROID_RANGE_RESOLUTION"]

#: One inch, metres.
INCH = 0.0254
#: The Polaroid transducer's beam (arc) width φ (paper, section 2): 22.5 degrees, radians.
DEFAULT_BEAM_WIDTH = math.radians(22.5)
#: The narrowest beam width accepted anywhere, radians (about 0.00006 degrees). Sonar beams are
#: 5-60 degrees wide and the narrowest range sensors (infrared, time of flight) about 1 degree;
#: far below that the beam geometry divides by widths that underflow (a 5e-324 rad beam divided
#: by zero in evidence carving), so a narrower width is a damaged value, not a sensor.
MIN_BEAM_WIDTH = 1e-6
#: The Polaroid ranging module's range quantum δ (paper, section 5: one inch), metres.
POLAROID_RANGE_RESOLUTION = INCH
