"""A 2-D world of walls as line segments, and exact ray casting against it."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from sonarcarve.errors import SonarcarveError

__all__ = ["World", "WorldError"]

FloatArray = npt.NDArray[np.float64]


class WorldError(SonarcarveError):
    """A world that cannot be loaded or built: bad file, unknown name, degenerate walls."""


@dataclass(frozen=True, eq=False)
class World:
    """Walls as segments.

    Attributes
    ----------
    segments : ndarray, shape (n, 4)
        Wall ``i`` runs from ``(x1, y1)`` to ``(x2, y2)`` = ``segments[i]``, metres.
    name : str
        Where the world came from (built-in name or file).
    """

    segments: FloatArray
    name: str = "world"

    def __post_init__(self) -> None:
        seg = np.asarray(self.segments, dtype=np.float64).reshape(-1, 4)
        if not np.all(np.isfinite(seg)):
            msg = f"{self.name}: wall coordinates must be finite"
            raise WorldError(msg)
        object.__setattr__(self, "segments", seg)

    def __len__(self) -> int:
        return int(self.segments.shape[0])

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """``(xmin, ymin, xmax, ymax)`` of all walls."""
        xs = self.segments[:, [0, 2]]
        ys = self.segments[:, [1, 3]]
        return float(xs.min()), float(ys.min()), float(xs.max()), float(ys.max())

    def cast_rays(
        self, origins: npt.ArrayLike, angles: npt.ArrayLike, max_range: float = np.inf
    ) -> tuple[FloatArray, npt.NDArray[np.int64]]:
        """Distance to the first wall along each ray, exactly (no sampling).

        Parameters
        ----------
        origins : array-like, shape (n, 2) or (2,)
            Ray starts, metres (one origin broadcast to every ray if shape (2,)).
        angles : array-like, shape (n,)
            Ray directions, radians counter-clockwise from +x.
        max_range : float
            Rays that hit nothing closer return ``inf``.

        Returns
        -------
        distance : ndarray, shape (n,)
            Distance to the first hit, or ``inf``.
        wall : ndarray of int64, shape (n,)
            Index of the wall hit, or -1.

        Examples
        --------
        >>> w = World(np.array([[1.0, -1.0, 1.0, 1.0]]))
        >>> d, i = w.cast_rays([0.0, 0.0], [0.0, np.pi])
        >>> d.tolist(), i.tolist()
        ([1.0, inf], [0, -1])
        """
        angle = np.atleast_1d(np.asarray(angles, dtype=np.float64))
        origin = np.broadcast_to(np.asarray(origins, dtype=np.float64), (angle.shape[0], 2))
        direction = np.column_stack((np.cos(angle), np.sin(angle)))
        a = self.segments[:, :2]
        edge = self.segments[:, 2:] - a
        # Solve origin + s * direction = a + u * edge for every (ray, wall) pair (Cramer's rule).
        denom = _cross(direction[:, None, :], edge[None, :, :])
        delta = a[None, :, :] - origin[:, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            s = _cross(delta, edge[None, :, :]) / denom
            u = _cross(delta, direction[:, None, :]) / denom
        hit = (np.abs(denom) > 1e-12) & (s > 1e-9) & (u >= 0.0) & (u <= 1.0) & (s <= max_range)
        s = np.where(hit, s, np.inf)
        wall = np.argmin(s, axis=1) if len(self) else np.zeros(angle.shape[0], dtype=np.int64)
        distance = s[np.arange(angle.shape[0]), wall] if len(self) else np.full(angle.shape, np.inf)
        return distance, np.where(np.isfinite(distance), wall, -1).astype(np.int64)

    def distance_to_walls(self, points: npt.ArrayLike) -> FloatArray:
        """Euclidean distance from each point, shape (n, 2), to the nearest wall, shape (n,)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if not len(self):
            return np.full(p.shape[0], np.inf)
        a = self.segments[None, :, :2]
        edge = self.segments[None, :, 2:] - a
        length2 = np.maximum(np.sum(edge * edge, axis=2), 1e-24)
        u = np.clip(np.sum((p[:, None, :] - a) * edge, axis=2) / length2, 0.0, 1.0)
        nearest = a + u[:, :, None] * edge
        return np.asarray(np.min(np.linalg.norm(p[:, None, :] - nearest, axis=2), axis=1))


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.asarray(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])
