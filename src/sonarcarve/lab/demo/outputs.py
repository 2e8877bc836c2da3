"""Writing a demo's outputs: the figures and summaries, rendered in memory, then written atomically;
and each occupancy grid as a ROS map_server map (YAML + trinary PGM).

A failure while rendering never leaves half an output folder: nothing touches the disk until
every figure and summary is ready. :func:`output_captions` says in one line what each file is.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING

from sonarcarve.io.atomic import atomic_path, make_output_dir
from sonarcarve.io.map_server import write_map_server
from sonarcarve.lab.demo.animation import ANIMATION_FILE, ANIMATION_TEXT, animation_gif
from sonarcarve.lab.demo.figures import (
    FIGURE_FILES,
    FIGURE_TEXT,
    plot_door_closeup,
    plot_error_by_range,
    plot_global_maps,
    plot_map_zoom,
)
from sonarcarve.lab.demo.grid_figure import (
    GRID_FIGURE_FILE,
    GRID_FIGURE_TEXT,
    plot_occupancy_grids,
)
from sonarcarve.lab.demo.kept_figure import (
    KEPT_FIGURE_FILE,
    KEPT_FIGURE_TEXT,
    kept_rows,
    plot_kept_and_lost,
)
from sonarcarve.lab.demo.results import DemoResult, GridSummary
from sonarcarve.lab.demo.scenario import DemoError
from sonarcarve.lab.demo.table import summary_json, summary_markdown

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "GRID_FILE_STEMS",
    "SUMMARY_JSON",
    "SUMMARY_MD",
    "check_output_dir",
    "grid_files",
    "output_captions",
    "write_demo_outputs",
]

SUMMARY_MD = "summary.md"
SUMMARY_JSON = "summary.json"
#: Grid kind -> the stem of its map_server files (``STEM.yaml`` beside ``STEM.pgm``).
GRID_FILE_STEMS = {"carved": "carved-grid", "range-sensor-layer": "range-sensor-layer"}
#: Who made each grid, for the captions.
_GRID_MAKERS = {"carved": "the carved grid", "range-sensor-layer": "ROS's RangeSensorLayer"}


def grid_files(grid: GridSummary) -> tuple[str, str]:
    """The names of ``grid``'s map_server files: ``(YAML, PGM)``."""
    stem = GRID_FILE_STEMS.get(grid.kind, grid.kind)
    return f"{stem}.yaml", f"{stem}.pgm"


def output_captions(result: DemoResult, *, animation: bool = False) -> list[tuple[str, str]]:
    """``(file name, what it is)`` for every file :func:`write_demo_outputs` writes, in the
    order to look at them. The CLI prints them one per line after a 30-character file name
    column, so each caption is kept within 49 characters (an 80-column terminal)."""
    out = [(name, FIGURE_TEXT[key]) for key, name in FIGURE_FILES.items()]
    if animation:
        out.append((ANIMATION_FILE, ANIMATION_TEXT))
    if result.grids:
        out.append((GRID_FIGURE_FILE, GRID_FIGURE_TEXT))
    if kept_rows(result):
        out.append((KEPT_FIGURE_FILE, KEPT_FIGURE_TEXT))
    for grid in result.grids:
        yaml_name, pgm_name = grid_files(grid)
        maker = _GRID_MAKERS.get(grid.kind, grid.label)
        out.append((yaml_name, f"{maker} as a ROS map_server map"))
        out.append((pgm_name, "image: black occupied, white free, grey unknown"))
    out.append((SUMMARY_MD, "the tables and how to read them, as text"))
    out.append((SUMMARY_JSON, "the same, as data"))
    return out


def write_demo_outputs(result: DemoResult, out: str | Path, *,
                       animation: bool = False) -> list[Path]:
    """Write the figures, ``summary.md`` and ``summary.json`` into ``out``, with
    ``animation`` the door-approach GIF (:data:`~sonarcarve.lab.demo.animation.ANIMATION_FILE`),
    and each grid of the result as a ROS map_server map (:func:`grid_files`).

    Figures and summaries are rendered in memory first; only then is ``out`` created (with
    its parents) and each file written atomically (a grid's YAML and PGM together), so an error
    leaves no half-written output.

    Returns
    -------
    list of Path
        The files written, figures first, the grid maps last.

    Raises
    ------
    DemoError
        ``out`` exists and is not a directory.
    """
    target = Path(out)
    check_output_dir(target)
    files: dict[str, bytes] = {
        FIGURE_FILES["global_maps"]: _png(plot_global_maps(result)),
        FIGURE_FILES["map_zoom"]: _png(plot_map_zoom(result)),
        FIGURE_FILES["error_by_range"]: _png(plot_error_by_range(result)),
        FIGURE_FILES["door_closeup"]: _png(plot_door_closeup(result.door_source)),
    }
    if result.grids:
        files[GRID_FIGURE_FILE] = _png(plot_occupancy_grids(result))
    if kept_rows(result):
        files[KEPT_FIGURE_FILE] = _png(plot_kept_and_lost(result))
    files |= {
        SUMMARY_MD: summary_markdown(result, animation=animation).encode(),
        SUMMARY_JSON: summary_json(result, animation=animation).encode(),
    }
    if animation:
        files[ANIMATION_FILE] = animation_gif(result.door_source)
    make_output_dir(target)  # atomic_path creates no folders
    written = []
    for name, content in files.items():
        with atomic_path(target / name) as tmp:
            tmp.write_bytes(content)
        written.append(target / name)
    for grid in result.grids:
        written += write_map_server(grid.cells, grid.resolution, grid.origin,
                                    target / grid_files(grid)[0])
    return written


def check_output_dir(out: Path) -> None:
    """Raise :class:`DemoError` if ``out`` (or an ancestor) exists and is not a directory."""
    for path in (out, *out.parents):
        if path.exists():
            if not path.is_dir():
                msg = f"--out {out}: {path} exists and is not a directory"
                raise DemoError(msg)
            return


def _png(fig: Figure) -> bytes:
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    try:
        fig.savefig(buffer, format="png", dpi=120)
    finally:
        plt.close(fig)
    return buffer.getvalue()
