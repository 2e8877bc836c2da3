"""File formats at the edges of the library: readings and maps as CSV, ROS bags in and out, and
dataset adapters."""

from sonarcarve.io.bag_out import BagOutReport, BagWriter, write_map_bag
from sonarcarve.io.errors import InputError, OutputError
from sonarcarve.io.map_csv import (
    MAP_COLUMNS,
    MapCsvSink,
    map_csv_sink,
    read_map_csv,
    write_map_csv,
)
from sonarcarve.io.readings_csv import READINGS_COLUMNS, read_readings_csv, write_readings_csv
from sonarcarve.io.roboND import RoboNDLog, RoboNDReport, bundled_robond_dir, read_robond
from sonarcarve.io.rosbag import (
    NoEchoReadings,
    RosbagLog,
    RosbagReport,
    SensorMounts,
    SensorSource,
    read_rosbag,
)

__all__ = [
    "MAP_COLUMNS",
    "READINGS_COLUMNS",
    "BagOutReport",
    "BagWriter",
    "InputError",
    "MapCsvSink",
    "NoEchoReadings",
    "OutputError",
    "RoboNDLog",
    "RoboNDReport",
    "RosbagLog",
    "RosbagReport",
    "SensorMounts",
    "SensorSource",
    "bundled_robond_dir",
    "map_csv_sink",
    "read_map_csv",
    "read_readings_csv",
    "read_robond",
    "read_rosbag",
    "write_map_bag",
    "write_map_csv",
    "write_readings_csv",
]
