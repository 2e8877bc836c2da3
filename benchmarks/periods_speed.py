"""The carved grid's firing-period bookkeeping alone: CPU per reading, this tree against a commit.

Run from the repository root (on a shared machine, with ``nice``)::

    nice .venv/bin/python benchmarks/periods_speed.py --against bf78277

What the grid pays for the ``fresh_periods`` rule when its map is read often
(``benchmarks/grid_reads.py`` measures the whole grid, where this part is a few µs among ~100 and
drowns in the machine's noise): the office log (seed 0) is fed to
:class:`~sonarcarve.grids.carved.periods.FiringPeriods` ``--every`` readings at a time, and after
each batch the periods of the sensors of the last ``--asked`` readings are asked for, as the grid
asks for its live newest echoes' sensors on a read. The module at ``--against`` is loaded from git
beside this tree's, both are warmed up, then timed in turns (CPU time, ``--rounds`` rounds); every
period both give is checked to be the same.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType

import numpy as np
import numpy.typing as npt

from sonarcarve.lab.scenarios import Scenario, run_simulation

MODULE = "src/sonarcarve/grids/carved/periods.py"


def _load(path: Path, name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def _module_at(commit: str, folder: Path) -> ModuleType:
    text = subprocess.run(["git", "show", f"{commit}:{MODULE}"], check=True, text=True,
                          capture_output=True).stdout
    path = folder / f"periods_{commit}.py"
    path.write_text(text)
    return _load(path, f"periods_{commit}")


def _feed(module: ModuleType, sensor: npt.NDArray[np.int64], t: npt.NDArray[np.float64],
          every: int, asked: int) -> tuple[float, list[float]]:
    """CPU µs per reading, and every period asked for."""
    periods = module.FiringPeriods()
    seen: list[float] = []
    start = time.process_time()
    for i in range(0, len(t), every):
        periods.note(sensor[i:i + every], t[i:i + every])
        seen.extend(periods.periods(sensor[max(0, i + every - asked):i + every]).tolist())
    return (time.process_time() - start) / len(t) * 1e6, seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", default="HEAD", help="the commit to compare with")
    parser.add_argument("--every", type=int, default=5,
                        help="readings per batch (a read after each)")
    parser.add_argument("--asked", type=int, default=13,
                        help="periods asked per read: the sensors of the last N readings")
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    readings = run_simulation(Scenario("office", 0)).readings
    sensor = np.asarray(readings.sensor, dtype=np.int64)
    t = np.asarray(readings.t, dtype=np.float64)
    with tempfile.TemporaryDirectory() as folder:
        modules = {args.against: _module_at(args.against, Path(folder)),
                   "this tree": _load(Path(MODULE), "periods_this_tree")}
        answers = {name: _feed(m, sensor, t, args.every, args.asked)[1]
                   for name, m in modules.items()}
        first, second = answers.values()
        same = np.array_equal(np.asarray(first), np.asarray(second))
        print(f"office seed 0, {len(t):,} readings, {args.every} a batch, {args.asked} periods "
              f"asked a read; CPU µs a reading; periods the same: {same}")
        print("| round | " + " | ".join(modules) + " | ratio |")
        print("|---:|" + "---:|" * (len(modules) + 1))
        for round_ in range(args.rounds):
            cost = [_feed(m, sensor, t, args.every, args.asked)[0] for m in modules.values()]
            print(f"| {round_} | " + " | ".join(f"{c:.2f}" for c in cost)
                  + f" | {cost[1] / cost[0]:.2f} |")


if __name__ == "__main__":
    main()
