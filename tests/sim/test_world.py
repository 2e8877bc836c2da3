"""Worlds by name: every loader of ``load_world``, the built-in worlds, random specs."""

from __future__ import annotations

import ast
import itertools
from pathlib import Path

import numpy as np
import pytest

import sonarcarve.sim.generate
import sonarcarve.sim.walls
import sonarcarve.sim.world_files
from sonarcarve.sim.world import WorldError, builtin_worlds, load_world


def _densify(polyline: np.ndarray, step: float = 0.02) -> np.ndarray:
    pieces = []
    for a, b in itertools.pairwise(polyline):
        n = max(2, int(np.hypot(*(b - a)) / step) + 2)
        pieces.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
    return np.vstack(pieces)


def test_missing_files_and_unknown_names(tmp_path: Path) -> None:
    for spec in (tmp_path / "nope.json", tmp_path / "nope.yaml"):
        with pytest.raises(WorldError, match="no such file") as info:
            load_world(spec)
        assert str(spec) in str(info.value)
    with pytest.raises(WorldError) as info:
        load_world("atlantis")
    message = str(info.value)
    assert "'atlantis'" in message
    for name in builtin_worlds():
        assert name.split(":")[0] in message
    for spec, expected in (("random:x", "seed must be an integer"),
                           ("random:1:40by30", "WIDTHxHEIGHT"), ("random:1:40xz", "WIDTHxHEIGHT"),
                           ("random:1:5x5", "size")):
        with pytest.raises(WorldError, match=expected):
            load_world(spec)


# --- built-in worlds ----------------------------------------------------------------------------

def test_builtin_worlds_listed_and_loadable() -> None:
    names = builtin_worlds()
    assert set(names) == {"t-junction", "narrow-hallway", "doorway", "office", "random:SEED"}
    assert all(text for text in names.values())
    for name in names:
        world = load_world(name.replace("SEED", "11"))
        assert len(world) > 0
        assert world.tour is not None
        assert world.openings.shape[0] >= 1


@pytest.mark.parametrize("name", ["t-junction", "narrow-hallway", "doorway", "office"])
def test_builtin_tours_keep_clear_of_walls(name: str) -> None:
    world = load_world(name)
    assert world.tour is not None
    assert world.distance_to_walls(_densify(world.tour)).min() >= 0.45 - 1e-9


@pytest.mark.parametrize("name", ["t-junction", "narrow-hallway", "doorway", "office"])
def test_builtin_openings_are_gaps_between_walls(name: str) -> None:
    world = load_world(name)
    ends = world.openings.reshape(-1, 2)
    # Both ends touch a wall; the middle is free, half the gap's width from the nearest wall.
    np.testing.assert_allclose(world.distance_to_walls(ends), 0.0, atol=1e-9)
    middles = world.openings.mean(axis=1)
    half_widths = np.linalg.norm(world.openings[:, 1] - world.openings[:, 0], axis=1) / 2
    np.testing.assert_allclose(world.distance_to_walls(middles), half_widths, atol=1e-9)


def test_builtin_copies_are_independent() -> None:
    first = load_world("doorway")
    first.segments[0, 0] = 1e6
    assert load_world("doorway").segments[0, 0] != 1e6


def test_paper_scenes_shapes() -> None:
    doorway = load_world("doorway")
    width = np.linalg.norm(doorway.openings[0, 1] - doorway.openings[0, 0])
    assert 0.8 <= width <= 0.9
    t = load_world("t-junction")
    # Corridors about 2 m wide: rays across the stem from its centre line.
    d, _ = t.cast_rays([0.0, 5.0], [0.0, np.pi])
    assert d.sum() == pytest.approx(2.0)


@pytest.mark.parametrize("spec", ["random:-1", "random:-7:40x30"])
def test_negative_random_seed_is_a_one_line_world_error(spec: str) -> None:
    with pytest.raises(WorldError) as info:
        load_world(spec)
    seed = spec.split(":")[1]
    assert str(info.value) == f"{spec}: seed must be an integer >= 0, got {seed}"


def _imported(module: object) -> set[str]:
    """The ``sonarcarve`` modules a module's source imports from (deferred imports included)."""
    tree = ast.parse(Path(str(getattr(module, "__file__", ""))).read_text())
    return {node.module for node in ast.walk(tree)
            if isinstance(node, ast.ImportFrom) and node.module
            and node.module.startswith("sonarcarve")}


def test_world_modules_import_one_way() -> None:
    # walls <- world_files <- generate <- world: load_world may use the generators, which build
    # on the world itself, without an import cycle.
    assert not _imported(sonarcarve.sim.walls) & {
        "sonarcarve.sim.world_files", "sonarcarve.sim.generate", "sonarcarve.sim.world"}
    assert not _imported(sonarcarve.sim.world_files) & {
        "sonarcarve.sim.generate", "sonarcarve.sim.world"}
    assert "sonarcarve.sim.world" not in _imported(sonarcarve.sim.generate)
