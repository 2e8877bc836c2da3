"""What the appendix experiments share: their settings, error, simulations and text helpers.

The experiments themselves live in :mod:`~sonarcarve.lab.appendix_polling`,
:mod:`~sonarcarve.lab.appendix_filters`, :mod:`~sonarcarve.lab.appendix_real_log`
and :mod:`~sonarcarve.lab.appendix_odometry`; :mod:`sonarcarve.lab.appendix` runs
them and writes their outputs. The helpers here are for those modules, not a general API.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from sonarcarve.errors import SonarcarveError
from sonarcarve.lab import metrics
from sonarcarve.lab.analyses import METHOD_LABELS
from sonarcarve.lab.drawing import METHOD_COLORS
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
    "fmt_cm",
    "fmt_dist",
    "fmt_mm",
    "fmt_ms",
    "fmt_num",
    "fmt_pct",
    "fmt_seeds",
    "fmt_span",
    "json_float",
    "md_image",
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
        :func:`~sonarcarve.lab.appendix_real_log.line_spread`, metres.
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


# ============================================================================ text


def fmt_cm(value: float | None) -> str:
    """A distance in cm, one decimal; n/a for None."""
    return "n/a" if value is None else f"{100.0 * value:.1f} cm"



def fmt_num(value: float | None, digits: int = 1) -> str:
    """``value`` with ``digits`` decimals; n/a for None."""
    return "n/a" if value is None else f"{value:.{digits}f}"


def fmt_dist(value: float | None) -> str:
    """A distance in cm below a metre, else in m."""
    if value is None:
        return "n/a"
    return fmt_cm(value) if abs(value) < 1.0 else f"{value:.1f} m"


def fmt_pct(value: float | None, digits: int = 0) -> str:
    """A percentage; n/a for None."""
    return "n/a" if value is None else f"{value:.{digits}f}%"


def fmt_span(values: Sequence[float | None], fmt: Callable[[float | None], str]) -> str:
    """``a`` or ``a-b`` (min-max) of the values that exist."""
    ok = [v for v in values if v is not None]
    if not ok:
        return "n/a"
    lo, hi = fmt(min(ok)), fmt(max(ok))
    return lo if lo == hi else f"{lo} to {hi}"


def fmt_seeds(n: int) -> str:
    """``seed 0`` or ``seeds 0-{n-1}``."""
    return "seed 0" if n == 1 else f"seeds 0-{n - 1}"


def fmt_ms(value: float | None) -> str:
    """Seconds shown in milliseconds; n/a for None."""
    return "n/a" if value is None else f"{1000.0 * value:.2f} ms"


def fmt_mm(value: float | None) -> str:
    """Metres shown in millimetres; n/a for None."""
    return "n/a" if value is None else f"{1000.0 * value:.1f} mm"



def md_image(figs: dict[str, str], name: str, alt: str) -> list[str]:
    """A Markdown image line for figure ``name`` (its path in ``figs``, else ``figures/name``)."""
    return [f"![{alt}]({figs.get(name, 'figures/' + name)})", ""]
