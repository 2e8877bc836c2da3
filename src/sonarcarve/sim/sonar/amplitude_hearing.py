"""Whether the amplitude model hears a candidate echo: its level, noise, the first arrival.

Levels come from the sonar equations of :mod:`sonarcarve.sim.amplitude`; here each candidate
gets its own amplitude noise draw, from a counter-based hash keyed by the firing, the family of
echo and its source (so the same whatever the batching), and the nearest heard candidate per
firing wins.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.special import ndtri

from sonarcarve.sim.amplitude import AmplitudeModel
from sonarcarve.typing import BoolArray, FloatArray, IntArray

#: Amplitude model: candidate echoes more than this many noise deviations below the threshold
#: are dropped before the (costly) line-of-sight test; they would be heard once in 10⁹.
_PRUNE_SIGMAS = 6.0


#: Codes of the amplitude model's candidate echo families, keying their noise draws.
_MIRROR, _DIFFUSE, _CORNER, _MULTIPATH, _FOLDED, _CROSSTALK = 1, 2, 3, 4, 5, 6


def _noise(key: int, firing: IntArray, family: int, source: IntArray) -> FloatArray:
    """Standard normal draws, one per (firing, family, source) triple, from a counter-based
    hash of ``key``: the same whatever the batching or the other candidates (splitmix64)."""
    h = _splitmix(np.asarray(firing, dtype=np.uint64).reshape(-1) + np.uint64(key))
    h = _splitmix(h ^ np.uint64(family))
    h = _splitmix(h + np.asarray(source, dtype=np.uint64).reshape(-1))
    u = ((h >> np.uint64(11)).astype(np.float64) + 0.5) * 2.0**-53
    return np.asarray(ndtri(u))


def _splitmix(x: npt.NDArray[np.uint64]) -> npt.NDArray[np.uint64]:
    # Array arithmetic on uint64 wraps modulo 2**64, as the algorithm wants.
    z = x + np.uint64(0x9E3779B97F4A7C15)
    z = (z ^ (z >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    z = (z ^ (z >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return np.asarray(z ^ (z >> np.uint64(31)))


def _heard(level: FloatArray, key: int, firing: IntArray, family: int, source: IntArray,
           amplitude: AmplitudeModel) -> BoolArray:
    """Which candidate echoes (levels in dB, shape (k,)) beat the threshold plus their noise."""
    if level.size == 0:
        return np.zeros(0, dtype=bool)
    z = _noise(key, firing, family, source) if amplitude.noise_db > 0.0 else 0.0
    return np.asarray(level + amplitude.noise_db * z >= amplitude.threshold_db)


def _keep_first(firing: IntArray, rng_: FloatArray, point: FloatArray, f: int) -> tuple[
        FloatArray, FloatArray]:
    """Per firing (0..f-1) the candidate with the smallest range: range (f,), point (f, 2)."""
    best = np.full(f, np.inf)
    where = np.full((f, 2), np.nan)
    if firing.size == 0:
        return best, where
    order = np.lexsort((rng_, firing))
    first = order[np.r_[True, np.diff(firing[order]) != 0]]
    best[firing[first]] = rng_[first]
    where[firing[first]] = point[first]
    return best, where
