"""The depth behind the newer arcs (``geometry/evidence/behind.py``) against its definition in
plain Python: bearings by ``atan2`` instead of the kernel's cosines, one loop, no slices."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.geometry.evidence import EVIDENCE_ALIVE, EVIDENCE_CARVED
from sonarcarve.geometry.evidence.behind import depth_behind_newer

ESTABLISH = 1.0
MARGIN = 0.1  # 2ε


def _oracle(j: int, first: int, n_newer: int, x: list[float], y: list[float], r: list[float],
            theta: list[float], half: list[float], status: list[int],
            viewpoints: list[float]) -> float:
    """``r_j - d`` for the nearest axis point ``o_i + r_i u(θ_i)`` of the ``n_newer`` rows from
    ``first`` on (wrapping) that is alive, heard from distinct viewpoints and within ``j``'s
    half-beam of its axis, nearer than ``r_j - 2ε``; 0 when there is none."""
    best = None
    for k in range(n_newer):
        i = (first + k) % len(x)
        if status[i] != EVIDENCE_ALIVE or viewpoints[i] < ESTABLISH:
            continue
        px = x[i] + r[i] * math.cos(theta[i])
        py = y[i] + r[i] * math.sin(theta[i])
        d = math.hypot(px - x[j], py - y[j])
        off = math.atan2(py - y[j], px - x[j]) - theta[j]
        off = abs((off + math.pi) % (2.0 * math.pi) - math.pi)
        if off <= half[j] and d < r[j] - MARGIN and (best is None or d < best):
            best = d
    return 0.0 if best is None else r[j] - best


def _depth(j: int, first: int, n_newer: int, x: list[float], y: list[float], r: list[float],
           theta: list[float], half: list[float], status: list[int],
           viewpoints: list[float]) -> float:
    """The kernel's depth for the same rows (its arrays built here)."""
    a = np.asarray
    return float(depth_behind_newer(
        j, first, n_newer, a(x, dtype=float), a(y, dtype=float), a(r, dtype=float),
        np.cos(a(theta)), np.sin(a(theta)), np.cos(a(half)), a(status, dtype=np.int8),
        a(viewpoints, dtype=float), ESTABLISH, MARGIN, np.zeros(len(x))))


def test_a_hand_made_scene() -> None:
    # Row 0 leaves: at the origin, axis along +x, 3 m, half-beam 11.25°. The rows after it:
    # 1: a wall 1 m ahead, 2 cm to the side (inside the beam), confirmed: it counts;
    # 2: nearer (0.6 m ahead) but carved; 3: nearer still but heard from one viewpoint only;
    # 4: 1.5 m ahead but 0.5 m aside, 18° off the axis: outside the beam;
    # 5: on the axis 2.95 m ahead, inside 2ε of the echo: not in front of it.
    x = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    y = [0.0, 0.02, 0.0, 0.0, 0.5, 0.0]
    r = [3.0, 1.0, 0.6, 0.5, 1.5, 2.95]
    theta = [0.0] * 6
    half = [math.radians(11.25)] * 6
    status = [EVIDENCE_ALIVE, EVIDENCE_ALIVE, EVIDENCE_CARVED, EVIDENCE_ALIVE, EVIDENCE_ALIVE,
              EVIDENCE_ALIVE]
    viewpoints = [0.0, 1.2, 3.0, 0.5, 3.0, 3.0]
    expected = 3.0 - math.sqrt(1.0 + 0.02**2)  # row 1's point (1, 0.02)
    assert _depth(0, 1, 5, x, y, r, theta, half, status, viewpoints) == pytest.approx(
        expected, abs=1e-12)
    # Row 1 alone left out (n_newer stops before it is reached when first is 2): nothing.
    assert _depth(0, 2, 4, x, y, r, theta, half, status, viewpoints) == 0.0
    # Confirmed, row 3 becomes the nearest: 3 - 0.5.
    viewpoints[3] = 1.0
    assert _depth(0, 1, 5, x, y, r, theta, half, status, viewpoints) == pytest.approx(2.5)


_Scene = tuple[int, int, int, list[float], list[float], list[float], list[float], list[float],
               list[int], list[float]]


def _scene(seed: int) -> _Scene:
    """Ten rows in a ring; the leaving row somewhere, the newer ones after it wrapping past
    the end; points scattered around it so that some fall in and out of its beam and range.
    The arguments of :func:`_depth` and :func:`_oracle`."""
    rng = np.random.default_rng(seed)
    n = 10
    x = rng.uniform(-0.5, 0.5, n).tolist()
    y = rng.uniform(-0.5, 0.5, n).tolist()
    r = rng.uniform(0.2, 4.0, n).tolist()
    theta = rng.uniform(-0.6, 0.6, n).tolist()
    half = [math.radians(float(h)) for h in rng.uniform(5.0, 30.0, n)]
    status = [EVIDENCE_ALIVE if s else EVIDENCE_CARVED for s in rng.uniform(size=n) < 0.8]
    viewpoints = rng.uniform(0.0, 2.0, n).tolist()
    j = int(rng.integers(n))
    return j, (j + 1) % n, int(rng.integers(1, n)), x, y, r, theta, half, status, viewpoints


@pytest.mark.parametrize("seed", range(40))
def test_random_scenes_match_the_definition(seed: int) -> None:
    scene = _scene(seed)
    assert _depth(*scene) == pytest.approx(_oracle(*scene), abs=1e-12)


def test_some_random_scenes_have_a_depth() -> None:
    # The scenes above are not all empty (the comparison would then prove little).
    depths = [_oracle(*_scene(seed)) for seed in range(40)]
    assert sum(d > 0.0 for d in depths) >= 5
    assert sum(d == 0.0 for d in depths) >= 5
