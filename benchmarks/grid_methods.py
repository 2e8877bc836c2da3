"""The carved grid with other carving methods under it, and without its clearing rules, on both
physics models, against ROS's range sensor layer.

Run from the repository root (on a shared machine, with ``nice``; about 3 minutes)::

    .venv/bin/python benchmarks/grid_methods.py
    .venv/bin/python benchmarks/grid_methods.py --worlds office t-junction --physics amplitude

:class:`~sonarcarve.grids.CarvedGrid` draws each reading's arc over the interval its method
leaves; its default method is combined carving and ATM at β = 20°. This runs the grid with other
methods (carving alone at 30°, the default before, and at 20°; combined at 30°; evidence carving)
and carving alone at 30° with the two clearing rules off (``surface_aware``, ``see_through``), on
the built-in tours (echoes only, seeds 0-2, cells of 0.05 and 0.10 m, the grid origin shifted by a
random fraction of a cell as in ``benchmarks/grids.py``), under the specular physics and the
amplitude physics (``echo_model="amplitude"``), and prints occupied precision, recall and the
phantom share (:mod:`sonarcarve.lab.grid_measures`), means over seeds, with ROS's layer
(defaults) measured on the same readings.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Sequence

from grids import _bounds, _mean, _measure, _scenario, _simulate
from sonarcarve.grids import CarvedGrid, CarvedGridParams, RangeSensorLayer
from sonarcarve.methods import MethodConfig, SonarMethod, make_method
from sonarcarve.sim.simulate import Simulation

Maker = Callable[[float, tuple[float, float, float, float]], CarvedGrid | RangeSensorLayer]


def _method(name: str, beta_deg: float | None = None) -> Callable[[], SonarMethod]:
    config = MethodConfig() if beta_deg is None else MethodConfig(
        max_incidence=math.radians(beta_deg))
    return lambda: make_method(name, config)


def _carved(method: Callable[[], SonarMethod], **params: float | bool) -> Maker:
    return lambda h, b: CarvedGrid(h, b, method(), CarvedGridParams(**params))  # type: ignore[arg-type]


GRIDS: dict[str, Maker] = {
    "carved grid, carve β 30° (the default before)": _carved(_method("carve", 30)),
    "carved grid, carve β 20°": _carved(_method("carve", 20)),
    "carved grid, combined β 20° (default)": _carved(_method("combined", 20)),
    "carved grid, combined β 30°": _carved(_method("combined", 30)),
    "carved grid, evidence": _carved(_method("evidence")),
    "carved grid, carve β 30°, surface_aware off": _carved(_method("carve", 30),
                                                        surface_aware=False),
    "carved grid, carve β 30°, see_through 0": _carved(_method("carve", 30), see_through=0.0),
    "RangeSensorLayer, ROS defaults": lambda h, b: RangeSensorLayer(h, b),
}


def _table(world: str, physics: str, sims: Sequence[Simulation], h: float) -> None:
    print(f"\n{world}, physics {physics}, {h:.2f} m, seeds 0-{len(sims) - 1}, mean over seeds\n")
    print("| grid | precision | recall | phantoms (%) |")
    print("|---|---:|---:|---:|")
    for label, make in GRIDS.items():
        rows = []
        for seed, sim in enumerate(sims):
            grid = make(h, _bounds(sim.world.bounds, h, seed))
            grid.add_many(sim.readings)
            rows.append(_measure(grid, sim))
        m = _mean(rows)
        print(f"| {label} | {m.precision:.3f} | {m.recall:.3f} | {100 * m.phantoms:.3f} |",
              flush=True)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--worlds", nargs="+", default=["office"])
    parser.add_argument("--physics", nargs="+", default=["specular", "amplitude"])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--resolutions", type=float, nargs="+", default=[0.05, 0.10])
    args = parser.parse_args(argv)
    for physics in args.physics:
        for world in args.worlds:
            sims = [_simulate(_scenario(world, seed, physics), False)
                    for seed in range(args.seeds)]
            for h in args.resolutions:
                _table(world, physics, sims, h)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
