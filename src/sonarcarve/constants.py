"""Physical constants and the paper's sensor figures, named once.

Everything in memory is SI (metres, radians, seconds); these are the few numbers the paper and
its sensors give in other units.
"""

from __future__ import annotations

import math

__all__ = ["DEFAULT_BEAM_WIDTH", "INCH", "POLAROID_RANGE_RESOLUTION"]

#: One inch, metres.
INCH = 0.0254
#: The Polaroid transducer's beam (arc) width φ (paper, section 2): 22.5 degrees, radians.
DEFAULT_BEAM_WIDTH = math.radians(22.5)
#: The Polaroid ranging module's range quantum δ (paper, section 5: one inch), metres.
POLAROID_RANGE_RESOLUTION = INCH
