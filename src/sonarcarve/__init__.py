"""sonarcarve: accurate, low-latency maps from ultrasonic range sensors.

Implements *Arc Carving: Obtaining Accurate, Low Latency Maps from Ultrasonic Range Sensors*:
the centerline model, the Arc Transversal Median (ATM), arc carving and their combination, over
a ring-buffer history of sonar arcs, with local and global maps and the paper's measures.
"""

from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
from sonarcarve.maps import GlobalMap, LocalMap, PointSource, chord_error
from sonarcarve.methods import (
    METHODS,
    CenterlineMethod,
    Measures,
    MethodConfig,
    SonarMethod,
    make_method,
)
from sonarcarve.pipeline import ProcessResult, process_readings
from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch, ReadingsError

__version__ = "0.1.0"

__all__ = [
    "DEFAULT_BEAM_WIDTH",
    "DEFAULT_HISTORY_SIZE",
    "METHODS",
    "CenterlineMethod",
    "GlobalMap",
    "LocalMap",
    "Measures",
    "MethodConfig",
    "PointSource",
    "ProcessResult",
    "Reading",
    "ReadingBatch",
    "ReadingsError",
    "SonarHistory",
    "SonarMethod",
    "__version__",
    "chord_error",
    "make_method",
    "process_readings",
]
