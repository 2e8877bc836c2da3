from pathlib import Path

import numpy as np

from sonarcarve.maps import LocalMap, PointSource
from sonarcarve.plotting import new_axes, plot_map, plot_walls, write_carving_explainer


def test_explainer_figure_is_written(tmp_path: Path) -> None:
    path = tmp_path / "explainer.png"
    write_carving_explainer(str(path))  # raises if its geometry stops showing a shrink
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_map_points_are_drawn_once_per_source() -> None:
    points = LocalMap(
        reading_id=np.arange(3), t=np.zeros(3), sensor=np.zeros(3, np.int64),
        xy=np.array([[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]]),
        source=np.array([PointSource.CARVED, PointSource.CARVED, PointSource.ATM], np.int8),
        width=np.zeros(3), max_error=np.zeros(3), range=np.ones(3),
    )
    ax = new_axes()
    artists = plot_map(points, ax)
    assert len(artists) == 2  # carved and atm; no empty centerline series
    offsets = np.concatenate([a.get_offsets() for a in artists])
    np.testing.assert_allclose(np.sort(offsets[:, 0]), [0.0, 1.0, 2.0])
    (walls,) = plot_walls(np.array([[0.0, 0.0, 1.0, 0.0]]), ax)
    assert len(walls.get_segments()) == 1
