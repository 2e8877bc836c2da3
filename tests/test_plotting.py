from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from sonarcarve.errors import ConfigError
from sonarcarve.io.errors import InputError, OutputError
from sonarcarve.maps import LocalMap, PointSource
from sonarcarve.plotting import (
    map_origins,
    new_axes,
    plot_carving_explainer,
    plot_error_bounds,
    plot_grid,
    plot_map,
    plot_map_arcs,
    plot_path,
    plot_sources,
    plot_user_map,
    plot_walls,
    read_grid_image,
    save_figure,
    write_carving_explainer,
)
from sonarcarve.readings import ReadingBatch


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


def _points(xy: list[list[float]], ids: list[int], t: list[float], width: list[float],
            max_error: list[float], source: list[PointSource]) -> LocalMap:
    n = len(ids)
    return LocalMap(
        reading_id=np.array(ids), t=np.array(t), sensor=np.zeros(n, np.int64),
        xy=np.array(xy, dtype=np.float64), source=np.array(source, np.int8),
        width=np.array(width), max_error=np.array(max_error), range=np.full(n, np.nan),
    )


def _readings(n: int = 4) -> ReadingBatch:
    """A sensor moving along +x, looking at a wall at y = 2."""
    return ReadingBatch.from_arrays(t=0.1 * np.arange(n), sensor=np.zeros(n), x=0.1 * np.arange(n),
                                    y=np.zeros(n), theta=np.full(n, np.pi / 2),
                                    range=np.full(n, 2.0))


def test_map_origins_look_up_each_points_reading() -> None:
    readings = _readings()
    points = _points([[0.1, 2.0], [0.3, 2.0]], [1, 3], [0.1, 0.3], [0.2, 0.2], [0.1, 0.1],
                     [PointSource.CARVED, PointSource.CENTERLINE])
    origins = map_origins(points, readings)
    np.testing.assert_allclose(origins.xy, [[0.1, 0.0], [0.3, 0.0]])
    np.testing.assert_allclose(origins.range, [2.0, 2.0])


@pytest.mark.parametrize(("ids", "t", "problem"), [
    ([7], [0.7], "has id 7 but run.csv has 4 rows"),
    ([1], [0.5], r"\(id 1, t 0.5, sensor 0\) does not match row 1 of run.csv \(t 0.1,"),
])
def test_map_origins_refuse_another_logs_readings(ids: list[int], t: list[float],
                                                  problem: str) -> None:
    points = _points([[0.0, 2.0]], ids, t, [0.1], [0.1], [PointSource.CARVED])
    with pytest.raises(InputError, match=problem):
        map_origins(points, _readings(), source="run.csv")


def test_arcs_are_centred_on_the_point_with_the_maps_width() -> None:
    readings = _readings()
    width = 0.3
    points = _points([[0.0, 2.0]], [0], [0.0], [width], [0.1], [PointSource.CARVED])
    (lines,) = plot_map_arcs(points, map_origins(points, readings), new_axes())
    (arc,) = lines.get_segments()
    np.testing.assert_allclose(np.hypot(arc[:, 0], arc[:, 1]), 2.0)  # on the circle r = 2
    bearings = np.arctan2(arc[:, 1], arc[:, 0])
    np.testing.assert_allclose([bearings.min(), bearings.max()],
                               [np.pi / 2 - width / 2, np.pi / 2 + width / 2])


def test_error_bounds_are_circles_of_max_error_and_skip_infinite_ones() -> None:
    points = _points([[0.0, 1.0], [1.0, 1.0]], [0, 1], [0.0, 0.1], [0.1, 0.1], [0.25, np.inf],
                     [PointSource.CARVED, PointSource.ATM])
    (circles,) = plot_error_bounds(points, new_axes())
    np.testing.assert_allclose(circles.get_offsets(), [[0.0, 1.0]])
    np.testing.assert_allclose(circles.get_widths(), [0.5])  # the diameter
    assert plot_error_bounds(points.select(np.array([False, True])), new_axes()) == []


def test_path_draws_one_line_per_sensor() -> None:
    readings = ReadingBatch.from_arrays(t=[0, 0, 1, 1, 2], sensor=[0, 1, 0, 1, 0],
                                        x=[0, 0, 1, 1, 2], y=[0, 1, 0, 1, 0],
                                        theta=np.zeros(5), range=np.ones(5))
    (paths,) = plot_path(readings, new_axes())
    segments = sorted(paths.get_segments(), key=len)
    np.testing.assert_allclose(segments[0], [[0, 1], [1, 1]])
    np.testing.assert_allclose(segments[1], [[0, 0], [1, 0], [2, 0]])


def _write_grid(folder: Path, *, negate: int = 0, yaw: float = 0.0) -> Path:
    image = np.full((4, 6), 254, np.uint8)
    image[0, :] = 0  # the top row (largest y) occupied
    Image.fromarray(image).save(folder / "grid.pgm")
    (folder / "grid.yaml").write_text(
        f"image: grid.pgm\nresolution: 0.5\norigin: [-1.0, 2.0, {yaw}]\nnegate: {negate}\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n", encoding="utf-8")
    return folder / "grid.yaml"


def test_grid_is_read_and_drawn_at_its_origin_and_resolution(tmp_path: Path) -> None:
    grid = read_grid_image(_write_grid(tmp_path))
    assert grid.extent == (-1.0, 2.0, 2.0, 4.0)
    assert grid.image[0, 0] == 0
    assert grid.image[3, 0] == 254
    (image,) = plot_grid(grid, new_axes())
    assert tuple(image.get_extent()) == grid.extent
    assert read_grid_image(_write_grid(tmp_path, negate=1)).image[0, 0] == 255  # undone


@pytest.mark.parametrize(("setup", "problem"), [
    (lambda p: _write_grid(p, yaw=0.5), "rotated map"),
    (lambda p: (p / "g.yaml").write_text("image: g.pgm\n") and p / "g.yaml",
     "missing resolution, origin"),
    (lambda p: (p / "g.yaml").write_text("image: g.pgm\nresolution: 1\norigin: [0, 0, 0]\n")
     and p / "g.yaml", "does not exist"),
    (lambda p: p / "nothing.yaml", "no such file"),
])
def test_bad_grids_are_one_line_errors(tmp_path: Path, setup: Callable[[Path], Path],
                                       problem: str) -> None:
    with pytest.raises(InputError, match=problem) as err:
        read_grid_image(setup(tmp_path))
    assert "\n" not in str(err.value)


def test_user_map_draws_everything_and_titles_the_counts(tmp_path: Path) -> None:
    readings = _readings()
    points = _points([[0.0, 2.0], [0.2, 2.0]], [0, 2], [0.0, 0.2], [0.3, 0.1], [0.2, 0.1],
                     [PointSource.CENTERLINE, PointSource.CARVED])
    ax = new_axes()
    artists = plot_user_map(points, ax, readings=readings, grid=read_grid_image(
        _write_grid(tmp_path)), error_bounds=True, arcs=True)
    assert len(artists) == 6  # grid, path, arcs, circles, two sources
    assert ax.get_title() == "2 points (1 centerline, 1 carved, 0 atm) from 4 readings"
    with pytest.raises(ConfigError, match="arcs needs readings"):
        plot_user_map(points, ax, arcs=True)
    save_figure(ax, tmp_path / "map.png")
    assert (tmp_path / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(OutputError, match=r"expected a \.png"):
        save_figure(new_axes(), tmp_path / "map.jpg")
    assert not (tmp_path / "map.jpg").exists()


def test_drawing_leaves_the_callers_backend_alone(tmp_path: Path) -> None:
    """A notebook's inline backend, or a script's, must survive a plot (review finding 18):
    the library draws on whatever backend the caller has, and only the commands pick Agg."""
    import matplotlib
    import matplotlib.pyplot as plt

    before = matplotlib.get_backend()
    plt.switch_backend("svg")  # not Agg, and needs no display
    try:
        points = _points([[0.0, 2.0]], [0], [0.0], [0.3], [0.2], [PointSource.CARVED])
        plot_map(points)
        plot_walls(np.array([[0.0, 0.0, 1.0, 0.0]]))
        plot_sources(points.xy, points.source)
        plot_user_map(points, readings=_readings(), arcs=True)
        plot_carving_explainer()
        write_carving_explainer(tmp_path / "explainer.png")
        assert matplotlib.get_backend() == "svg"
    finally:
        plt.close("all")
        plt.switch_backend(before)


def test_the_explainer_is_saved_as_every_figure_is(tmp_path: Path) -> None:
    """Through save_figure (review finding 20): the figure closed after, a wrong suffix an
    OutputError and nothing written."""
    import matplotlib.pyplot as plt

    open_before = plt.get_fignums()
    write_carving_explainer(tmp_path / "explainer.svg")
    assert (tmp_path / "explainer.svg").read_bytes().lstrip().startswith(b"<?xml")
    assert plt.get_fignums() == open_before
    with pytest.raises(OutputError, match=r"explainer\.jpg: expected a \.png, \.svg or \.pdf"):
        write_carving_explainer(tmp_path / "explainer.jpg")
    assert not (tmp_path / "explainer.jpg").exists()
    assert plt.get_fignums() == open_before


def test_sources_are_labelled_with_their_counts() -> None:
    xy = np.zeros((1234, 2))
    source = np.full(1234, PointSource.ATM, np.int8)
    (series,) = plot_sources(xy, source)
    assert series.get_label() == "atm (1,234)"
    import matplotlib.pyplot as plt

    plt.close("all")


def test_the_readme_figure_and_its_parts_are_public() -> None:
    import sonarcarve.plotting

    assert {"plot_carving_explainer", "plot_walls", "write_carving_explainer",
            "plot_sources", "new_figure", "check_figure_path"} <= set(sonarcarve.plotting.__all__)


@pytest.mark.parametrize("drawn", [(), ("grid",), ("arcs", "error_bounds"),
                                   ("grid", "arcs", "error_bounds")])
def test_user_map_legend_keys_every_layer_it_draws(tmp_path: Path, drawn: tuple[str, ...]) -> None:
    """The grid's shades, the arcs and the error circles carry no label of their own (they take
    each point's colour), so the legend gets a key for each one drawn, and only for those."""
    points = _points([[0.0, 2.0], [0.2, 2.0]], [0, 2], [0.0, 0.2], [0.3, 0.1], [0.2, 0.1],
                     [PointSource.CENTERLINE, PointSource.CARVED])
    ax = new_axes()
    grid = read_grid_image(_write_grid(tmp_path)) if "grid" in drawn else None
    plot_user_map(points, ax, readings=_readings(), grid=grid, arcs="arcs" in drawn,
                  error_bounds="error_bounds" in drawn)
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    keys = {"grid": ["grid: occupied", "grid: unknown", "grid: free"],
            "arcs": ["final arc of each point"],
            "error_bounds": ["error bound (circle of radius max_error)"]}
    expected = [label for layer in ("grid", "arcs", "error_bounds") if layer in drawn
                for label in keys[layer]]
    assert labels == ["sensor paths", "centerline (1)", "carved (1)", *expected]
