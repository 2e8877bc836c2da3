"""sonarcarve: accurate, low-latency maps from ultrasonic range sensors.

Implements *Arc Carving: Obtaining Accurate, Low Latency Maps from Ultrasonic Range Sensors*:
the centerline model, the Arc Transversal Median (ATM), arc carving and their combination, over
a ring-buffer history of sonar arcs, with local and global maps and the paper's measures.
"""

from sonarcarve._version import __version__
from sonarcarve.filters import MapFilter, ReadingFilter, filter_map, filter_readings
from sonarcarve.geometry import ArcFate, arc_remainder, carve_arc
from sonarcarve.grids.elfes import GridError, OccupancyGrid, SonarConeModel
from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.io import (
    read_map_csv,
    read_readings_csv,
    read_rosbag,
    write_map_csv,
    write_readings_csv,
)
from sonarcarve.maps import GlobalMap, LocalMap, PointSource, chord_error
from sonarcarve.methods import (
    METHODS,
    AtmMethod,
    CarvingMethod,
    CenterlineMethod,
    CombinedMethod,
    Measures,
    MethodConfig,
    SonarMethod,
    make_method,
)
from sonarcarve.pipeline import ProcessResult, process_readings
from sonarcarve.polling import PolledLog, SonarPoller, naive_stamps, poll_readings
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch, ReadingsError

__all__ = [
    "DEFAULT_BEAM_WIDTH",
    "DEFAULT_HISTORY_SIZE",
    "METHODS",
    "ArcFate",
    "AtmMethod",
    "CarvingMethod",
    "CenterlineMethod",
    "CombinedMethod",
    "GlobalMap",
    "GridError",
    "LocalMap",
    "MapFilter",
    "Measures",
    "MethodConfig",
    "OccupancyGrid",
    "PointSource",
    "PolledLog",
    "ProcessResult",
    "Reading",
    "ReadingBatch",
    "ReadingFilter",
    "ReadingsError",
    "SonarConeModel",
    "SonarHistory",
    "SonarMethod",
    "SonarPoller",
    "__version__",
    "arc_remainder",
    "carve_arc",
    "chord_error",
    "filter_map",
    "filter_readings",
    "make_method",
    "naive_stamps",
    "poll_readings",
    "process_readings",
    "read_map_csv",
    "read_readings_csv",
    "read_rosbag",
    "write_map_csv",
    "write_readings_csv",
]
