"""The profile's bins: which of an arc's ``K`` bins a bearing or a direction falls in.

An arc's beam ``[θ - φ/2, θ + φ/2]`` is cut into ``K`` equal bins of width ``Δ = φ / K``; bin
``k`` covers the bearings ``θ - φ/2 + [k, k + 1) Δ`` and is represented by its centre
(``docs/evidence-carving.md``, "The profile"). The weighing pass needs the bin of a direction
inside a beam for every supporting bin, so it finds it from the sine of the angle to the axis
(no arc tangent; "Speed: the weighing kernel's layout").
"""

from __future__ import annotations

import math

from sonarcarve.geometry._compiled import compiled_inline
from sonarcarve.typing import FloatArray

__all__ = ["bin_from_guess", "bin_of", "bin_of_sine", "sine_guess"]


@compiled_inline
def bin_of(rel: float, half: float, width: float, bins: int) -> int:
    """Bin index of a bearing ``rel`` relative to the axis (clamped to the beam)."""
    k = math.floor((rel + half) / width)
    return min(max(k, 0), bins - 1)


@compiled_inline
def bin_of_sine(sine: float, edges: FloatArray, bins: int, scale: float) -> int:
    """Bin index of a direction inside a beam (``along > 0``) from the sine of its angle to the
    axis, ``edges[k]`` the sines of the bin edges (increasing; the beam is narrower than π):
    the same bin as :func:`bin_of` of the angle, without an arc tangent (clamped).

    The largest ``k`` in ``1 .. K - 1`` with ``edges[k] <= sine``, else 0. Found from a guess
    that treats the sines as evenly spaced (``scale = K / (edges[K] - edges[0])``; within a
    bin of the answer for a beam of 22.5°), then stepped to the exact bin by the comparisons
    themselves, so the guess changes only the speed: a binary search took 4-5 branches that
    the processor could not predict, for every supporting bin.
    """
    return bin_from_guess(sine_guess(sine, edges[0], bins, scale), sine, edges, bins)


@compiled_inline
def sine_guess(sine: float, first_edge: float, bins: int, scale: float) -> int:
    """:func:`bin_of_sine`'s guess (no branch: a loop of these runs on several sines at
    once)."""
    guess = (sine - first_edge) * scale
    # Clamped as a float before the conversion: for a very narrow beam the guess exceeds the
    # int64 range, and int() of that is undefined (it gave a huge negative index).
    return int(min(guess, bins - 1.0)) if guess > 0.0 else 0  # NaN: 0, as the search gave


@compiled_inline
def bin_from_guess(k: int, sine: float, edges: FloatArray, bins: int) -> int:
    """:func:`bin_of_sine` stepped from the guess ``k`` (in ``0 .. K - 1``)."""
    while k < bins - 1 and edges[k + 1] <= sine:
        k += 1
    while k > 0 and edges[k] > sine:
        k -= 1
    return k
