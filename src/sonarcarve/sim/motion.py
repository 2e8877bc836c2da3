"""Robot motion: time-stamped poses, and ways to make them (paths, exploration, odometry drift)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve.sim.world import WorldError

__all__ = ["Trajectory"]

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Robot poses over time, arrays of shape (n,), times strictly increasing.

    Attributes
    ----------
    t : ndarray
        Times, seconds.
    x, y : ndarray
        Robot centre in the world frame, metres.
    heading : ndarray
        Robot heading, radians counter-clockwise from +x, unwrapped (continuous).
    """

    t: FloatArray
    x: FloatArray
    y: FloatArray
    heading: FloatArray

    def __post_init__(self) -> None:
        arrays = [np.asarray(a, dtype=np.float64).reshape(-1) for a in
                  (self.t, self.x, self.y, self.heading)]
        if len({a.shape for a in arrays}) != 1 or arrays[0].shape[0] < 1:
            msg = "trajectory arrays must be non-empty and of equal length"
            raise WorldError(msg)
        if np.any(np.diff(arrays[0]) <= 0.0):
            msg = "trajectory times must be strictly increasing"
            raise WorldError(msg)
        for name, value in zip(("t", "x", "y", "heading"), arrays, strict=True):
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def duration(self) -> float:
        """Seconds from the first pose to the last."""
        return float(self.t[-1] - self.t[0])

    @property
    def path_length(self) -> float:
        """Metres travelled."""
        return float(np.sum(np.hypot(np.diff(self.x), np.diff(self.y))))

    def pose_at(self, times: npt.ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Linearly interpolated ``(x, y, heading)`` at ``times`` (clamped to the ends)."""
        q = np.asarray(times, dtype=np.float64)
        return (np.interp(q, self.t, self.x), np.interp(q, self.t, self.y),
                np.interp(q, self.t, self.heading))

    def distance_at(self, times: npt.ArrayLike) -> FloatArray:
        """Metres travelled from the start until ``times``."""
        travelled = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(self.x), np.diff(self.y)))))
        return np.asarray(np.interp(np.asarray(times, dtype=np.float64), self.t, travelled))
