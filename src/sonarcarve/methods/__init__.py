"""Sonar processing methods, picked by name from a dispatch table (``--method`` in the CLI)."""

from __future__ import annotations

from collections.abc import Callable

from sonarcarve.methods.base import ArcModel, Estimates, Measures, SonarMethod
from sonarcarve.methods.centerline import CenterlineMethod
from sonarcarve.methods.config import MethodConfig

__all__ = [
    "METHODS",
    "ArcModel",
    "CenterlineMethod",
    "Estimates",
    "Measures",
    "MethodConfig",
    "SonarMethod",
    "make_method",
]


def _centerline(config: MethodConfig) -> SonarMethod:
    return CenterlineMethod(config.history_size, config.beam_width)


#: Method name -> factory from a :class:`MethodConfig`.
METHODS: dict[str, Callable[[MethodConfig], SonarMethod]] = {
    "centerline": _centerline,
}


def make_method(name: str, config: MethodConfig | None = None) -> SonarMethod:
    """A new method by its CLI name (``centerline``, ``carve``, ``atm``, ``combined``)."""
    try:
        factory = METHODS[name]
    except KeyError:
        msg = f"unknown method {name!r}; choose one of {', '.join(METHODS)}"
        raise ValueError(msg) from None
    return factory(config or MethodConfig())
