"""Worlds by name: :func:`load_world` and :func:`builtin_worlds`, and the world API in one place.

:func:`load_world` accepts

- a built-in name (:func:`builtin_worlds` lists them; JSON files in ``sonarcarve/sim/worlds/``),
- ``random:SEED`` or ``random:SEED:WIDTHxHEIGHT`` (:func:`sonarcarve.sim.generate.random_world`),
- a ``.json`` world file or a ``.yaml``/``.yml`` ROS map_server map
  (:mod:`~sonarcarve.sim.world_files` describes both formats).

This module also re-exports the world itself (:class:`World`, :class:`WorldError`,
:func:`check_seed`, from :mod:`~sonarcarve.sim.walls`) and the file readers and writer, so that
``from sonarcarve.sim.world import ...`` gives every world name. Imports flow one way:
``walls`` <- ``world_files`` <- ``generate`` <- ``world``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from importlib import resources
from pathlib import Path

from sonarcarve.sim.generate import random_world
from sonarcarve.sim.walls import World, WorldError, check_seed
from sonarcarve.sim.world_files import (
    read_ros_map,
    read_world_json,
    segments_from_occupancy,
    write_world_json,
)

__all__ = [
    "World",
    "WorldError",
    "builtin_worlds",
    "check_seed",
    "load_world",
    "read_ros_map",
    "read_world_json",
    "segments_from_occupancy",
    "write_world_json",
]

#: How to spell a random world (see :func:`sonarcarve.sim.generate.random_world`).
_RANDOM_SPEC_HELP = "random:SEED or random:SEED:WIDTHxHEIGHT (metres)"


def load_world(spec: str | Path) -> World:
    """Load a world from a built-in name, ``random:SEED[:WxH]``, a ``.json`` or a ROS ``.yaml``.

    Parameters
    ----------
    spec : str or Path
        ``"office"``, ``"random:7"``, ``"random:7:40x30"``, ``"walls.json"``, ``"map.yaml"``.

    Raises
    ------
    WorldError
        With one line naming the spec or file and what is wrong.

    Examples
    --------
    >>> load_world("t-junction").name
    't-junction'
    >>> load_world("random:3:20x15").size
    (20.0, 15.0)
    """
    text = str(spec)
    if not isinstance(spec, Path) and text in _builtin_paths():
        return _load_builtin(text)
    scheme, colon, rest = text.partition(":")
    if not isinstance(spec, Path) and colon and scheme in _SCHEMES:
        return _SCHEMES[scheme](rest, text)
    loader = _FILE_LOADERS.get(Path(text).suffix.lower())
    if loader is None:
        known = ", ".join([*_builtin_paths(), _RANDOM_SPEC_HELP])
        msg = (f"unknown world {text!r}: use a built-in world ({known}), a .json file or a ROS "
               f"map .yaml file")
        raise WorldError(msg)
    return loader(Path(text))


def builtin_worlds() -> dict[str, str]:
    """Built-in world names and their one-line descriptions (``random:SEED`` last).

    Examples
    --------
    >>> sorted(builtin_worlds())
    ['doorway', 'narrow-hallway', 'office', 'random:SEED', 't-junction']
    """
    described = {name: _read_builtin(name).description for name in _builtin_paths()}
    described["random:SEED"] = (
        "seeded floor of corridors and rooms with doors; random:SEED:WxH for another size")
    return {name: str(text) for name, text in described.items()}


@functools.cache
def _builtin_paths() -> dict[str, Path]:
    folder = resources.files("sonarcarve.sim").joinpath("worlds")
    paths = {Path(str(entry)).stem: Path(str(entry)) for entry in folder.iterdir()
             if str(entry).endswith(".json")}
    return dict(sorted(paths.items()))


@functools.cache
def _read_builtin(name: str) -> World:
    return read_world_json(_builtin_paths()[name])


def _load_builtin(name: str) -> World:
    world = _read_builtin(name)
    # Worlds are frozen, but their arrays are not: hand out copies of the cached one.
    return World(world.segments.copy(), name,
                 None if world.tour is None else world.tour.copy(),
                 world.openings.copy(), world.description)


def _load_random(rest: str, spec: str) -> World:
    seed_text, _, size_text = rest.partition(":")
    try:
        seed = int(seed_text)
    except ValueError:
        msg = f"{spec}: seed must be an integer ({_RANDOM_SPEC_HELP})"
        raise WorldError(msg) from None
    check_seed(seed, f"{spec}: seed")
    if not size_text:
        return random_world(seed)
    width_text, x, height_text = size_text.lower().partition("x")
    try:
        width, height = float(width_text), float(height_text)
    except ValueError:
        msg = f"{spec}: size must be WIDTHxHEIGHT in metres, e.g. 60x40"
        raise WorldError(msg) from None
    if not x:
        msg = f"{spec}: size must be WIDTHxHEIGHT in metres, e.g. 60x40"
        raise WorldError(msg)
    return random_world(seed, width=width, height=height)


_SCHEMES: dict[str, Callable[[str, str], World]] = {"random": _load_random}


_FILE_LOADERS: dict[str, Callable[[Path], World]] = {
    ".json": read_world_json,
    ".yaml": read_ros_map,
    ".yml": read_ros_map,
}
