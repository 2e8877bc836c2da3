"""What the appendix experiments share: their settings, error, simulations and summaries.

The experiments themselves live in :mod:`~sonarcarve.lab.experiments.polling`,
:mod:`~sonarcarve.lab.experiments.filters`, :mod:`~sonarcarve.lab.experiments.real_log`
and :mod:`~sonarcarve.lab.experiments.odometry`; they plan no jobs of the runner but run
themselves in ``summarise``, with :class:`AppendixSettings` derived from the run's
:class:`~sonarcarve.lab.plan.Settings`. The helpers here are for those modules, not a general
API.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sonarcarve.errors import SonarcarveError
from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import METHOD_LABELS
from sonarcarve.lab.drawing import METHOD_COLORS
from sonarcarve.lab.plan import Settings
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import GlobalMap
from sonarcarve.methods import MethodConfig, make_method
from sonarcarve.pipeline import process_readings
from sonarcarve.readings import ReadingBatch
from sonarcarve.typing import FloatArray, JsonDict

if TYPE_CHECKING:
    from sonarcarve.sim.motion import Trajectory
    from sonarcarve.sim.simulate import Simulation

__all__ = [
    "COLORS",
    "LABELS",
    "METHODS",
    "AppendixError",
    "AppendixSettings",
    "json_float",
    "mean_or_none",
    "office_simulation",
    "run_global_map",
    "summary_dict",
]


#: Method CLI names in table order, the labels results use and their colours (as the
#: experiments' own).
METHODS = ("centerline", "carve", "atm", "combined")
LABELS = METHOD_LABELS
COLORS = METHOD_COLORS


class AppendixError(SonarcarveError):
    """A bad appendix request: unknown experiment name, bad setting, broken markers."""


# ============================================================================ settings


@dataclass(frozen=True)
class AppendixSettings:
    """How big the appendix experiments are.

    Attributes
    ----------
    quick : bool
        Small runs for the test suite.
    seeds : int
        Simulation seeds 0..seeds-1 (polling, filters and odometry).
    tour_length : float or None
        Metres of the office tour to drive (None: all of it, 261 m).
    poll_rates : tuple of float
        Host polling rates, Hz.
    figure_rate : float
        The polling rate whose maps Fig. 14 shows, Hz (one of ``poll_rates``).
    poll_jitter : float
        Each poll interval is ``(1 + u) / rate`` with ``u`` uniform in ``[-jitter, jitter]``: a
        host's polls are not perfectly periodic.
    spread_radius : float
        Neighbourhood radius of
        :func:`~sonarcarve.lab.experiments.real_log.line_spread`, metres.
    spread_min_points : int
        Fewest points (the point itself included) for a spread to be defined.
    distance_bin : float
        Width of the distance-travelled bins of the odometry curves, metres.
    """

    quick: bool = False
    seeds: int = 3
    tour_length: float | None = None
    poll_rates: tuple[float, ...] = (2.5, 5.0, 10.0, 20.0)
    figure_rate: float = 10.0
    poll_jitter: float = 0.2
    spread_radius: float = 0.25
    spread_min_points: int = 5
    distance_bin: float = 20.0

    def __post_init__(self) -> None:
        if self.seeds < 1:
            msg = f"seeds must be at least 1, got {self.seeds}"
            raise AppendixError(msg)
        if self.figure_rate not in self.poll_rates:
            msg = f"figure_rate {self.figure_rate} Hz is not one of poll_rates {self.poll_rates}"
            raise AppendixError(msg)
        if any(not (math.isfinite(r) and r > 0.0) for r in self.poll_rates):
            msg = f"poll rates must be finite and > 0 Hz, got {self.poll_rates}"
            raise AppendixError(msg)
        if not 0.0 <= self.poll_jitter < 1.0:
            msg = f"poll_jitter must lie in [0, 1), got {self.poll_jitter}"
            raise AppendixError(msg)

    @classmethod
    def make(cls, *, quick: bool = False, seeds: int | None = None) -> AppendixSettings:
        """Full settings (3 seeds, whole tour), or quick ones (1 seed, 40 m, 10 Hz only)."""
        if not quick:
            return cls(seeds=3 if seeds is None else seeds)
        return cls(quick=True, seeds=1 if seeds is None else seeds, tour_length=40.0,
                   poll_rates=(10.0,), distance_bin=10.0)

    @classmethod
    def from_settings(cls, settings: Settings) -> AppendixSettings:
        """The appendix's settings for a run of the experiments: quick or full, same seeds."""
        return cls.make(quick=settings.quick, seeds=settings.seeds)

    def method_config(self) -> MethodConfig:
        """The library defaults (history 250, φ 22.5°, ψ 20°, ε 5 cm, δ one inch)."""
        return MethodConfig()


# ============================================================================ helpers


def json_float(x: float | None) -> float | None:
    """``x``, or None where it is None, NaN or infinite (strict JSON)."""
    return None if x is None or not math.isfinite(x) else float(x)


def mean_or_none(values: Sequence[float | None]) -> float | None:
    """Mean of the finite values (None and NaN left out); None when there are none."""
    ok = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.mean(ok)) if ok else None


def summary_dict(err: FloatArray) -> JsonDict:
    """:func:`~sonarcarve.lab.metrics.error_summary` of ``err`` (metres), JSON-ready."""
    return dict(metrics.error_summary(err).as_dict())



def office_simulation(settings: AppendixSettings, seed: int,
                      drift: bool = False) -> tuple[Simulation, Trajectory | None]:
    """The office tour (the first ``tour_length`` metres) simulated with seed ``seed``; with
    ``drift``, stamped with dead-reckoned poses (:func:`~sonarcarve.sim.motion.with_odometry_drift`
    with the same seed) and that odometry returned too."""
    sim = run_simulation(Scenario("office", seed, max_length=settings.tour_length,
                                  odometry_drift=drift))
    return sim, sim.odometry


def run_global_map(batch: ReadingBatch, method: str,
                   config: MethodConfig) -> tuple[GlobalMap, JsonDict]:
    """``method``'s global map of ``batch`` and its counts (readings, fully carved, split)."""
    result = process_readings(batch, make_method(method, config))
    return result.global_map, {"readings": result.readings, "fully_carved": result.fully_carved,
                               "split": result.split}
