"""Sonar processing methods, picked by name from a dispatch table (``--method`` in the CLI).

Each method's module (and its numba kernels' dispatchers) is imported when the method is first
made or its class first named (:func:`__getattr__`), so that ``sonarcarve process --method
carve`` does not import evidence carving or ATM.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import TYPE_CHECKING

from sonarcarve.errors import ConfigError
from sonarcarve.methods.base import ArcModel, Estimates, Measures, SonarMethod
from sonarcarve.methods.config import MethodConfig

if TYPE_CHECKING:
    from sonarcarve.methods.atm import AtmMethod
    from sonarcarve.methods.carving import CarvingMethod, CarvingModel
    from sonarcarve.methods.centerline import CenterlineMethod
    from sonarcarve.methods.combined import CombinedMethod
    from sonarcarve.methods.evidence import EvidenceMethod

__all__ = [
    "METHODS",
    "ArcModel",
    "AtmMethod",
    "CarvingMethod",
    "CarvingModel",
    "CenterlineMethod",
    "CombinedMethod",
    "Estimates",
    "EvidenceMethod",
    "Measures",
    "MethodConfig",
    "SonarMethod",
    "make_method",
]


#: Class name -> the module that defines it (imported on first use: :func:`__getattr__`).
_LAZY = {
    "AtmMethod": "sonarcarve.methods.atm",
    "CarvingMethod": "sonarcarve.methods.carving",
    "CarvingModel": "sonarcarve.methods.carving",
    "CenterlineMethod": "sonarcarve.methods.centerline",
    "CombinedMethod": "sonarcarve.methods.combined",
    "EvidenceMethod": "sonarcarve.methods.evidence",
}


def __getattr__(name: str) -> object:
    """The method classes, each imported with its module when first asked for."""
    module = _LAZY.get(name)
    if module is None:
        msg = f"module {__name__!r} has no attribute {name!r}"
        raise AttributeError(msg)
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})


def _centerline(config: MethodConfig) -> SonarMethod:
    from sonarcarve.methods.centerline import CenterlineMethod

    return CenterlineMethod(config.history_size, config.beam_width)


def _atm(config: MethodConfig) -> SonarMethod:
    from sonarcarve.methods.atm import AtmMethod

    return AtmMethod(
        config.history_size, config.beam_width, config.min_transversal, config.range_resolution
    )


def _carve(config: MethodConfig) -> SonarMethod:
    from sonarcarve.methods.carving import CarvingMethod

    return CarvingMethod(config.history_size, config.beam_width, config.range_tolerance,
                         config.max_incidence)


def _combined(config: MethodConfig) -> SonarMethod:
    from sonarcarve.methods.combined import CombinedMethod

    return CombinedMethod(
        config.history_size, config.beam_width, config.range_tolerance,
        config.min_transversal, config.range_resolution, config.max_incidence,
    )


def _evidence(config: MethodConfig) -> SonarMethod:
    from sonarcarve.methods.evidence import EvidenceMethod

    return EvidenceMethod(
        config.history_size, config.beam_width, config.range_tolerance, config.min_transversal,
        config.range_resolution, config.evidence_bins, config.carve_probability,
        config.min_confidence, config.stamp_error, config.stamp_heading_error,
    )


#: Method name -> factory from a :class:`MethodConfig`.
METHODS: dict[str, Callable[[MethodConfig], SonarMethod]] = {
    "centerline": _centerline,
    "carve": _carve,
    "atm": _atm,
    "combined": _combined,
    "evidence": _evidence,
}


def make_method(name: str, config: MethodConfig | None = None) -> SonarMethod:
    """A new method by its CLI name, built from a validated :class:`MethodConfig`.

    Parameters
    ----------
    name : str
        ``"centerline"`` (section 2-A), ``"carve"`` (arc carving, section 3), ``"atm"`` (Arc
        Transversal Median, section 2-D), ``"combined"`` (carving and ATM on one history,
        section 4) or ``"evidence"`` (evidence carving with integrated ATM and per-point
        confidence, beyond the paper: :mod:`sonarcarve.methods.evidence`); the keys of
        :data:`METHODS`.
    config : MethodConfig, optional
        The parameters (history size in arcs, beam width φ in radians, range tolerance ε in
        metres, ATM's ψ in radians and δ in metres, specular β in radians; for evidence
        carving also its bins per beam K, P_carve, the minimum confidence of a mapped point
        and the stamping error bound in metres); each method reads the ones it needs.
        Default: ``MethodConfig()``, the paper's settings and the measured defaults
        documented there.

    Raises
    ------
    ConfigError
        For an unknown ``name``, or a ``config`` that is not a :class:`MethodConfig` (build
        one: ``MethodConfig(**values)``, which checks every value).

    Examples
    --------
    >>> make_method("carve", MethodConfig(history_size=100)).history.capacity
    100
    >>> make_method("carving")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sonarcarve.errors.ConfigError: unknown method 'carving'; choose one of centerline, carve, ...
    """
    try:
        factory = METHODS[name]
    except (KeyError, TypeError):
        msg = f"unknown method {name!r}; choose one of {', '.join(METHODS)}"
        raise ConfigError(msg) from None
    if config is None:
        config = MethodConfig()
    elif not isinstance(config, MethodConfig):
        msg = (f"config must be a MethodConfig, got {type(config).__name__} "
               "(build one with MethodConfig(**values))")
        raise ConfigError(msg)
    return factory(config)
