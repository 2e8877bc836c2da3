"""Writing a demo's outputs: the figures and summaries, rendered in memory, then written atomically.

A failure while rendering never leaves half an output folder: nothing touches the disk until
every file is ready.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING

from sonarcarve.io.atomic import atomic_path, make_output_dir
from sonarcarve.lab.demo.animation import ANIMATION_FILE, animation_gif
from sonarcarve.lab.demo.figures import (
    FIGURE_FILES,
    plot_door_closeup,
    plot_error_by_range,
    plot_global_maps,
    plot_map_zoom,
)
from sonarcarve.lab.demo.results import DemoResult
from sonarcarve.lab.demo.scenario import DemoError
from sonarcarve.lab.demo.table import summary_json, summary_markdown

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["SUMMARY_JSON", "SUMMARY_MD", "check_output_dir", "write_demo_outputs"]

SUMMARY_MD = "summary.md"
SUMMARY_JSON = "summary.json"


def write_demo_outputs(result: DemoResult, out: str | Path, *,
                       animation: bool = False) -> list[Path]:
    """Write the figures, ``summary.md`` and ``summary.json`` into ``out``, and with
    ``animation`` the door-approach GIF (:data:`~sonarcarve.lab.demo.animation.ANIMATION_FILE`).

    Everything is rendered in memory first; only then is ``out`` created (with its parents)
    and each file written atomically, so an error leaves no half-written output.

    Returns
    -------
    list of Path
        The files written, figures first.

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
        FIGURE_FILES["door_closeup"]: _png(plot_door_closeup(result)),
        SUMMARY_MD: summary_markdown(result).encode(),
        SUMMARY_JSON: summary_json(result).encode(),
    }
    if animation:
        files[ANIMATION_FILE] = animation_gif(result)
    make_output_dir(target)  # atomic_path creates no folders
    written = []
    for name, content in files.items():
        with atomic_path(target / name) as tmp:
            tmp.write_bytes(content)
        written.append(target / name)
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
