"""The held-out car park of ``benchmarks/parking.py``: its layout, its walls file and its path.

Run from the repository root to (re)write ``benchmarks/worlds/car-park.json`` (walls and tour)
and ``benchmarks/worlds/car-park.path.json`` (the same waypoints alone, for
``sonarcarve simulate --path``)::

    .venv/bin/python benchmarks/car_park.py

Not a built-in world: nothing in sonarcarve was developed on it. Metres, x east, y north::

    y 24 ┌──────────────────┬───────┐   cross lane (x 43-52), the path turns north into it
         │ (wall)           │ ▫   ▫ │   ▫ pillars (0.5 m squares)
    12.3 ├──────────────────┘       │   back wall of the north row
         │ ▮▮▮▮▮▮ ▮▮▮▮▮▮▮▮▮         │   north row: 15 cars in 16 perpendicular bays (2.5 m
     7.3 │ ----------------         │   pitch), bay 6 empty: a 3.2 m gap between car sides
     4.9 │ ══════ path ═════════╗   │   the lane (3.0 to 7.3): the car drives its middle
     3.0 │ ▬ ▬   ▬ ▬   ▬ ▬      ▫   │   south row: 6 parallel-parked cars: gaps 0.8, 6.0
     1.0 │ ─────── kerb ──────      │   (a slot), 1.0, 4.5 (too short), 0.9 m
       0 └──────────────────────────┘   footway behind the kerb, boundary wall at y 0

Every parked car is a closed 4.5 x 1.8 m rectangle of four walls. The simulator's walls have
no height, so the kerb is a full-height wall (a real 15 cm kerb is heard only near, or not
at all, by a bumper sensor 0.5 m up): it stands 1.8 m behind the slot's lane-side line, as a
kerb or a low wall at the back of a parallel slot would.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import NamedTuple

import numpy as np

from sonarcarve.sim.world import World, write_world_json

CAR_LENGTH, CAR_WIDTH = 4.5, 1.8
#: The south row: parallel-parked cars' x spans (rear, front), between the kerb and the lane.
SOUTH_CARS = ((1.0, 5.5), (6.3, 10.8), (16.8, 21.3), (22.3, 26.8), (31.3, 35.8), (36.7, 41.2))
KERB_Y = 1.0
SOUTH_CAR_Y = (1.2, 3.0)  # the south cars' flanks; y 3.0 faces the lane
#: The north row: perpendicular bays of BAY_PITCH from FIRST_BAY_X, cars centred in them.
BAY_PITCH, FIRST_BAY_X, BAYS, EMPTY_BAY = 2.5, 2.0, 16, 6
NORTH_CAR_Y = (7.3, 11.8)  # bumper facing the lane at y 7.3
NORTH_BACK_Y = 12.3
#: Lower-left corners of the square pillars, and their side.
PILLARS = ((42.0, 2.0), (43.6, 15.0), (50.6, 18.0))
PILLAR_SIDE = 0.5
WIDTH, HEIGHT, CROSS_LANE_X = 52.0, 24.0, 43.0
#: The path: east along the lane's middle past both rows, then one left turn into the cross
#: lane. The car's centre; its body (4.5 x 1.8) clears every wall along it.
PATH = ((3.0, 4.9), (47.5, 4.9), (47.5, 21.0))
#: Parking speed, m/s (3.6 km/h, the slow end of a slot search), and the radius of the turn.
SPEED, CORNER_RADIUS = 1.0, 4.0

WORLD_FILE = Path(__file__).resolve().parent / "worlds" / "car-park.json"
PATH_FILE = WORLD_FILE.with_suffix(".path.json")


class Row(NamedTuple):
    """A parking row along the lane (x): its cars' x spans and where their lane side is.

    ``lane_side_y`` is the line the parked cars present to the lane (flank or bumper);
    ``band`` the y range (metres) whose map points count as the row's (the cars' first 1.5 m
    from the lane side, plus 0.3 m into the lane for range errors: it stops short of the kerb
    and the back wall).
    """

    name: str
    kind: str  # "parallel" or "perpendicular"
    lane_side_y: float
    band: tuple[float, float]
    cars: tuple[tuple[float, float], ...]


class Gap(NamedTuple):
    """The free stretch between two neighbouring parked cars: truth from the layout."""

    row: Row
    left: float   # x of the left car's end (its lane-side corner)
    right: float  # x of the right car's start

    @property
    def length(self) -> float:
        return self.right - self.left


def north_cars() -> tuple[tuple[float, float], ...]:
    """x spans of the cars in the perpendicular bays, each centred in its bay."""
    margin = (BAY_PITCH - CAR_WIDTH) / 2
    return tuple((FIRST_BAY_X + i * BAY_PITCH + margin, FIRST_BAY_X + i * BAY_PITCH + margin
                  + CAR_WIDTH) for i in range(BAYS) if i != EMPTY_BAY)


def rows() -> tuple[Row, Row]:
    """The south (parallel) and north (perpendicular) rows."""
    south = Row("south (parallel)", "parallel", SOUTH_CAR_Y[1],
                (SOUTH_CAR_Y[1] - 1.5, SOUTH_CAR_Y[1] + 0.3), SOUTH_CARS)
    north = Row("north (perpendicular)", "perpendicular", NORTH_CAR_Y[0],
                (NORTH_CAR_Y[0] - 0.3, NORTH_CAR_Y[0] + 1.5), north_cars())
    return south, north


def gaps(row: Row) -> list[Gap]:
    """Every gap between neighbouring cars of ``row``, west to east."""
    return [Gap(row, a[1], b[0]) for a, b in zip(row.cars, row.cars[1:], strict=False)]


def _box(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    """A closed rectangle as four walls."""
    return [[x0, y0, x1, y0], [x1, y0, x1, y1], [x1, y1, x0, y1], [x0, y1, x0, y0]]


def segments() -> np.ndarray:
    """Every wall: boundary, kerb, the north row's back wall, cars and pillars, shape (n, 4)."""
    walls = [
        [0.0, 0.0, WIDTH, 0.0], [WIDTH, 0.0, WIDTH, HEIGHT], [WIDTH, HEIGHT, CROSS_LANE_X, HEIGHT],
        [CROSS_LANE_X, HEIGHT, CROSS_LANE_X, NORTH_BACK_Y],
        [CROSS_LANE_X, NORTH_BACK_Y, 0.0, NORTH_BACK_Y], [0.0, NORTH_BACK_Y, 0.0, 0.0],
        [0.5, KERB_Y, 42.0, KERB_Y],
    ]
    for x0, x1 in SOUTH_CARS:
        walls += _box(x0, SOUTH_CAR_Y[0], x1, SOUTH_CAR_Y[1])
    for x0, x1 in north_cars():
        walls += _box(x0, NORTH_CAR_Y[0], x1, NORTH_CAR_Y[1])
    for x, y in PILLARS:
        walls += _box(x, y, x + PILLAR_SIDE, y + PILLAR_SIDE)
    return np.round(np.array(walls, dtype=np.float64), 9)


def world() -> World:
    """The car park as a :class:`~sonarcarve.sim.world.World`, the path as its tour."""
    return World(segments(), "car-park", np.array(PATH, dtype=np.float64),
                 description="Held-out car park (benchmarks/car_park.py): a lane between a row of "
                 "parallel-parked cars (gaps 0.8, 6.0, 1.0, 4.5, 0.9 m) and a row of "
                 "perpendicular bays (one empty: 3.2 m between car sides), pillars, a kerb, "
                 "one left turn into a cross lane.")


def main() -> int:
    WORLD_FILE.parent.mkdir(exist_ok=True)
    write_world_json(world(), WORLD_FILE)
    PATH_FILE.write_text(json.dumps([list(p) for p in PATH]) + "\n", encoding="utf-8")
    print(f"wrote {WORLD_FILE} and {PATH_FILE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
