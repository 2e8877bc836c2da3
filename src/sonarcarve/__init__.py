"""sonarcarve: accurate, low-latency maps from ultrasonic range sensors.

Implements *Arc Carving: Obtaining Accurate, Low Latency Maps from Ultrasonic Range Sensors*:
the centerline model, the Arc Transversal Median (ATM), arc carving and their combination, over
a ring-buffer history of sonar arcs, with local and global maps and the paper's measures; and
beyond it, evidence carving and occupancy grids (the carved grid, ROS's range-sensor layer).

The names below are loaded on first use (PEP 562), so ``import sonarcarve`` and the command
line's ``--version`` and ``--help`` start without numpy, scipy or numba.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from sonarcarve._version import __version__

if TYPE_CHECKING:
    from sonarcarve.errors import (
        ConfigError,
        MethodStateError,
        ReadingTypeError,
        SonarcarveError,
    )
    from sonarcarve.extras import MissingExtraError
    from sonarcarve.filters import (
        BodyFootprint,
        FilterError,
        MapFilter,
        ReadingFilter,
        filter_map,
        filter_readings,
    )
    from sonarcarve.filters.late_echoes import LateEchoError, late_echo_mask
    from sonarcarve.geometry import ArcFate, arc_remainder, carve_arc
    from sonarcarve.grids import (
        CarvedGrid,
        CarvedGridParams,
        GridError,
        OccupancyGrid,
        RangeSensorLayer,
        SonarConeModel,
        make_grid,
        readings_extent,
    )
    from sonarcarve.history import DEFAULT_HISTORY_SIZE, SonarHistory
    from sonarcarve.io import (
        InputError,
        OutputError,
        read_map_csv,
        read_readings_csv,
        read_rosbag,
        write_map_csv,
        write_readings_csv,
    )
    from sonarcarve.io.marker_bytes import UnsupportedLayoutError
    from sonarcarve.io.rosbag import RosbagError, SensorMounts
    from sonarcarve.maps import (
        CallbackSink,
        CountingSink,
        GlobalMap,
        GlobalMapSink,
        LocalMap,
        PointSource,
        chord_error,
    )
    from sonarcarve.methods import (
        METHODS,
        AtmMethod,
        CarvingMethod,
        CenterlineMethod,
        CombinedMethod,
        EvidenceMethod,
        Measures,
        MethodConfig,
        SonarMethod,
        make_method,
    )
    from sonarcarve.methods.atm import CrossingStoreError
    from sonarcarve.methods.evidence import ConfidenceModel
    from sonarcarve.pipeline import ProcessError, ProcessResult, process_chunks, process_readings
    from sonarcarve.polling import (
        PolledLog,
        PollingError,
        SonarPoller,
        naive_stamps,
        poll_readings,
    )
    from sonarcarve.readings import DEFAULT_BEAM_WIDTH, Reading, ReadingBatch, ReadingsError

#: Public name -> the module that defines it.
_EXPORTS = {
    "SonarcarveError": "sonarcarve.errors",
    "ConfigError": "sonarcarve.errors",
    "MethodStateError": "sonarcarve.errors",
    "ReadingTypeError": "sonarcarve.errors",
    "InputError": "sonarcarve.io",
    "OutputError": "sonarcarve.io",
    "RosbagError": "sonarcarve.io.rosbag",
    "UnsupportedLayoutError": "sonarcarve.io.marker_bytes",
    "FilterError": "sonarcarve.filters",
    "LateEchoError": "sonarcarve.filters.late_echoes",
    "late_echo_mask": "sonarcarve.filters.late_echoes",
    "CrossingStoreError": "sonarcarve.methods.atm",
    "ProcessError": "sonarcarve.pipeline",
    "PollingError": "sonarcarve.polling",
    "MissingExtraError": "sonarcarve.extras",
    "ArcFate": "sonarcarve.geometry",
    "AtmMethod": "sonarcarve.methods",
    "CarvedGrid": "sonarcarve.grids",
    "CarvedGridParams": "sonarcarve.grids",
    "ConfidenceModel": "sonarcarve.methods.evidence",
    "SensorMounts": "sonarcarve.io.rosbag",
    "process_chunks": "sonarcarve.pipeline",
    "CarvingMethod": "sonarcarve.methods",
    "CenterlineMethod": "sonarcarve.methods",
    "CombinedMethod": "sonarcarve.methods",
    "EvidenceMethod": "sonarcarve.methods",
    "DEFAULT_BEAM_WIDTH": "sonarcarve.readings",
    "DEFAULT_HISTORY_SIZE": "sonarcarve.history",
    "CallbackSink": "sonarcarve.maps",
    "CountingSink": "sonarcarve.maps",
    "GlobalMap": "sonarcarve.maps",
    "GlobalMapSink": "sonarcarve.maps",
    "GridError": "sonarcarve.grids",
    "LocalMap": "sonarcarve.maps",
    "METHODS": "sonarcarve.methods",
    "MapFilter": "sonarcarve.filters",
    "BodyFootprint": "sonarcarve.filters",
    "Measures": "sonarcarve.methods",
    "MethodConfig": "sonarcarve.methods",
    "OccupancyGrid": "sonarcarve.grids",
    "PointSource": "sonarcarve.maps",
    "PolledLog": "sonarcarve.polling",
    "ProcessResult": "sonarcarve.pipeline",
    "RangeSensorLayer": "sonarcarve.grids",
    "Reading": "sonarcarve.readings",
    "ReadingBatch": "sonarcarve.readings",
    "ReadingFilter": "sonarcarve.filters",
    "ReadingsError": "sonarcarve.readings",
    "SonarConeModel": "sonarcarve.grids",
    "SonarHistory": "sonarcarve.history",
    "SonarMethod": "sonarcarve.methods",
    "SonarPoller": "sonarcarve.polling",
    "arc_remainder": "sonarcarve.geometry",
    "carve_arc": "sonarcarve.geometry",
    "chord_error": "sonarcarve.maps",
    "filter_map": "sonarcarve.filters",
    "filter_readings": "sonarcarve.filters",
    "make_grid": "sonarcarve.grids",
    "make_method": "sonarcarve.methods",
    "naive_stamps": "sonarcarve.polling",
    "poll_readings": "sonarcarve.polling",
    "process_readings": "sonarcarve.pipeline",
    "read_map_csv": "sonarcarve.io",
    "read_readings_csv": "sonarcarve.io",
    "read_rosbag": "sonarcarve.io",
    "readings_extent": "sonarcarve.grids",
    "write_map_csv": "sonarcarve.io",
    "write_readings_csv": "sonarcarve.io",
}

__all__ = [
    "DEFAULT_BEAM_WIDTH",
    "DEFAULT_HISTORY_SIZE",
    "METHODS",
    "ArcFate",
    "AtmMethod",
    "BodyFootprint",
    "CallbackSink",
    "CarvedGrid",
    "CarvedGridParams",
    "CarvingMethod",
    "CenterlineMethod",
    "CombinedMethod",
    "ConfidenceModel",
    "ConfigError",
    "CountingSink",
    "CrossingStoreError",
    "EvidenceMethod",
    "FilterError",
    "GlobalMap",
    "GlobalMapSink",
    "GridError",
    "InputError",
    "LateEchoError",
    "LocalMap",
    "MapFilter",
    "Measures",
    "MethodConfig",
    "MethodStateError",
    "MissingExtraError",
    "OccupancyGrid",
    "OutputError",
    "PointSource",
    "PolledLog",
    "PollingError",
    "ProcessError",
    "ProcessResult",
    "RangeSensorLayer",
    "Reading",
    "ReadingBatch",
    "ReadingFilter",
    "ReadingTypeError",
    "ReadingsError",
    "RosbagError",
    "SensorMounts",
    "SonarConeModel",
    "SonarHistory",
    "SonarMethod",
    "SonarPoller",
    "SonarcarveError",
    "UnsupportedLayoutError",
    "__version__",
    "arc_remainder",
    "carve_arc",
    "chord_error",
    "filter_map",
    "filter_readings",
    "late_echo_mask",
    "make_grid",
    "make_method",
    "naive_stamps",
    "poll_readings",
    "process_chunks",
    "process_readings",
    "read_map_csv",
    "read_readings_csv",
    "read_rosbag",
    "readings_extent",
    "write_map_csv",
    "write_readings_csv",
]


def __getattr__(name: str) -> Any:
    try:
        module = _EXPORTS[name]
    except KeyError:
        msg = f"module 'sonarcarve' has no attribute {name!r}"
        raise AttributeError(msg) from None
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_EXPORTS])
