"""Reading filters and map filters (paper, Appendix B and Fig. 13b), and ours beyond it.

- :mod:`~sonarcarve.filters.readings`: drop readings before a method sees them (maximum and
  minimum range, the jump filter), in a batch or one reading at a time.
- :mod:`~sonarcarve.filters.maps`: drop points from a local or global map
  (:func:`filter_map`), in this order: late echoes (below), confidence, the paper's
  maximum-error thresholding, driven through and occlusion (below), the paper's outlier test.
  The three beyond the paper are off by default.
- :mod:`~sonarcarve.filters.late_echoes`: points that are the far echo of an earlier firing
  off a surface of the map (ghost walls, when a sensor fires faster than its hearing range's
  round trip).
- :mod:`~sonarcarve.filters.driven_through`: points the robot's body covered at a later pose
  (ghost walls of late echoes, floor echoes, what has moved away).
- :mod:`~sonarcarve.filters.occlusion`: points behind a surface of the map, seen from their
  own sensor (multipath echoes mostly).
- :mod:`~sonarcarve.filters.checks`: :class:`FilterError` and the one check of a positive
  parameter they share.

Everything is importable from here (``from sonarcarve.filters import MapFilter``).
"""

from __future__ import annotations

from sonarcarve.filters.checks import FilterError
from sonarcarve.filters.driven_through import (
    DISC_SIDES,
    DRIVEN_MARGIN,
    DRIVEN_MAX_GAP,
    DRIVEN_STEP,
    BodyFootprint,
    driven_through_mask,
    swept_poses,
)
from sonarcarve.filters.late_echoes import (
    BETWEEN_MARGIN,
    FIRING_TIME_TOLERANCE,
    LATE_ECHO_HALF_WIDTH,
    LATE_ECHO_LAGS,
    LATE_ECHO_SURFACE_ERROR,
    LATE_ECHO_TOLERANCE,
    MAX_LATE_ECHO_LAGS,
    SOUND_SPEED,
    FiringSchedule,
    LateEchoError,
    far_echo_distance,
    late_echo_mask,
)
from sonarcarve.filters.maps import (
    FilteredMap,
    MapFilter,
    MapFilterReport,
    confidence_mask,
    filter_map,
    max_error_mask,
    outlier_mask,
)
from sonarcarve.filters.occlusion import (
    OCCLUSION_CROSSING,
    OCCLUSION_DEPTH,
    OCCLUSION_REACH,
    SURFACE_NEIGHBOURS,
    SURFACE_RADIUS,
    occlusion_mask,
    origins_by_id,
    point_origins,
)
from sonarcarve.filters.readings import (
    PAPER_MAX_RANGE,
    DropReason,
    FilteredReadings,
    ReadingFilter,
    ReadingFilterReport,
    ReadingFilterStream,
    filter_readings,
)

__all__ = [
    "BETWEEN_MARGIN",
    "DISC_SIDES",
    "DRIVEN_MARGIN",
    "DRIVEN_MAX_GAP",
    "DRIVEN_STEP",
    "FIRING_TIME_TOLERANCE",
    "LATE_ECHO_HALF_WIDTH",
    "LATE_ECHO_LAGS",
    "LATE_ECHO_SURFACE_ERROR",
    "LATE_ECHO_TOLERANCE",
    "MAX_LATE_ECHO_LAGS",
    "OCCLUSION_CROSSING",
    "OCCLUSION_DEPTH",
    "OCCLUSION_REACH",
    "PAPER_MAX_RANGE",
    "SOUND_SPEED",
    "SURFACE_NEIGHBOURS",
    "SURFACE_RADIUS",
    "BodyFootprint",
    "DropReason",
    "FilterError",
    "FilteredMap",
    "FilteredReadings",
    "FiringSchedule",
    "LateEchoError",
    "MapFilter",
    "MapFilterReport",
    "ReadingFilter",
    "ReadingFilterReport",
    "ReadingFilterStream",
    "confidence_mask",
    "driven_through_mask",
    "far_echo_distance",
    "filter_map",
    "filter_readings",
    "late_echo_mask",
    "max_error_mask",
    "occlusion_mask",
    "origins_by_id",
    "outlier_mask",
    "point_origins",
    "swept_poses",
]

