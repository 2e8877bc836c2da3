"""Which direct echoes evidence carving loses when it is fed silent firings, and why.

Run from the repository root::

    nice .venv/bin/python benchmarks/silent_looks.py \
        --runs office:0:amplitude t-junction:0:amplitude office:0:specular

Each run (``WORLD:SEED:PHYSICS``) is simulated twice with the Scout2 ring, echoes only and with
a no-echo reading for every firing that heard nothing (the same echoes); evidence carving maps
both. For the direct echoes kept without the silent firings and lost with them, and for a
sample of those kept in both, it prints the *silent looks* at each echo's true reflection
point R: the no-echo readings of the next 30 s whose beam (nominal width, up to their maximum
range less 5 cm) holds R. Of those looks: the true incidence on the wall at R (the simulator's
wall normal), and the ``P_detect`` the evidence model gives them
(:func:`~sonarcarve.geometry.evidence.model.detect_probability`), which takes the surface's
normal to point from R at the older echo's sensor (the implied normal). A look with a high model
``P_detect`` at a glancing true incidence is a miss the model misreads as a look that should have
heard. A column gives how far the implied normal lies from the wall's at R. A point in a beam is
tested at R itself, not at the arc's bins, so the numbers describe the looks, not the kernel's
evidence to the digit.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence

import numpy as np

from sonarcarve.geometry.evidence.model import detect_probability
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import make_method
from sonarcarve.methods.evidence import SensorModel
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.sim.simulate import Simulation, simulate
from sonarcarve.sim.sonar import NO_ECHO, EchoKind

#: How long after an echo a silent firing counts as a look at it, seconds.
WINDOW = 30.0
SAMPLE = 2000


def _kept(readings: ReadingBatch) -> np.ndarray:
    kept = np.zeros(len(readings), dtype=bool)
    kept[process_readings(readings, make_method("evidence")).global_map.reading_id] = True
    return kept


def _wall_normal(segments: np.ndarray, point: np.ndarray) -> np.ndarray:
    """The unit normal of the wall segment nearest ``point``."""
    a, b = segments[:, :2], segments[:, 2:]
    d = b - a
    t = np.clip(((point - a) * d).sum(1) / (d * d).sum(1), 0.0, 1.0)
    k = int(np.argmin(np.hypot(*(a + t[:, None] * d - point).T)))
    n = np.array([-d[k, 1], d[k, 0]])
    return n / np.hypot(*n)


class _Looks:
    """The silent firings of a run with no-echo readings, as arrays."""

    def __init__(self, readings: ReadingBatch, kind: np.ndarray) -> None:
        rows = np.flatnonzero(kind == NO_ECHO)
        self.t, self.x, self.y = readings.t[rows], readings.x[rows], readings.y[rows]
        self.theta, self.max_range = readings.theta[rows], readings.max_range[rows]
        width = readings.beam_width[rows]
        self.half = 0.5 * np.where(np.isfinite(width), width, math.radians(22.5))

    def at(self, point: np.ndarray, after: float) -> np.ndarray:
        """Rows of the silent firings within WINDOW after ``after`` whose beam holds ``point``."""
        near = np.flatnonzero((self.t > after) & (self.t < after + WINDOW))
        vx, vy = point[0] - self.x[near], point[1] - self.y[near]
        off = np.abs(np.angle(np.exp(1j * (np.arctan2(vy, vx) - self.theta[near]))))
        inside = (np.hypot(vx, vy) < self.max_range[near] - 0.05) & (off <= self.half[near])
        return near[inside]


def _look_stats(sim: Simulation, looks: _Looks, echo: int,
                model: SensorModel) -> tuple[np.ndarray, np.ndarray, float]:
    """True incidence (degrees) and model P_detect of each silent look at ``echo``'s point, and
    how far the implied normal is from the wall's (degrees)."""
    point = sim.truth.reflection[echo]
    rows = looks.at(point, float(sim.readings.t[echo]))
    normal = _wall_normal(np.asarray(sim.world.segments).reshape(-1, 4), point)
    implied = point - np.array([sim.readings.x[echo], sim.readings.y[echo]])
    implied /= np.hypot(*implied)
    incidence, p_detect = [], []
    for j in rows:
        vx, vy = point[0] - looks.x[j], point[1] - looks.y[j]
        cos_true = abs(vx * normal[0] + vy * normal[1]) / math.hypot(vx, vy)
        incidence.append(math.degrees(math.acos(min(1.0, cos_true))))
        p_detect.append(detect_probability(
            vx, vy, implied[0], implied[1], math.cos(looks.theta[j]), math.sin(looks.theta[j]),
            math.sin(looks.half[j]), model.edge_gain, math.cos(model.incidence_full),
            math.cos(model.incidence_zero), model.rough, model.max_detect, model.range_scale))
    normal_error = math.degrees(math.acos(min(1.0, abs(float(implied @ normal)))))
    return np.array(incidence), np.array(p_detect), normal_error


def _report(label: str, sim: Simulation, looks: _Looks, echoes: np.ndarray) -> None:
    model = SensorModel()
    stats = [_look_stats(sim, looks, int(i), model) for i in echoes]
    counts = np.array([len(inc) for inc, _, _ in stats])
    evidence = np.array([float(-np.log1p(-p).sum()) for _, p, _ in stats])
    incidence = np.concatenate([inc for inc, _, _ in stats]) if counts.sum() else np.zeros(0)
    p_detect = np.concatenate([p for _, p, _ in stats]) if counts.sum() else np.zeros(0)
    normal_error = np.median([err for _, _, err in stats])
    print(f"| {label} | {len(echoes)} | {normal_error:.0f} | {100 * np.mean(counts > 0):.0f} | "
          f"{np.median(counts):.0f} | {np.median(evidence):.2f} | "
          + (f"{np.median(incidence):.0f} | {100 * np.mean(incidence >= 30):.0f} | "
             f"{np.median(p_detect):.2f} | {100 * np.mean(p_detect > 0.5):.0f} |"
             if len(incidence) else "– | – | – | – |"))


def _run(world: str, seed: int, physics: str) -> None:
    overrides = () if physics == "specular" else (("echo_model", physics),)
    sim = run_simulation(Scenario(world, seed, physics=overrides))  # type: ignore[arg-type]
    every = simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics, sim.odometry,
                     scene=sim.scene, no_echo=True)
    echo_rows = np.flatnonzero(every.truth.kind != NO_ECHO)
    if not np.array_equal(every.readings.t[echo_rows], sim.readings.t):
        raise SystemExit("the two simulations' echoes differ")
    kept, kept_with = _kept(sim.readings), _kept(every.readings)[echo_rows]
    direct = sim.truth.kind == EchoKind.DIRECT
    lost = np.flatnonzero(direct & kept & ~kept_with)
    both = np.flatnonzero(direct & kept & kept_with)
    sample = np.random.default_rng(0).choice(both, min(SAMPLE, len(both)), replace=False)
    print(f"\n{world}, seed {seed}, {physics}: {int(direct.sum())} direct echoes, kept "
          f"{int(kept[direct].sum())} → {int(kept_with[direct].sum())} with silent firings "
          f"({len(lost)} lost, {int((direct & ~kept & kept_with).sum())} gained)\n")
    print("| direct echoes | n | implied normal off the wall's, median ° | with a silent look % | "
          "looks, median | silent evidence, median | looks' true incidence, median ° | "
          "at 30° or more % | model P_detect, median | model P_detect > 0.5 % |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    looks = _Looks(every.readings, every.truth.kind)
    _report("lost with silent firings", sim, looks, lost)
    _report(f"kept in both (sample of {len(sample)})", sim, looks, sample)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="+", default=["office:0:amplitude"],
                        metavar="WORLD:SEED:PHYSICS")
    args = parser.parse_args(argv)
    for run in args.runs:
        world, seed, physics = run.split(":")
        _run(world, int(seed), physics)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
