"""The demo's door-approach animation: a GIF with frames, small enough for the README."""

from __future__ import annotations

import io
from functools import partial
from pathlib import Path

import pytest
from PIL import Image

from sonarcarve.lab.demo import DemoResult, outputs, write_demo_outputs
from sonarcarve.lab.demo.animation import ANIMATION_FILE, DoorGauge, animation_gif, live_map
from sonarcarve.lab.demo.scenario import CLOSEUP_METHODS
from sonarcarve.methods import make_method


def test_the_gif_has_frames_and_is_small(doorway: DemoResult) -> None:
    data = animation_gif(doorway, frames=6)
    assert len(data) < 2_000_000
    with Image.open(io.BytesIO(data)) as gif:
        assert gif.format == "GIF"
        assert gif.n_frames == 7  # the start and six steps
        assert gif.info.get("loop") == 0  # loops forever, as a README's GIF should
        first = gif.convert("RGB").tobytes()
        gif.seek(gif.n_frames - 1)
        assert gif.convert("RGB").tobytes() != first  # the arcs moved


def test_demo_outputs_write_it_on_request(doorway: DemoResult, tmp_path: Path,
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    # Whether the GIF is written is the point here: two frames of it, and no figures drawn
    # (40 frames and the figures twice cost 11 s; the test above, tests/lab/demo/test_figures.py
    # and the demo CLI's test check them).
    monkeypatch.setattr(outputs, "animation_gif", partial(animation_gif, frames=2))
    for figure in ("plot_global_maps", "plot_map_zoom", "plot_error_by_range",
                   "plot_door_closeup", "plot_occupancy_grids"):
        monkeypatch.setattr(outputs, figure, lambda result: None)
    monkeypatch.setattr(outputs, "_png", lambda figure: b"")
    written = write_demo_outputs(doorway, tmp_path / "with", animation=True)
    assert tmp_path / "with" / ANIMATION_FILE in written
    assert ANIMATION_FILE not in [p.name for p in write_demo_outputs(doorway, tmp_path / "w")]


def test_the_last_frame_measures_what_fig4_measured(doorway: DemoResult) -> None:
    """The titles are measured on the live maps, so at the door's moment they must give the free
    widths fig. 4 measured on the recorded local maps (doorway: centerline closes the door)."""
    door = doorway.closeup
    assert door is not None
    measure = DoorGauge(doorway)
    readings = doorway.simulation.readings[:door.view.readings]
    for name in CLOSEUP_METHODS:
        method = make_method(name, doorway.config)
        method.add_many(readings, first_id=0)
        points, _, _ = live_map(method)
        verdict = "passable" if door.passable[name] else "BLOCKED"
        assert measure.title(name, points) == (
            f"{name}: {door.free_width[name]:.2f} of {measure.gap:.2f} m free, {verdict}")
    assert not door.passable["centerline"]
    assert door.passable["carve"]
