"""Local and global range maps: one point per surviving arc (paper, eq. 3.3, 3.6, 5.1-5.3).

A :class:`LocalMap` is what a method returns on request: one point per arc in the history that
survived, labelled by the model that placed it. A :class:`GlobalMap` collects the *final* point of
every arc as it leaves the history (paper, Fig. 7 and 13). Both are struct-of-arrays values with
the batch axis first.

Where the global map goes is a *sink* (:class:`GlobalMapSink`): anything with a ``commit(points)``
method, called with each block of final points as arcs leave the history, in reading order. The
default, :class:`GlobalMapBuilder`, keeps them all in memory (a map grows by about 22 MB per
million readings); :class:`CallbackSink` hands each block to a function, :class:`CountingSink`
counts and drops them, and :func:`sonarcarve.io.map_csv.map_csv_sink` appends them to a map CSV,
so a long run holds only the history and bounded buffers
(:meth:`~sonarcarve.methods.base.SonarMethod.set_global_sink`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, fields
from enum import IntEnum
from typing import Protocol, Self

import numpy as np
import numpy.typing as npt

from sonarcarve.typing import FloatArray, Int8Array, IntArray

__all__ = [
    "SOURCE_ATM",
    "SOURCE_CARVED",
    "SOURCE_CENTERLINE",
    "CallbackSink",
    "CountingSink",
    "GlobalMap",
    "GlobalMapBuilder",
    "GlobalMapSink",
    "LocalMap",
    "PointSource",
    "chord_error",
]



class PointSource(IntEnum):
    """The sonar model that placed a map point (the ``source`` column of the map CSV)."""

    CENTERLINE = 0  #: centre of an uncarved arc (section 2-A)
    CARVED = 1  #: centre of a carved arc (eq. 3.6)
    ATM = 2  #: median of transversal intersections (section 2-D)

    @property
    def label(self) -> str:
        """Lower-case name used in files: ``centerline``, ``carved`` or ``atm``."""
        return self.name.lower()


# The codes as plain ints for the compiled kernels (numba freezes int globals as constants).
SOURCE_CENTERLINE = int(PointSource.CENTERLINE)
SOURCE_CARVED = int(PointSource.CARVED)
SOURCE_ATM = int(PointSource.ATM)


def chord_error(r: npt.ArrayLike, width: npt.ArrayLike) -> FloatArray:
    """Maximum Euclidean error of a point at the centre of an arc (eq. 5.2 and 5.3).

    ``E_m = θ_d / 2`` (eq. 5.2) and ``E_s = 2 r sin(E_m / 2)`` (eq. 5.3).

    Parameters
    ----------
    r : array-like, shape (n,)
        Arc radii, metres.
    width : array-like, shape (n,)
        Angular widths θ_d = |θ2 − θ1| (eq. 5.1), radians.

    Examples
    --------
    >>> float(chord_error(2.0, 0.0)[()])
    0.0
    >>> round(float(chord_error(1.0, np.pi)[()]), 6)  # E_m = π/2: chord of a quarter circle
    1.414214
    """
    e_m = 0.5 * np.asarray(width, dtype=np.float64)
    return np.asarray(2.0 * np.asarray(r, dtype=np.float64) * np.sin(0.5 * e_m))


@dataclass(frozen=True, eq=False)
class _PointMap:
    """Map points as a struct of arrays (see :class:`LocalMap` for the fields)."""

    reading_id: IntArray
    t: FloatArray
    sensor: IntArray
    xy: FloatArray
    source: npt.NDArray[np.int8]
    width: FloatArray
    max_error: FloatArray
    range: FloatArray
    confidence: FloatArray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        # "Not modelled" by default: a NaN per point (a default cannot know n).
        if self.confidence.shape != self.reading_id.shape:
            if self.confidence.size:
                msg = (f"confidence has {self.confidence.size} values for "
                       f"{self.reading_id.size} points")
                raise ValueError(msg)
            object.__setattr__(self, "confidence", np.full(self.reading_id.shape, np.nan))

    def __len__(self) -> int:
        return int(self.reading_id.shape[0])

    @classmethod
    def empty(cls) -> Self:
        """A map with no points."""
        return cls(
            reading_id=np.zeros(0, dtype=np.int64), t=np.zeros(0), sensor=np.zeros(0, np.int64),
            xy=np.zeros((0, 2)), source=np.zeros(0, dtype=np.int8), width=np.zeros(0),
            max_error=np.zeros(0), range=np.zeros(0),
        )

    @classmethod
    def concatenate(cls, maps: Sequence[_PointMap]) -> Self:
        """The points of ``maps`` one after the other."""
        if not maps:
            return cls.empty()
        return cls(**{f.name: np.concatenate([getattr(m, f.name) for m in maps])
                      for f in fields(cls)})

    def select(self, mask: npt.NDArray[np.bool_] | IntArray) -> Self:
        """The points picked by a boolean mask or index array."""
        return type(self)(**{f.name: getattr(self, f.name)[mask] for f in fields(self)})

    def source_labels(self) -> list[str]:
        """``source`` as the file labels (``centerline``, ``carved``, ``atm``)."""
        return [PointSource(int(code)).label for code in self.source]

    def count(self, source: PointSource) -> int:
        """Number of points placed by ``source``."""
        return int(np.count_nonzero(self.source == source))


class LocalMap(_PointMap):
    """One point per surviving arc in the history at the moment it was requested (eq. 3.6).

    Arrays of shape (n,), oldest reading first (``xy`` is (n, 2)). Filter it like any struct
    of arrays, e.g. ``local.select(local.max_error < 0.15)``; note that an ATM point's bound is
    ``δ (1/sin ψ + 1/tan ψ)``, 0.144 m at the defaults, so a threshold below that keeps no ATM
    point.

    Attributes
    ----------
    reading_id : int64
        The reading's 0-based position in the input stream.
    t : float64
        The reading's time, seconds.
    sensor : int64
        The sensor that heard it.
    xy : float64, shape (n, 2)
        The point, world frame, metres.
    source : int8
        :class:`PointSource` code of the model that placed the point.
    width : float64
        Final angular width θ_d of the arc, radians (eq. 5.1); for ATM points the width of the
        interval spanned by the arc's kept intersections.
    max_error : float64
        Upper bound on the point's distance from the true reflection, metres (eq. 5.3 for arcs;
        see :mod:`sonarcarve.methods.atm` for the ATM bound).
    range : float64
        The arc's radius r, metres.
    confidence : float64
        Probability (0-1) that the point is a real surface (paper, section 6: certainty values),
        for methods that model it; NaN where the method does not (the paper's methods). Built
        without it, a map gets NaN.
    """


class GlobalMap(_PointMap):
    """The final point of every surviving arc of a whole log, in reading order (Fig. 7, 13).

    The same fields as :class:`LocalMap`; each point is the arc's state when it left the
    history. This is what ``sonarcarve process`` writes (the map CSV contract).
    """


class GlobalMapSink(Protocol):
    """Where a method sends the final points of arcs leaving its history (module docstring).

    ``commit`` is called with every point of the global map exactly once, in blocks, in
    reading order (never with an empty block); a sink must not keep a reference to a block's
    arrays and then modify them.
    """

    def commit(self, points: GlobalMap) -> None:
        """Take the final points of arcs leaving the history."""


class GlobalMapBuilder:
    """The in-memory sink: collects committed points cheaply (chunks) and hands out a
    :class:`GlobalMap`. Memory grows with the map: use another sink for long runs."""

    def __init__(self) -> None:
        self._chunks: list[_PointMap] = []

    def commit(self, points: _PointMap) -> None:
        """Add the final points of arcs leaving the history."""
        if len(points):
            self._chunks.append(points)

    def build(self) -> GlobalMap:
        """All points committed so far, as one map."""
        merged = GlobalMap.concatenate(self._chunks)
        self._chunks = [merged] if len(merged) else []
        return merged


class CallbackSink:
    """A sink that calls ``callback(points)`` with each non-empty block of committed points.

    Examples
    --------
    >>> blocks = []
    >>> sink = CallbackSink(blocks.append)
    >>> sink.commit(GlobalMap.empty())
    >>> blocks, sink.points
    ([], 0)
    """

    def __init__(self, callback: Callable[[GlobalMap], object]) -> None:
        self.callback = callback
        self.points = 0  #: points passed on so far

    def commit(self, points: GlobalMap) -> None:
        """Pass ``points`` to the callback (an empty block is not passed)."""
        if len(points):
            self.points += len(points)
            self.callback(points)


class CountingSink:
    """A sink that counts committed points, by source, and keeps none of them (a grid that is
    its own map, a benchmark)."""

    def __init__(self) -> None:
        self.points = 0  #: points committed so far
        self.by_source = np.zeros(len(PointSource), dtype=np.int64)  #: per PointSource code

    def commit(self, points: GlobalMap) -> None:
        """Count ``points``."""
        self.count(points.source)

    def count(self, source: Int8Array) -> None:
        """Count points of these :class:`PointSource` codes (what :meth:`commit` counts, for a
        method that need not make the points)."""
        if len(source):
            self.points += len(source)
            self.by_source += np.bincount(source.astype(np.int64),
                                          minlength=_SOURCES)[:_SOURCES]


#: Number of :class:`PointSource` codes (``len`` of an enum goes through its metaclass: slow).
_SOURCES = len(PointSource)
