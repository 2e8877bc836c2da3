"""The carved grid under evidence carving (review rev9p): the band of an evidence-carved
arc is its kept run, wherever the evidence put the point."""

from __future__ import annotations

import math

import numpy as np

from sonarcarve.grids.carved import _intervals
from sonarcarve.methods import EvidenceMethod
from sonarcarve.methods.evidence import EvidenceModel
from sonarcarve.readings import Reading

PHI = math.radians(22.5)


def _reading(t: float, x: float, y: float, theta: float, r: float, sensor: int) -> Reading:
    return Reading(t=t, sensor=sensor, x=x, y=y, theta=theta, range=r, beam_width=PHI)


def test_an_evidence_arcs_band_is_its_kept_run_not_an_interval_around_its_point() -> None:
    # A wall at x = 2 heard head-on from the origin; a head-on look from (0.3, -0.35) sees
    # through its lower half (the kept run is the upper part, up to the beam's edge, 11.25°);
    # two other sensors' echoes cross it near bearing 0.15 rad (8.6°), where the posterior puts
    # the point. The band must cover the kept run and nothing else: "point ± width / 2" ran
    # 6° past the beam's edge and left the run's lower third out.
    method = EvidenceMethod(min_confidence=0.0, with_atm=False)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0))
    method.add(_reading(0.05, 0.3, -0.35, 0.0, 4.0, sensor=3))
    target = (2.0 * math.cos(0.15), 2.0 * math.sin(0.15))
    for k, (ox, oy) in enumerate(((0.8, -1.2), (0.9, -1.1))):
        method.add(_reading(0.1 + 0.05 * k, ox, oy, math.atan2(target[1] - oy, target[0] - ox),
                            math.hypot(target[0] - ox, target[1] - oy), sensor=1 + k))
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    slots = method.history.slots()
    est = method.estimates(slots)
    lo, hi, weight = _intervals(method.history.x[slots], method.history.y[slots], est)
    kept = np.flatnonzero(model.free[slots[0]] < model.threshold)
    assert np.all(np.diff(kept) == 1)  # one run
    step = PHI / model.bins
    run_lo, run_hi = -PHI / 2 + kept[0] * step, -PHI / 2 + (kept[-1] + 1) * step
    assert run_hi == PHI / 2 or abs(run_hi - PHI / 2) < 1e-12  # up to the beam's edge
    point = math.atan2(est.xy[0, 1], est.xy[0, 0])
    assert point > 0.5 * (run_lo + run_hi) + step  # the point is not at the run's middle
    assert weight[0] > 0.0
    assert abs(lo[0] - run_lo) < 1e-9
    assert abs(hi[0] - run_hi) < 1e-9
