"""Evidence carving's laws across its parts (beyond the paper): weak looks accumulate into
carving (eq. 3.2), ATM's crossings count only inside the kept run (section 6), and the
confidence threshold and stamp error reach the local map (Appendix A)
(``docs/evidence-carving.md``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve import MethodConfig, make_method
from sonarcarve.geometry.evidence import EstimateRules, PieceEstimates, evidence_estimates
from sonarcarve.geometry.evidence.arrays import BinEvidence, CrossingArrays, ReadingRows
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import LocalMap
from sonarcarve.methods import EvidenceMethod
from sonarcarve.methods.evidence import EvidenceModel, SensorModel
from sonarcarve.readings import Reading

PHI = math.radians(22.5)

# --- 1. One strong reading or several weak ones -------------------------------------------

# The detection model, spelled out here (the defaults of SensorModel, given explicitly so the
# hand computation below does not depend on them).
_EDGE_GAIN = 0.5  # g
_INCIDENCE_FULL = math.radians(10.0)  # γ0
_MAX_DETECT = 0.95  # P_max
_RANGE_SCALE = 20.0  # L, metres
_CARVE_PROBABILITY = 0.8  # P_carve
_BINS = 24  # K

_OLDER_RANGE = 3.0  # the older arc: origin (0, 0), axis 0, r_i = 3 m
_TARGET_BIN = 12
_LOOK_DISTANCE = 6.0  # d: far, so A(d) = 1 / 1.3
_OFF_AXIS = 0.9 * PHI / 2  # δ: near the beam's edge
_INCIDENCES = (-6.0, -2.0, 2.0, 6.0)  # γ of each look, degrees: all below γ0, so I(γ) = 1


def _weak_look_evidence() -> float:
    """``w = -log(1 - P_detect)`` of one look (eq. 3.2), ``P_detect = P_max B I A`` from
    "The detection model": ``B = 1 - (1 - g) (sin δ / sin(φ/2))²``, ``I = 1`` (γ ≤ γ0),
    ``A = 1 / (1 + d / L)``."""
    u = math.sin(_OFF_AXIS) / math.sin(PHI / 2)
    beam = 1.0 - (1.0 - _EDGE_GAIN) * u * u
    spreading = 1.0 / (1.0 + _LOOK_DISTANCE / _RANGE_SCALE)
    return -math.log(1.0 - _MAX_DETECT * beam * 1.0 * spreading)


def _weak_look(k: int, gamma_deg: float) -> Reading:
    """A look from ``d`` metres at the older arc's target bin centre ``p``: ``p - o_j`` makes
    the angle γ with ``p``'s direction from the older origin (the implied surface's normal),
    ``p`` lies δ off the look's axis (alternating sides), and the echo is 1 m beyond ``p`` (a
    miss there: ``d < r_j - ε``; no support, the echo circle is far from the older arc)."""
    step = PHI / _BINS
    tau = -PHI / 2 + (_TARGET_BIN + 0.5) * step  # the bin centre's bearing
    px, py = _OLDER_RANGE * math.cos(tau), _OLDER_RANGE * math.sin(tau)
    look = tau + math.radians(gamma_deg)
    ox = px - _LOOK_DISTANCE * math.cos(look)
    oy = py - _LOOK_DISTANCE * math.sin(look)
    axis = look + (_OFF_AXIS if k % 2 == 0 else -_OFF_AXIS)
    return Reading(t=0.1 * (k + 1), sensor=1, x=ox, y=oy, theta=axis,
                   range=_LOOK_DISTANCE + 1.0, beam_width=PHI)


def test_several_weak_looks_carve_a_bin_that_one_leaves_alive() -> None:
    """Evidence of independent misses adds (log-odds, eq. 3.2): a bin is carved once the
    looks' sum reaches ``T = -log(1 - P_carve)``, "one strong reading or several weak ones".
    Each look here is weak (far, near the beam's edge), so one leaves the bin alive and
    ``ceil(T / w)`` looks from distinct places carve it; after ``m`` looks its evidence is
    ``m w``. A kernel that kept only the strongest look, or weighed a look otherwise than
    ``-log(1 - P_detect)``, fails."""
    threshold = -math.log(1.0 - _CARVE_PROBABILITY)
    w = _weak_look_evidence()
    needed = math.ceil(threshold / w)
    assert w < threshold  # one look is weak
    assert 1 < needed <= len(_INCIDENCES)
    sensor = SensorModel(edge_gain=_EDGE_GAIN, incidence_full=_INCIDENCE_FULL,
                         incidence_zero=math.radians(30.0), max_detect=_MAX_DETECT,
                         range_scale=_RANGE_SCALE)
    method = EvidenceMethod(min_confidence=0.0, evidence_bins=_BINS,
                            carve_probability=_CARVE_PROBABILITY, sensor=sensor)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    method.add(Reading(t=0.0, sensor=0, x=0.0, y=0.0, theta=0.0, range=_OLDER_RANGE,
                       beam_width=PHI))
    older = int(method.history.slots()[0])
    assert model.threshold == pytest.approx(threshold, rel=1e-12)
    for m, gamma in enumerate(_INCIDENCES[:needed], start=1):
        method.add(_weak_look(m - 1, gamma))
        free = float(model.free[older, _TARGET_BIN])
        assert free == pytest.approx(m * w, rel=1e-9), m
        assert (free >= threshold) == (m >= needed), m
    assert model.support[older].max() == 0.0  # nothing but misses weighed here


# --- 2. Crossings counted only inside the kept run ----------------------------------------

# One hand-made arc: r = 2 m, axis 0, a beam of 0.4 rad in K = 8 bins of 0.05 rad (bin k spans
# [-0.2 + 0.05 k, -0.15 + 0.05 k)); free evidence T + 1 carves a bin.
_K = 8
_STEP = 0.4 / _K
_T = -math.log(1.0 - 0.8)
_CUT = _T + 1.0


def _estimate(free: list[float], located: list[float],
              crossings: tuple[float, ...]) -> PieceEstimates:
    """:func:`evidence_estimates` of the arc with these per-bin evidence and ATM crossings
    (bearings relative to the axis), ATM's eq. 5.4 bound 1 cm, three crossings needed."""
    bearings = np.zeros((1, 16), dtype=np.float32)
    bearings[0, : len(crossings)] = crossings
    one = np.zeros(1)
    readings = ReadingRows(x=one, y=one, r=np.array([2.0]), theta=one,
                           beam_width=np.array([0.4]), sensor=np.zeros(1, dtype=np.int64))
    loc = np.array([located], dtype=np.float64)
    evidence = BinEvidence(free=np.array([free], dtype=np.float64), support=loc.copy(),
                           located=loc)
    store = CrossingArrays(bearings=bearings, counts=np.array([len(crossings)], dtype=np.int32),
                           spill=np.zeros((1, 2)))
    rules = EstimateRules(threshold=_T, atm_bound=0.01, with_atm=True, place_located=True,
                          min_crossings=3)
    return evidence_estimates(np.array([0], dtype=np.int64), readings, evidence,
                              np.zeros(1, dtype=np.int8), store, rules)


def _inside(crossings: tuple[float, ...], start: int, end: int) -> np.ndarray:
    """The crossings whose bearing lies in bins ``start .. end - 1`` (the oracle), as the
    store keeps them (float32)."""
    values = np.array(crossings, dtype=np.float32).astype(np.float64)
    lo, hi = -0.2 + start * _STEP, -0.2 + end * _STEP
    return values[(values >= lo) & (values < hi)]


def test_crossings_in_carved_bins_do_not_move_atms_median() -> None:
    """Section 6 integration: a crossing confirms a piece only if it lies in a surviving bin
    of it. Bins 0-1 are carved, 2-7 survive (one run). Three crossings inside it (bins 4, 5,
    6) and four in the carved bins: the piece holds 3 and ATM's point is their median (0.07);
    the median of all seven would be -0.12, in a carved bin."""
    inside = (0.02, 0.07, 0.11)
    carved = (-0.19, -0.18, -0.16, -0.12)
    crossings = (carved[0], inside[2], carved[1], inside[0], carved[2], carved[3], inside[1])
    expected = _inside(crossings, 2, _K)
    assert len(expected) == len(inside)
    assert np.median(np.array(crossings, dtype=np.float32)) < -0.1  # the mutant's answer
    out = _estimate([_CUT, _CUT, 0, 0, 0, 0, 0, 0], [0.0] * _K, crossings)
    assert out.has_piece[0]
    assert out.runs[0] == 1
    assert out.piece_crossings[0] == len(inside)
    assert out.is_atm[0]
    assert out.bearing[0] == pytest.approx(float(np.median(expected)), abs=1e-12)
    assert out.max_error[0] == 0.01  # eq. 5.4's bound: the run is all that survives


def test_crossings_in_a_run_not_kept_do_not_place_the_point() -> None:
    """A split arc: bin 3 carved, runs 0-2 and 4-7. Run 4-7 is kept (localised support 5 in
    bin 6 outweighs run 0-2's three crossings). Every crossing lies outside it (three in run
    0-2, two in the carved bin 3): the kept piece counts none, ATM does not place its point,
    and the posterior puts it at bin 6's middle (0.125), its only weighted bin. Counting all
    five would make ATM place it at their median, -0.12 (hull bound 2 r sin(0.345 / 2),
    smaller than 2 r sin(0.35 / 2) of 0.125)."""
    crossings = (-0.17, -0.03, -0.14, -0.02, -0.12)
    located = [0.0] * _K
    located[6] = 5.0
    out = _estimate([0, 0, 0, _CUT, 0, 0, 0, 0], located, crossings)
    assert len(_inside(crossings, 4, _K)) == 0
    assert out.runs[0] == 2
    assert out.piece_crossings[0] == 0
    assert not out.is_atm[0]
    assert out.bearing[0] == pytest.approx(-0.2 + 6.5 * _STEP, abs=1e-12)
    assert out.max_error[0] == pytest.approx(4.0 * math.sin((0.325 + 0.5 * _STEP) / 2),
                                             abs=1e-12)


# --- 3. The confidence threshold and the stamp error reach the local map -------------------

_STAMP = 0.07


def _local_map(min_confidence: float, stamp_error: float) -> LocalMap:
    readings = run_simulation(Scenario("office", 1, max_length=3.0)).readings
    method = make_method("evidence", MethodConfig(min_confidence=min_confidence,
                                                  stamp_error=stamp_error))
    method.add_many(readings)
    return method.local_map()


def test_the_local_map_holds_exactly_the_points_at_or_above_the_threshold() -> None:
    """``min_confidence`` X leaves out of the maps every point less likely real than X, and
    nothing else: on the same log, the local map at X holds the points of the map at X = 0
    whose confidence is at least X, at the same place with the same confidence, and none
    below X. The stamp error (Appendix A) widens every kept point's bound by itself and
    changes nothing else. The oracle is the X = 0, no-stamp map, filtered here; X runs over
    0, 0.5, 0.9 and one point's own confidence (the boundary: that point stays)."""
    everything = _local_map(0.0, 0.0)
    confidence = everything.confidence
    # The log must hold points on both sides of each threshold, or the filter proves nothing.
    assert np.count_nonzero(confidence < 0.5) > 0
    assert np.count_nonzero((confidence >= 0.5) & (confidence < 0.9)) > 0
    assert np.count_nonzero(confidence >= 0.9) > 0
    # And one point's own confidence: "at or above" keeps that point (and its equals).
    own = float(np.sort(confidence)[len(confidence) // 2])
    for threshold in (0.0, 0.5, 0.9, own):
        local = _local_map(threshold, _STAMP)
        keep = confidence >= threshold
        np.testing.assert_array_equal(local.reading_id, everything.reading_id[keep])
        np.testing.assert_array_equal(local.xy, everything.xy[keep])
        np.testing.assert_array_equal(local.confidence, confidence[keep])
        np.testing.assert_allclose(local.max_error, everything.max_error[keep] + _STAMP,
                                   rtol=0.0, atol=1e-12)
        assert np.all(local.confidence >= threshold)
