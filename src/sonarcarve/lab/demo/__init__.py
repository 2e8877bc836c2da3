"""The demo: one simulated tour, every method and two occupancy grids over the same readings.

:func:`run_demo` simulates the built-in tour of a world with a Scout2-like sonar ring, runs
centerline, ATM, arc carving, the combined method and evidence carving (beyond the paper) over
the same readings, builds the carved grid and ROS's range sensor layer from them, and measures
each against the ground truth the simulator knows. :func:`write_demo_outputs` turns the
:class:`DemoResult` into ``summary.md``, ``summary.json``, six PNG figures and each grid as a
ROS map_server map. Nothing here prints; the CLI (``sonarcarve demo``) does.

The modules, each importing only those above it:

- :mod:`~sonarcarve.lab.demo.scenario`: what the demo simulates (methods, world, settings);
- :mod:`~sonarcarve.lab.demo.doors`: the doors the tour approaches and the local maps then;
- :mod:`~sonarcarve.lab.demo.results`: the records a run produces;
- :mod:`~sonarcarve.lab.demo.costmaps`: the occupancy grids, built and measured;
- :mod:`~sonarcarve.lab.demo.runs`: :func:`run_demo`, running the methods and measuring;
- :mod:`~sonarcarve.lab.demo.figures`: figures 1-4 (the paper's methods);
- :mod:`~sonarcarve.lab.demo.grid_figure`: figure 5 (the grids) and which grid is better;
- :mod:`~sonarcarve.lab.demo.kept_figure`: figure 6 (which echoes paper carving and evidence
  carving kept, by the truth);
- :mod:`~sonarcarve.lab.demo.table`: the printed tables, ``summary.md`` and ``summary.json``;
- :mod:`~sonarcarve.lab.demo.outputs`: writing all of them at once, atomically.
"""

from sonarcarve.lab.demo.costmaps import GRID_KINDS, grid_bounds, run_grids
from sonarcarve.lab.demo.doors import DoorApproach, LocalView
from sonarcarve.lab.demo.figures import FIGURE_FILES, FIGURE_TEXT
from sonarcarve.lab.demo.grid_figure import GRID_FIGURE_FILE, free_verdict, grid_verdict
from sonarcarve.lab.demo.kept_figure import KEPT_FIGURE_FILE
from sonarcarve.lab.demo.outputs import (
    check_output_dir,
    grid_files,
    output_captions,
    write_demo_outputs,
)
from sonarcarve.lab.demo.results import DemoResult, FilterSummary, GridSummary, MethodSummary
from sonarcarve.lab.demo.runs import run_demo
from sonarcarve.lab.demo.scenario import (
    APPROACH_DISTANCE,
    DEMO_METHODS,
    GRID_RESOLUTION,
    METHOD_COLORS,
    METHOD_LABELS,
    PAPER_METHODS,
    SAMPLE_EVERY,
    DemoError,
    demo_config,
    load_demo_world,
)
from sonarcarve.lab.demo.table import (
    GRID_COLUMNS,
    TABLE_COLUMNS,
    caption,
    door_note,
    grid_caption,
    grid_table_rows,
    method_verdict,
    summary_json,
    summary_markdown,
    table_rows,
)

__all__ = [
    "APPROACH_DISTANCE",
    "DEMO_METHODS",
    "FIGURE_FILES",
    "FIGURE_TEXT",
    "GRID_COLUMNS",
    "GRID_FIGURE_FILE",
    "GRID_KINDS",
    "GRID_RESOLUTION",
    "KEPT_FIGURE_FILE",
    "METHOD_COLORS",
    "METHOD_LABELS",
    "PAPER_METHODS",
    "SAMPLE_EVERY",
    "TABLE_COLUMNS",
    "DemoError",
    "DemoResult",
    "DoorApproach",
    "FilterSummary",
    "GridSummary",
    "LocalView",
    "MethodSummary",
    "caption",
    "check_output_dir",
    "demo_config",
    "door_note",
    "free_verdict",
    "grid_bounds",
    "grid_caption",
    "grid_files",
    "grid_table_rows",
    "grid_verdict",
    "load_demo_world",
    "method_verdict",
    "output_captions",
    "run_demo",
    "run_grids",
    "summary_json",
    "summary_markdown",
    "table_rows",
    "write_demo_outputs",
]
