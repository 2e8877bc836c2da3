"""What the sonar simulator takes and gives: firings, their echoes and the echoes' kinds.

:class:`Firings` (when and where each sensor fired) go into
:func:`~sonarcarve.sim.sonar.fire_sonars`; :class:`Echoes` (what each firing heard, with its
truth: an :class:`EchoKind` code, or :data:`NO_ECHO`) come out. Both are structs of arrays,
one row per firing, in time order.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from enum import IntEnum

import numpy as np

from sonarcarve.typing import BoolArray, FloatArray, IntArray

__all__ = [
    "NO_ECHO",
    "EchoKind",
    "Echoes",
    "Firings",
]


#: Kind code of a firing that heard nothing.
NO_ECHO = -1


class EchoKind(IntEnum):
    """What produced a reading: the code stored per reading in the truth arrays."""

    DIRECT = 0
    CROSSTALK = 1
    FLOOR = 2
    MULTIPATH = 3

    @property
    def label(self) -> str:
        """Lower-case name, as written in truth files: ``direct``, ``crosstalk``, ..."""
        return self.name.lower()


@dataclass(frozen=True, eq=False)
class Firings:
    """When and where sensors fired: struct of arrays, shape (n,), in time order.

    Attributes
    ----------
    t : ndarray
        Firing times, seconds.
    sensor : ndarray of int64
        Index of the sensor that fired.
    x, y, theta : ndarray
        The sensor's true origin (m) and axis (rad) in the world frame at that time.
    """

    t: FloatArray
    sensor: IntArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray

    def __len__(self) -> int:
        return int(self.t.shape[0])

    def __getitem__(self, index: slice | IntArray | BoolArray) -> Firings:
        return Firings(**{f.name: getattr(self, f.name)[index] for f in fields(self)})


@dataclass(frozen=True, eq=False)
class Echoes:
    """What each firing heard: struct of arrays aligned with :class:`Firings`.

    Attributes
    ----------
    range : ndarray, shape (n,)
        Measured range (noise, quantisation), metres; NaN where the sensor heard nothing.
    true_range : ndarray, shape (n,)
        Noise-free range of the echo that was heard (half its path length, less the firing gap
        for crosstalk), metres; NaN where nothing was heard.
    kind : ndarray of int64, shape (n,)
        :class:`EchoKind` code, or :data:`NO_ECHO`.
    reflection : ndarray, shape (n, 2)
        True reflection point in the world frame, metres; NaN for floor and crosstalk echoes
        and where nothing was heard.
    obstacle : ndarray of int64, shape (n,)
        Index of the :class:`~sonarcarve.sim.scene.Scene` obstacle the echo came from (its
        reflection point lies on it), -1 for a static wall, no reflection point, or no scene.
    """

    range: FloatArray
    true_range: FloatArray
    kind: IntArray
    reflection: FloatArray
    obstacle: IntArray

    def __len__(self) -> int:
        return int(self.range.shape[0])

    @property
    def heard(self) -> BoolArray:
        """Firings that produced a reading."""
        return np.asarray(self.kind != NO_ECHO)
