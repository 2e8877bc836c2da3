"""The demo's door-approach animation: a GIF with frames, small enough for the README."""

from __future__ import annotations

import io
from pathlib import Path

from PIL import Image

from sonarcarve.lab.demo import DemoResult, write_demo_outputs
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


def test_demo_outputs_write_it_on_request(doorway: DemoResult, tmp_path: Path) -> None:
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
