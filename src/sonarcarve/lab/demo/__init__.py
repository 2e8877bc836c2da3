"""The demo: one simulated tour, every method over the same readings, a table and four figures.

:func:`run_demo` simulates the built-in tour of a world with a Scout2-like sonar ring, runs
centerline, ATM, arc carving and the combined method over the same readings, and measures each
against the ground truth the simulator knows. :func:`write_demo_outputs` turns the
:class:`DemoResult` into ``summary.md``, ``summary.json`` and four PNG figures. Nothing here
prints; the CLI (``sonarcarve demo``) does.

The modules, each importing only those above it:

- :mod:`~sonarcarve.lab.demo.scenario`: what the demo simulates (methods, world, settings);
- :mod:`~sonarcarve.lab.demo.doors`: the doors the tour approaches and the local maps then;
- :mod:`~sonarcarve.lab.demo.results`: the records a run produces;
- :mod:`~sonarcarve.lab.demo.runs`: :func:`run_demo`, running the methods and measuring;
- :mod:`~sonarcarve.lab.demo.figures`: the four figures;
- :mod:`~sonarcarve.lab.demo.table`: the printed table, ``summary.md`` and ``summary.json``;
- :mod:`~sonarcarve.lab.demo.outputs`: writing all of them at once, atomically.
"""

from sonarcarve.lab.demo.doors import DoorApproach, LocalView
from sonarcarve.lab.demo.figures import FIGURE_FILES, FIGURE_TEXT
from sonarcarve.lab.demo.outputs import check_output_dir, write_demo_outputs
from sonarcarve.lab.demo.results import DemoResult, MethodSummary
from sonarcarve.lab.demo.runs import run_demo
from sonarcarve.lab.demo.scenario import (
    APPROACH_DISTANCE,
    DEMO_METHODS,
    METHOD_COLORS,
    METHOD_LABELS,
    SAMPLE_EVERY,
    DemoError,
    demo_config,
    load_demo_world,
)
from sonarcarve.lab.demo.table import (
    TABLE_COLUMNS,
    caption,
    summary_json,
    summary_markdown,
    table_rows,
)

__all__ = [
    "APPROACH_DISTANCE",
    "DEMO_METHODS",
    "FIGURE_FILES",
    "FIGURE_TEXT",
    "METHOD_COLORS",
    "METHOD_LABELS",
    "SAMPLE_EVERY",
    "TABLE_COLUMNS",
    "DemoError",
    "DemoResult",
    "DoorApproach",
    "LocalView",
    "MethodSummary",
    "caption",
    "check_output_dir",
    "demo_config",
    "load_demo_world",
    "run_demo",
    "summary_json",
    "summary_markdown",
    "table_rows",
    "write_demo_outputs",
]
