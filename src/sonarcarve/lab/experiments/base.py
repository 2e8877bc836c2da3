"""The shape every experiment has, and what its Markdown gets to know about the run.

An :class:`Experiment` says what it runs (:attr:`~Experiment.plan`: method runs, see
:class:`~sonarcarve.lab.plan.Job`), what it computes from their outputs
(:attr:`~Experiment.summarise`: a typed result, and the arrays its figure needs), its figures
(:attr:`~Experiment.figure`) and its part of ``docs/RESULTS.md`` (:attr:`~Experiment.markdown`).
:data:`sonarcarve.lab.experiments.EXPERIMENTS` registers one per module.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Generic, NamedTuple, TypeVar

from sonarcarve.lab.plan import Job, Settings
from sonarcarve.typing import JsonDict

__all__ = ["Artifacts", "Experiment", "Outputs", "Page", "Part", "no_jobs"]

R = TypeVar("R")

#: What a run's jobs returned, by job key (see :func:`~sonarcarve.lab.experiments.jobs.run_job`).
Outputs = Mapping[tuple[Any, ...], JsonDict]
#: Arrays and other large things a figure needs; never written to JSON.
Artifacts = dict[str, Any]


class Part(NamedTuple):
    """One subsection of a ``docs/RESULTS.md`` section.

    Attributes
    ----------
    order : int
        Its place in its section (the paper's order; parts of several experiments interleave).
    lines : list of str
        Markdown lines, ending with a blank line.
    """

    order: int
    lines: list[str]


@dataclass(frozen=True)
class Page:
    """What an experiment's Markdown may use besides its own result.

    Attributes
    ----------
    figures : mapping of str to str
        PNG file name -> its link relative to the Markdown file (figures written this run).
    settings : Settings
        The run's settings.
    results : mapping of str to object
        Every result of this run, by experiment name (for sentences comparing experiments).
    """

    figures: Mapping[str, str]
    settings: Settings
    results: Mapping[str, Any]


@dataclass(frozen=True)
class Experiment(Generic[R]):
    """One experiment of the registry.

    Attributes
    ----------
    name : str
        Its name on the command line (``sonarcarve experiments --only NAME``).
    title : str
        What it reproduces, in a few words.
    section : str
        The ``docs/RESULTS.md`` section its parts go to: ``"experiments"`` or ``"appendix"``.
    plan : callable
        ``plan(settings) -> list[Job]``: the method runs it needs (none for experiments that
        run themselves in ``summarise``).
    summarise : callable
        ``summarise(settings, outputs) -> (result, artifacts)``: its typed result from the
        outputs of its jobs (keyed by job key), and the arrays its figure needs.
    figure : callable
        ``figure(result, artifacts, folder) -> list[Path]``: writes its PNGs into ``folder``.
    markdown : callable
        ``markdown(result, page) -> list[Part]``: its subsections of ``docs/RESULTS.md``.
    """

    name: str
    title: str
    section: str
    plan: Callable[[Settings], list[Job]]
    summarise: Callable[[Settings, Outputs], tuple[R, Artifacts]]
    figure: Callable[[R, Artifacts, Path], list[Path]]
    markdown: Callable[[R, Page], list[Part]]


def no_jobs(settings: Settings) -> list[Job]:
    """The plan of an experiment that runs itself in ``summarise``."""
    return []
