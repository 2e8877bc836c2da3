"""Sonar processing methods, picked by name from a dispatch table (``--method`` in the CLI)."""

from __future__ import annotations

from collections.abc import Callable

from sonarcarve.methods.atm import AtmMethod
from sonarcarve.methods.base import ArcModel, Estimates, Measures, SonarMethod
from sonarcarve.methods.carving import CarvingMethod, CarvingModel
from sonarcarve.methods.centerline import CenterlineMethod
from sonarcarve.methods.combined import CombinedMethod
from sonarcarve.methods.config import MethodConfig

__all__ = [
    "METHODS",
    "ArcModel",
    "AtmMethod",
    "CarvingMethod",
    "CarvingModel",
    "CenterlineMethod",
    "CombinedMethod",
    "Estimates",
    "Measures",
    "MethodConfig",
    "SonarMethod",
    "make_method",
]


def _centerline(config: MethodConfig) -> SonarMethod:
    return CenterlineMethod(config.history_size, config.beam_width)


def _atm(config: MethodConfig) -> SonarMethod:
    return AtmMethod(
        config.history_size, config.beam_width, config.min_transversal, config.range_resolution
    )


def _carve(config: MethodConfig) -> SonarMethod:
    return CarvingMethod(config.history_size, config.beam_width, config.range_tolerance,
                         config.max_incidence)


def _combined(config: MethodConfig) -> SonarMethod:
    return CombinedMethod(
        config.history_size, config.beam_width, config.range_tolerance,
        config.min_transversal, config.range_resolution, config.max_incidence,
    )


#: Method name -> factory from a :class:`MethodConfig`.
METHODS: dict[str, Callable[[MethodConfig], SonarMethod]] = {
    "centerline": _centerline,
    "carve": _carve,
    "atm": _atm,
    "combined": _combined,
}


def make_method(name: str, config: MethodConfig | None = None) -> SonarMethod:
    """A new method by its CLI name (``centerline``, ``carve``, ``atm``, ``combined``)."""
    try:
        factory = METHODS[name]
    except KeyError:
        msg = f"unknown method {name!r}; choose one of {', '.join(METHODS)}"
        raise ValueError(msg) from None
    return factory(config or MethodConfig())
