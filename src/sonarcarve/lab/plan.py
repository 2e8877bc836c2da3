"""What an experiment plans: its size (:class:`Settings`) and its method runs (:class:`Job`).

A job is one sonar method on one simulated log (a :class:`~sonarcarve.lab.scenarios.Scenario`)
followed by one analysis of what it did (a function of :data:`~sonarcarve.lab.analyses.ANALYSES`,
named so that jobs pickle to worker processes). The runner
(:func:`~sonarcarve.lab.experiments.run_experiments`) makes each distinct simulation once and
runs every job on it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from sonarcarve.lab.scenarios import ExperimentError, Scenario
from sonarcarve.methods import MethodConfig
from sonarcarve.methods.carving import DEFAULT_RANGE_TOLERANCE
from sonarcarve.sim.motion import DEFAULT_SPEED

__all__ = ["ALL_METHODS", "ExperimentError", "Job", "Settings"]


#: Every method, in the order tables list them.
ALL_METHODS = ("atm", "carve", "combined", "centerline", "evidence")


@dataclass(frozen=True)
class Settings:
    """How big the experiments are. ``Settings.make()`` is what ``make experiments`` runs.

    Attributes
    ----------
    quick : bool
        Small runs (for the test suite): short tours, few openings, short sweeps.
    seeds : int
        Simulation seeds 0..seeds-1 for the office tour, the T junction and the openings.
    jobs : int
        Worker processes (1: everything in this process).
    history_size : int
        History length of the paper-style runs (paper, section 5-C: 250).
    speed : float
        Robot speed, m/s.
    sample_every : int
        Readings between two snapshots of the history (16 = one Scout2 ring cycle, 0.64 s).
    office_length : float or None
        Metres of the office tour to drive (None: all of it).
    sweep_length : float or None
        Metres of the office tour driven by each sensitivity run (None: all of it).
    opening_widths : tuple of float
        Door and side-opening widths, metres.
    """

    quick: bool = False
    seeds: int = 3
    jobs: int = 1
    history_size: int = 250
    speed: float = DEFAULT_SPEED
    sample_every: int = 16
    office_length: float | None = None
    sweep_length: float | None = None
    opening_widths: tuple[float, ...] = (0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2)
    door_headings_deg: tuple[float, ...] = (0.0, 20.0, -35.0, 45.0)
    door_offsets: tuple[float, ...] = (0.0, 0.15, -0.15)
    corridor_offsets: tuple[float, ...] = (-0.4, 0.0, 0.4)
    sweep_sample_every: int = 32
    sweeps: tuple[tuple[str, tuple[float, ...]], ...] = (
        ("history", (50, 100, 250, 500, 1000, 2000)),
        ("range_tolerance", (0.0, 0.01, 0.025, 0.05, 0.1)),
        ("beam_width_deg", (15.0, 22.5, 30.0)),
        ("min_transversal_deg", (10.0, 20.0, 30.0, 45.0, 60.0)),
        ("speed", (0.2, 0.4, 0.8)),
        ("range_noise", (0.0, 0.01, 0.03, 0.05)),
    )

    def __post_init__(self) -> None:
        if self.seeds < 1:
            msg = f"--seeds must be at least 1, got {self.seeds}"
            raise ExperimentError(msg)
        if self.jobs < 1:
            msg = f"--jobs must be at least 1, got {self.jobs}"
            raise ExperimentError(msg)

    @classmethod
    def make(cls, *, quick: bool = False, seeds: int | None = None, jobs: int = 1) -> Settings:
        """The full settings, or the quick ones (small enough for the test suite)."""
        if not quick:
            return cls(seeds=3 if seeds is None else seeds, jobs=jobs)
        return cls(
            quick=True, seeds=1 if seeds is None else seeds, jobs=jobs, office_length=30.0,
            sweep_length=12.0, opening_widths=(0.6, 1.2), door_headings_deg=(0.0,),
            door_offsets=(0.0,), corridor_offsets=(0.0,), sweep_sample_every=32,
            sweeps=(("history", (50, 250)), ("range_tolerance", (0.0, 0.025)),
                    ("beam_width_deg", (22.5, 30.0)), ("min_transversal_deg", (20.0, 30.0)),
                    ("speed", (0.4, 0.8)), ("range_noise", (0.01, 0.03))),
        )

    def method_config(self, **changes: Any) -> MethodConfig:
        """The paper-style configuration: history 250, φ 22.5°, ψ 30°, δ one inch, and carving's
        measured default ε (:data:`~sonarcarve.methods.carving.DEFAULT_RANGE_TOLERANCE`)."""
        base = MethodConfig(history_size=self.history_size,
                            range_tolerance=DEFAULT_RANGE_TOLERANCE)
        return replace(base, **changes)


@dataclass(frozen=True)
class Job:
    """One method on one scenario, then one analysis.

    ``key`` names the job's output among all outputs of a run; ``analysis`` is a key of
    :data:`~sonarcarve.lab.analyses.ANALYSES`, called with ``options`` as keyword arguments;
    a snapshot of the local map is taken every ``sample_every`` readings.
    """

    key: tuple[Any, ...]
    scenario: Scenario
    method: str
    config: MethodConfig
    analysis: str
    sample_every: int = 16
    options: tuple[tuple[str, Any], ...] = ()
