"""Evidence carving (``evidence``): constructed cases and its own laws (beyond the paper)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest

from sonarcarve import MethodConfig, make_method
from sonarcarve.errors import ConfigError, SonarcarveError
from sonarcarve.geometry.evidence.arrays import (
    AddScratch,
    ArcEvidence,
    ArcShapes,
    BinEvidence,
    CrossingArrays,
    EvidenceState,
    ReadingRows,
)
from sonarcarve.history import SonarHistory
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.maps import PointSource
from sonarcarve.methods import EvidenceMethod
from sonarcarve.methods import atm as atm_module
from sonarcarve.methods import evidence as evidence_module
from sonarcarve.methods.atm import CrossingStoreError
from sonarcarve.methods.evidence import (
    CONFIDENCE_FEATURES,
    ConfidenceModel,
    EvidenceModel,
    EvidenceOptions,
)
from sonarcarve.readings import Reading, ReadingBatch

PHI = math.radians(22.5)


def _reading(t: float, x: float, y: float, theta: float, r: float, sensor: int = 0) -> Reading:
    return Reading(t=t, sensor=sensor, x=x, y=y, theta=theta, range=r, beam_width=PHI)


def _ids(method: EvidenceMethod | object) -> set[int]:
    local = method.local_map()  # type: ignore[attr-defined]
    return set(local.reading_id.tolist())


def test_glancing_newer_beam_does_not_delete_a_true_echo() -> None:
    # A wall at x = 1 seen head-on from the origin, then looked past at ~40° incidence by a
    # reading from (0, 0.9) that heard nothing before 3 m (carve_arc's doctest case).
    first = _reading(0.0, 0.0, 0.0, 0.0, 1.0)
    glancing = _reading(0.1, 0.0, 0.9, -0.7, 3.0, sensor=1)
    paper = make_method("carve")
    # The carving alone (confidence filter off): a lone echo never heard again loses
    # confidence as it matures whether or not a glancing beam passed it.
    evidence = make_method("evidence", MethodConfig(min_confidence=0.0))
    for method in (paper, evidence):
        method.add(first)
        method.add(glancing)
    assert 0 not in _ids(paper)  # the paper's veto deletes the true echo
    assert 0 in _ids(evidence)


def test_crosstalk_echo_in_open_space_is_removed() -> None:
    # Facing a wall 3 m away, heard by several sensors (distinct viewpoints confirm it); one
    # phantom at 1 m (crosstalk) among them; the ring goes on for a second (its confidence
    # matures: a fresh point is shown at once).
    method = make_method("evidence")
    readings = [_reading(0.05 * k, 0.0, 0.02 * k, 0.0, 3.0, k + 1) for k in range(3)]
    readings.append(_reading(0.15, 0.0, 0.06, 0.0, 1.0))
    readings += [_reading(0.2 + 0.05 * k, 0.0, 0.08 + 0.02 * k, 0.0, 3.0, k % 6 + 1)
                 for k in range(30)]
    for reading in readings:
        method.add(reading)
    ids = _ids(method)
    assert 3 not in ids
    assert {0, 1, 2, 4, 5, 6} <= ids


def test_multipath_echo_behind_an_established_wall_is_flagged() -> None:
    # A wall at x = 2 heard head-on from three places (each echo supports the others), then an
    # echo that reads 3.5 m straight through it: it must come from behind the wall.
    method = make_method("evidence")
    assert isinstance(method, EvidenceMethod)
    for k, y in enumerate((0.0, 0.1, -0.1, 0.05, -0.05)):
        method.add(_reading(0.05 * k, 0.0, y, 0.0, 2.0, sensor=k))
    method.add(_reading(0.3, 0.0, 0.0, 0.0, 3.5, sensor=5))
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    slot = int(method.history.slots()[-1])
    assert model.occluded[slot] > 0.5  # the flag: most of its beam lies behind the wall
    ids = _ids(method)
    assert 5 not in ids
    assert {0, 1, 2, 3, 4} <= ids  # the wall stays


def _image_then_wall(history: int,
                     model: ConfidenceModel | None = None) -> tuple[EvidenceMethod, list[Reading]]:
    # Sensors 5 and 6, 0.1 m apart, hear a mirror image 3 m ahead (a multipath path: the two
    # agree, each supports the other); then five sensors hear, head-on from the same places,
    # the wall 1 m ahead that the image lies behind. Their beams stop at the wall, so none of
    # them looks through the image: only the wall in front of it says it is not there.
    readings = [_reading(0.05 * k, 0.0, 0.1 * k, 0.0, 3.0, sensor=5 + k) for k in range(2)]
    readings += [_reading(3.0 + 0.05 * k, 0.0, 0.1 * (k % 2) + 0.02 * k, 0.0, 1.0, k % 5)
                 for k in range(10)]
    method = EvidenceMethod(history_size=history, min_confidence=0.0, confidence_model=model)
    return method, readings


def _committed_confidence(history: int, model: ConfidenceModel | None) -> dict[int, float]:
    """The confidence of every reading's point in the global map of :func:`_image_then_wall`."""
    method, readings = _image_then_wall(history, model)
    method.add_many(ReadingBatch.from_readings(readings))
    points = method.finish()
    return dict(zip(points.reading_id.tolist(), points.confidence.tolist(), strict=True))


def test_an_echo_behind_a_wall_heard_after_it_is_judged_when_it_leaves() -> None:
    # The wall is established only after the image arrived, so the occlusion rule (on arrival)
    # cannot flag it; the image is judged when it leaves the history (10 arcs), 2 m behind
    # the wall.
    method, readings = _image_then_wall(history=10)
    model = _model(method)
    seen: dict[int, float] = {}

    def listener(history: object, slots: np.ndarray, est: object) -> None:
        column = method.features(slots)[:, CONFIDENCE_FEATURES.index("behind")]
        seen.update(zip(method.history.reading_id[slots].tolist(), column.tolist(),
                        strict=True))

    method.add_commit_listener(listener)  # type: ignore[arg-type]
    method.add_many(ReadingBatch.from_readings(readings[:10]))
    # Nothing has left the history yet: no arc has a depth.
    np.testing.assert_array_equal(model.behind, 0.0)
    method.add_many(ReadingBatch.from_readings(readings[10:]))
    method.finish()
    # 3 m less the nearest wall point on its axis, 1 m ahead within 2 cm sideways (at most
    # 3 - sqrt(1 + 0.02²) = 1.9998); the wall's echoes have nothing in front of them, and
    # those still in the history when the log ends are committed with 0.
    assert seen[0] == pytest.approx(2.0, abs=0.01)
    assert seen[1] == pytest.approx(2.0, abs=0.01)
    assert all(seen[k] == 0.0 for k in range(2, 12))
    assert ConfidenceModel().behind < 0.0


@pytest.mark.parametrize("history", [10, 40])
def test_behind_lowers_only_the_confidence_of_arcs_judged_as_they_leave(history: int) -> None:
    # With history 10 the image leaves (judged: its committed confidence falls by the weight
    # times its 2 m depth in logit); with 40 it is still in the history when the log ends and
    # keeps behind 0: the same confidence as with the weight 0. The wall's points never change.
    with_it = _committed_confidence(history, None)
    without = _committed_confidence(history, dataclasses.replace(ConfidenceModel(), behind=0.0))
    assert with_it.keys() == without.keys() == set(range(12))
    for k in range(2, 12):
        assert with_it[k] == without[k]
    for k in (0, 1):
        if history == 10:
            logit = math.log(without[k] / (1.0 - without[k]))
            lowered = 1.0 / (1.0 + math.exp(-(logit + 2.0 * ConfidenceModel().behind)))
            assert with_it[k] == pytest.approx(lowered, abs=2e-3)  # depth 1.9998 m, mature
        else:
            assert with_it[k] == without[k]


def test_the_live_map_does_not_depend_on_behind() -> None:
    # 6 m of the office tour (327 readings: the 60 rows of history are reused), read every 7
    # readings: the local map with the fitted weight is the one with the weight 0, bit for
    # bit, while the global maps differ (arcs judged as they leave: 32 with a depth).
    readings = run_simulation(Scenario("office", 1, max_length=6.0)).readings
    without = dataclasses.replace(ConfidenceModel(), behind=0.0)
    methods = [EvidenceMethod(history_size=60, confidence_model=model)
               for model in (ConfidenceModel(), without)]
    judged: list[float] = []
    model = _model(methods[0])
    methods[0].add_commit_listener(
        lambda history, slots, est: judged.extend(model.behind[slots].tolist()))
    for start in range(0, len(readings), 7):
        for method in methods:
            method.add_many(readings[start:start + 7])
        ours, before = (method.local_map() for method in methods)
        np.testing.assert_array_equal(ours.reading_id, before.reading_id)
        np.testing.assert_array_equal(ours.confidence, before.confidence)
        np.testing.assert_array_equal(ours.xy, before.xy)
    ours, before = (method.finish() for method in methods)
    assert sum(depth > 0.0 for depth in judged) > 10
    assert len(ours) < len(before)


def test_behind_is_judged_in_blocks_as_one_reading_at_a_time() -> None:
    # The image leaves the history inside a block of add_many, or on one add() of its own.
    points = []
    for blocks in (False, True):
        method, readings = _image_then_wall(history=10)
        if blocks:
            method.add_many(ReadingBatch.from_readings(readings))
        else:
            for reading in readings:
                method.add(reading)
        points.append(method.finish())
    np.testing.assert_array_equal(points[0].reading_id, points[1].reading_id)
    np.testing.assert_array_equal(points[0].confidence, points[1].confidence)


def test_split_arc_keeps_a_piece_with_an_honest_bound() -> None:
    # An arc whose middle is seen through head-on by a closer, narrower look keeps a piece.
    method = make_method("evidence", MethodConfig(min_confidence=0.0))
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 3.0))
    method.add(_reading(0.05, 0.5, 0.0, 0.0, 4.0, sensor=1))
    local = method.local_map()
    assert 0 in local.reading_id.tolist()
    row = local.reading_id.tolist().index(0)
    assert local.width[row] < PHI
    # The bound covers every surviving piece (the echo may be in either) plus half a bin: at
    # most the chord from one end of the beam to the other, widened by half a bin.
    assert 0.0 < local.max_error[row] <= 2.0 * 3.0 * math.sin((PHI + PHI / 48.0) / 2.0)


def test_without_keep_split_a_split_arc_leaves_the_map_as_in_the_paper() -> None:
    # The case above: the first arc's middle is carved, so two runs survive. The ablation's
    # switch drops it (the paper drops an arc carving splits); the newer, unsplit arc stays.
    maps = {}
    for keep in (True, False):
        method = EvidenceMethod(min_confidence=0.0, options=EvidenceOptions(keep_split=keep))
        method.add(_reading(0.0, 0.0, 0.0, 0.0, 3.0))
        method.add(_reading(0.05, 0.5, 0.0, 0.0, 4.0, sensor=1))
        model = method.models[0]
        assert isinstance(model, EvidenceModel)
        assert model.raw(method.history.slots()).runs.tolist() == [2.0, 1.0]
        maps[keep] = method.local_map().reading_id.tolist()
    assert maps == {True: [0, 1], False: [1]}


def test_evidence_never_grows_back_and_confidence_is_a_probability() -> None:
    rng = np.random.default_rng(3)
    method = make_method("evidence", MethodConfig(history_size=60))
    assert isinstance(method, EvidenceMethod)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    before = model.free.copy()
    for k in range(300):
        theta = 2 * math.pi * (k % 8) / 8
        method.add(_reading(0.01 * k, 0.01 * k, 0.0, theta, float(rng.uniform(0.5, 4.0)), k % 8))
        live = method.history.slots()[:-1]
        assert np.all(model.free[live] >= before[live] - 1e-12)  # carving never widens
        before = model.free.copy()
    local = method.local_map()
    assert np.all((local.confidence >= 0.5) & (local.confidence <= 1.0))


@pytest.mark.parametrize(("field", "value"), [("evidence_bins", 0), ("carve_probability", 1.0),
                                          ("min_confidence", -0.1), ("stamp_error", -1.0),
                                          ("stamp_heading_error", 2.0),
                                          ("stamp_heading_error", -0.1)])
def test_config_refuses_bad_evidence_parameters(field: str, value: float) -> None:
    with pytest.raises(ConfigError, match=field):
        MethodConfig(**{field: value})


def test_stamp_error_widens_every_bound() -> None:
    readings = [_reading(0.05 * k, 0.0, 0.05 * k, 0.0, 2.0, k) for k in range(4)]
    maps = []
    for stamp in (0.0, 0.1):
        method = make_method("evidence", MethodConfig(stamp_error=stamp))
        for reading in readings:
            method.add(reading)
        maps.append(method.local_map())
    np.testing.assert_allclose(maps[1].max_error, maps[0].max_error + 0.1)


def test_repeated_looks_from_one_place_are_not_distinct_viewpoints() -> None:
    # The same sensor from (almost) the same place hears the same range again: support, but not
    # from a distinct viewpoint; another sensor hearing it does confirm it.
    method = make_method("evidence")
    assert isinstance(method, EvidenceMethod)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0))
    method.add(_reading(0.05, 0.0, 0.01, 0.0, 2.0, sensor=0))
    first = int(method.history.slots()[0])
    assert model.support[first].max() > 0.0
    assert model.viewpoints[first] == 0.0
    method.add(_reading(0.1, 0.0, 0.1, 0.0, 2.0, sensor=1))
    assert model.viewpoints[first] > 0.0


def test_a_fresh_point_has_the_fresh_confidence() -> None:
    method = make_method("evidence")
    assert isinstance(method, EvidenceMethod)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0))
    fresh = method.confidence_model.fresh
    np.testing.assert_allclose(method.local_map().confidence, 1.0 / (1.0 + math.exp(-fresh)))


def _model(method: object) -> EvidenceModel:
    assert isinstance(method, EvidenceMethod)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    return model


def test_support_from_the_same_sensor_moved_is_not_support_from_another_sensor() -> None:
    # A wall at x = 2 heard by sensor 0 from two places 0.3 m apart (distinct viewpoints, but
    # one transducer: a systematic phantom repeats that way too), then by sensor 1.
    method = make_method("evidence")
    model = _model(method)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0))
    method.add(_reading(0.05, 0.0, 0.3, 0.0, 2.0, sensor=0))
    first = int(method.history.slots()[0])
    assert model.viewpoints[first] > 0.0
    assert model.others[first] == 0.0
    method.add(_reading(0.1, 0.0, 0.15, 0.0, 2.0, sensor=1))
    assert model.others[first] > 0.0
    # The confidence model prefers the arc another sensor confirmed (fitted weight > 0).
    assert method.confidence_model.others > 0.0


def test_through_is_the_support_of_the_surface_a_new_beam_passed() -> None:
    # A wall at x = 1 heard head-on by three sensors (each echo supports the others); an echo
    # at 2.5 m along the same line passed it, an echo at 0.8 m did not reach it.
    method = make_method("evidence")
    model = _model(method)
    for k, y in enumerate((0.0, 0.05, -0.05)):
        method.add(_reading(0.05 * k, 0.0, y, 0.0, 1.0, sensor=k))
    wall_support = model.support[method.history.slots()].max()
    method.add(_reading(0.2, 0.0, 0.02, 0.0, 2.5, sensor=3))
    behind = int(method.history.slots()[-1])
    assert model.through[behind] > 0.5 * wall_support
    method.add(_reading(0.25, 0.0, -0.02, 0.0, 0.8, sensor=4))
    short = int(method.history.slots()[-1])
    assert model.through[short] == 0.0


def _phantom_and_oblique_looks(transmission: bool, *, grazing: bool) -> tuple[float, float]:
    """A phantom arc at 1 m along +x from the origin (sensor 0), then two other sensors'
    echoes that confirm a surface beyond it, then two beams that pass it obliquely (45°, or
    along +y when ``grazing``) and hear that surface. Returns the free evidence of the
    phantom's middle bin and the threshold."""
    method = EvidenceMethod(min_confidence=0.0, options=EvidenceOptions(transmission=transmission))
    model = _model(method)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 1.0, sensor=0))
    if grazing:
        origins, heading, far = [(1.0, -2.0), (1.05, -2.0)], math.pi / 2, (1.0, 1.0)
    else:
        origins, heading, far = [(-0.5, -1.5), (-0.45, -1.55)], math.pi / 4, (1.97, 0.97)
    # Two sensors beyond the phantom hear the far surface head-on (along the beams' heading).
    for k, back in enumerate((0.8, 0.9)):
        ox = far[0] - back * math.cos(heading) + 0.03 * k
        oy = far[1] - back * math.sin(heading)
        method.add(_reading(0.1 + 0.05 * k, ox, oy, heading, back, sensor=5 + k))
    for k, (ox, oy) in enumerate(origins):
        r = math.hypot(far[0] - ox, far[1] - oy)
        method.add(_reading(0.3 + 0.05 * k, ox, oy, heading, r, sensor=1 + k))
    first = int(method.history.slots()[0])
    return float(model.free[first, model.bins // 2]), model.threshold


def test_an_oblique_look_through_a_phantom_at_a_confirmed_echo_carves_it() -> None:
    # At 45° the phantom's implied surface returns nothing to the passing beams (specular), so
    # their incidence evidence is weak; but their echo beyond it is confirmed by other
    # sensors, so the sound went through: transmission evidence carves the phantom.
    with_it, threshold = _phantom_and_oblique_looks(True, grazing=False)
    without, _ = _phantom_and_oblique_looks(False, grazing=False)
    assert without < threshold
    assert with_it >= threshold


def test_a_beam_running_along_a_wall_does_not_carve_it_by_transmission() -> None:
    # The same, with beams running along the wall the arc implies (γ near 90°): a wall edge-on
    # does not block the beam, so its confirmed echo beyond says nothing about the wall.
    with_it, threshold = _phantom_and_oblique_looks(True, grazing=True)
    without, _ = _phantom_and_oblique_looks(False, grazing=True)
    assert with_it < threshold
    assert with_it == pytest.approx(without, abs=0.05 * threshold)


def test_blocks_of_readings_give_the_maps_of_one_reading_at_a_time() -> None:
    # add_many runs the evidence kernel once per block; arcs commit between blocks with the
    # confidence (and its maturity clock) that add() per reading gives them.
    rng = np.random.default_rng(7)
    n = 400
    t = np.cumsum(rng.uniform(0.01, 0.05, n))
    sensor = np.arange(n) % 8
    theta = 2 * math.pi * sensor / 8
    xs = 0.01 * np.arange(n)
    ranges = rng.uniform(0.5, 4.0, n)
    readings = [Reading(t=float(t[k]), sensor=int(sensor[k]), x=float(xs[k]), y=0.0,
                        theta=float(theta[k]), range=float(ranges[k]), beam_width=PHI)
                for k in range(n)]
    one = make_method("evidence", MethodConfig(history_size=40))
    for reading in readings:
        one.add(reading)
    blocks = make_method("evidence", MethodConfig(history_size=40))
    for start in range(0, n, 97):
        blocks.add_many(ReadingBatch.from_readings(readings[start : start + 97]),
                        first_id=start)
    a, b = one.finish(), blocks.finish()
    np.testing.assert_array_equal(a.reading_id, b.reading_id)
    np.testing.assert_array_equal(a.xy, b.xy)
    np.testing.assert_array_equal(a.confidence, b.confidence)


def test_a_split_arc_keeps_the_piece_a_crossing_echo_locates_not_a_tangent_one() -> None:
    # An arc at 3 m whose middle a head-on look carves (two pieces at the beam's edges). The
    # upper piece is supported by the same sensor one step along that piece's direction (its
    # circle touches the arc there: the same range again says nothing about the bearing); the
    # lower piece by another sensor's echo crossing the arc at 55°. ATM is off, so only the
    # localised support can tell them apart.
    method = EvidenceMethod(min_confidence=0.0, options=EvidenceOptions(atm=False))
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 3.0, sensor=0))
    method.add(_reading(0.05, 0.5, 0.0, 0.0, 4.0, sensor=1))
    up = math.radians(10.5)
    method.add(_reading(0.1, 0.3 * math.cos(up), 0.3 * math.sin(up), up, 2.7, sensor=0))
    low = (3.0 * math.cos(-up), 3.0 * math.sin(-up))
    ox, oy = 1.5, -2.0
    method.add(_reading(0.15, ox, oy, math.atan2(low[1] - oy, low[0] - ox),
                        math.hypot(low[0] - ox, low[1] - oy), sensor=2))
    model = _model(method)
    first = int(method.history.slots()[0])
    carved = model.free[first] >= model.threshold
    assert carved[model.bins // 2]  # split in two
    assert not carved[0]
    assert not carved[-1]
    assert model.support[first, -1] > model.support[first, 0]  # the tangent one is louder
    local = method.local_map()
    row = local.reading_id.tolist().index(0)
    assert local.xy[row, 1] < 0.0  # the point is on the lower, located piece


def _wall_with_crossings(located: bool, *, carve_lower: bool, posterior: bool = True,
                         uncut: bool = False) -> tuple[np.ndarray, float]:
    """A wall at x = 2 heard head-on from the origin (sensor 0); optionally its lower half seen
    through head-on by sensor 3; then two other sensors' echoes crossing the arc at a wide
    angle near bearing 0.15. Returns the point of the first echo and its bound."""
    options = EvidenceOptions(atm=False, located_placement=located,
                              posterior_placement=posterior, uncut_posterior=uncut)
    method = EvidenceMethod(min_confidence=0.0, options=options)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0))
    if carve_lower:
        method.add(_reading(0.05, 0.3, -0.35, 0.0, 4.0, sensor=3))
    target = (2.0 * math.cos(0.15), 2.0 * math.sin(0.15))
    for k, (ox, oy) in enumerate(((0.8, -1.2), (0.9, -1.1))):
        method.add(_reading(0.1 + 0.05 * k, ox, oy, math.atan2(target[1] - oy, target[0] - ox),
                            math.hypot(target[0] - ox, target[1] - oy), sensor=1 + k))
    local = method.local_map()
    row = local.reading_id.tolist().index(0)
    return local.xy[row], float(local.max_error[row])


@pytest.mark.parametrize("posterior", [True, False])
def test_a_point_goes_where_crossing_echoes_locate_the_surface(posterior: bool) -> None:
    # Once evidence has cut the arc (its lower half seen through), the point moves to where
    # the crossing echoes put the surface, not the middle of what is left; the bound still
    # covers the far end of the surviving piece from there.
    moved, bound = _wall_with_crossings(True, carve_lower=True, posterior=posterior)
    middle, _ = _wall_with_crossings(False, carve_lower=True)
    assert moved[1] == pytest.approx(2.0 * math.sin(0.15), abs=0.04)
    assert moved[1] - middle[1] > 0.1  # the run's middle is lower (its lower end was cut)
    # The bound reaches at least from the point to the lower end of the piece left, which
    # lies below the middle.
    below = math.atan2(moved[1], moved[0]) - math.atan2(middle[1], middle[0])
    assert bound >= 2.0 * 2.0 * math.sin(below) - 1e-9


def test_an_uncut_beam_keeps_its_point_in_the_middle() -> None:
    # Nothing has seen through any of it: crossings on a whole beam may be ghosts (two jambs'
    # circles meet in the doorway), so the point stays at the beam's middle (eq. 3.6), with
    # the posterior placement (the default) or the one before it.
    for posterior in (True, False):
        point, _ = _wall_with_crossings(True, carve_lower=False, posterior=posterior)
        assert abs(point[1]) < 0.02


def test_asked_to_an_uncut_beam_goes_where_crossing_echoes_locate_the_surface() -> None:
    # with_uncut_posterior: every bin's miss factor exp(-F) is 1, so the posterior is the
    # localised support alone, near bearing 0.15 (the crossings), and the bound reaches the
    # beam's far edge (-11.25°) from there, plus half a bin.
    point, bound = _wall_with_crossings(True, carve_lower=False, uncut=True)
    assert point[1] == pytest.approx(2.0 * math.sin(0.15), abs=0.04)
    bearing = math.atan2(point[1], point[0])
    far = bearing + math.radians(11.25) + 0.5 * math.radians(22.5) / 24
    assert bound == pytest.approx(2.0 * 2.0 * math.sin(0.5 * far), rel=1e-9)


def test_a_points_confidence_does_not_depend_on_the_rows_beside_it() -> None:
    # Arcs are committed in blocks whose size depends on when the map or the measures are
    # read; a matrix product sums in an order that depends on the block, which moved
    # confidences in their last digits (and so the process output).
    model = ConfidenceModel()
    rng = np.random.default_rng(3)
    features = rng.uniform(0.0, 3.0, (1001, len(model.weights())))
    maturity = rng.uniform(0.0, 1.0, 1001)
    together = model.confidence(features, maturity)
    alone = np.concatenate([model.confidence(features[k : k + 1], maturity[k : k + 1])
                            for k in range(len(features))])
    np.testing.assert_array_equal(together, alone)


def _post_ring(n: int) -> list[Reading]:
    # Arcs from a ring of origins all around a central post: they cross each other pairwise in
    # their beams, so the busiest arc keeps far more crossings than a narrow store holds.
    rng = np.random.default_rng(4)
    angle = rng.uniform(0.0, 2.0 * math.pi, n)
    dist = rng.uniform(1.0, 1.5, n)
    return [Reading(0.1 * i, i % 16, float(dist[i] * math.cos(angle[i])),
                    float(dist[i] * math.sin(angle[i])), float(angle[i] + math.pi),
                    float(dist[i]), PHI) for i in range(n)]


@pytest.mark.parametrize("blocks", [False, True])
def test_the_crossing_store_grows_on_demand_and_keeps_every_crossing(blocks: bool) -> None:
    # A store that starts at 2 columns must grow and give, crossing for crossing and bit for
    # bit, what a store with room for every crossing an arc can have (4 (n - 1)) gives.
    n = 120
    readings = _post_ring(n)
    runs = []
    for initial in (2, 4 * (n - 1)):
        method = EvidenceMethod(history_size=n, beam_width=PHI)
        model = method.models[0]
        assert isinstance(model, EvidenceModel)
        model.bearings = np.zeros((model.bearings.shape[0], initial), dtype=np.float32)
        if blocks:
            for start in range(0, n, 50):
                method.add_many(ReadingBatch.from_readings(readings[start : start + 50]),
                                first_id=start)
        else:
            for reading in readings:
                method.add(reading)
        assert model.counts.max() <= model.bearings.shape[1]
        runs.append((model, method.local_map(), method.finish()))
    (small, small_local, small_map), (full, full_local, full_map) = runs
    assert small.bearings.shape[1] > 2  # it grew
    assert full.bearings.shape[1] == 4 * (n - 1)  # it did not
    assert full.counts.max() > 2
    np.testing.assert_array_equal(small.counts, full.counts)
    for slot in np.flatnonzero(full.counts):
        c = full.counts[slot]
        np.testing.assert_array_equal(small.bearings[slot, :c], full.bearings[slot, :c])
    for field in ("reading_id", "xy", "width", "max_error", "source", "confidence"):
        np.testing.assert_array_equal(getattr(small_local, field), getattr(full_local, field))
        np.testing.assert_array_equal(getattr(small_map, field), getattr(full_map, field))


def test_a_long_history_starts_with_a_narrow_store() -> None:
    # History 10,000: room for every crossing would take 20,000 x 39,996 float32 (3.2 GB).
    method = make_method("evidence", MethodConfig(history_size=10_000))
    method.add_many(ReadingBatch.from_readings(_post_ring(60)))
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    assert model.bearings.shape == (20_000, 64)  # 32 columns, doubled once
    assert 32 < model.counts.max() <= 64


def test_a_store_beyond_the_memory_limit_stops_the_method(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # 256 bytes hold 256 // (4 * 240) = 0 float32 columns of 240 rows, so the store's first
    # growth (a row with 3 crossings in 2 columns) must fail.
    monkeypatch.setattr(atm_module, "MAX_ATM_STATE_BYTES", 256)
    n = 120
    method = EvidenceMethod(history_size=n, beam_width=PHI)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    model.bearings = np.zeros((2 * n, 2), dtype=np.float32)
    readings = _post_ring(n)
    method.add_many(ReadingBatch.from_readings(readings[:3]))
    method.local_map()  # a map from before the failure is cached
    with pytest.raises(CrossingStoreError,
                       match=r"^evidence carving's crossing store would take"):
        method.add_many(ReadingBatch.from_readings(readings[3:]), first_id=3)
    assert issubclass(CrossingStoreError, SonarcarveError)
    assert model.counts.max() <= 2  # no row claims a crossing past the store's end
    # Crossings were lost: the method refuses to go on rather than map from them.
    stored = method.history.appended
    with pytest.raises(CrossingStoreError):
        method.add(readings[-1]._replace(t=100.0))
    with pytest.raises(CrossingStoreError):
        method.add(readings[-1]._replace(t=101.0, range=math.inf, max_range=5.0))
    with pytest.raises(CrossingStoreError):
        method.add_many(ReadingBatch.from_readings([readings[-1]._replace(t=102.0)]))
    assert method.history.appended == stored  # refused before it was stored
    slots = method.history.slots()
    for read in (method.local_map, method.measures, method.global_map, method.finish,
                 lambda: method.estimates(slots), lambda: model.raw(slots)):
        with pytest.raises(CrossingStoreError, match=r"^evidence carving's crossing store"):
            read()


def test_from_weights_takes_the_fields_default_maturity_time() -> None:
    weights = np.arange(len(evidence_module.CONFIDENCE_FEATURES), dtype=float)
    (default,) = (f.default for f in dataclasses.fields(ConfidenceModel)
                  if f.name == "maturity_time")
    for model in (ConfidenceModel.from_weights(-1.0, weights, 2.5),
                  ConfidenceModel.from_weights(-1.0, weights, 2.5, maturity_time=None)):
        assert model.maturity_time == default
        assert (model.intercept, model.fresh) == (-1.0, 2.5)
        np.testing.assert_array_equal(model.weights(), weights)
    assert ConfidenceModel.from_weights(-1.0, weights, 2.5, 0.75).maturity_time == 0.75


def _approach(t0: float, n: int, sensor: int = 20, sideways: bool = False) -> list[Reading]:
    # One sensor facing +x hearing a wall at x = 5, a reading every 0.5 s. Head-on: origins
    # (0.2 k, 30), ranges 5 - 0.2 k: each pair repeats (the circles touch at (5, 30), on the
    # axis). Sideways: origins (0, 30 + 0.2 k), ranges 5: no pair repeats (origins 0.2 k apart,
    # the range unchanged: |0.2 k - 0| > ε).
    return [Reading(t=t0 + 0.5 * k, sensor=sensor, x=0.0 if sideways else 0.2 * k,
                    y=30.0 + (0.2 * k if sideways else 0.0), theta=0.0,
                    range=5.0 if sideways else 5.0 - 0.2 * k, beam_width=PHI)
            for k in range(n)]


def _ring_readings(n: int, seed: int) -> list[Reading]:
    # Eight sensors on a robot stepping along x, random ranges: supports, carves, crossings.
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.01, 0.05, n))
    sensor = np.arange(n) % 8
    return [Reading(t=float(t[k]), sensor=int(sensor[k]), x=0.01 * k, y=0.0,
                    theta=2 * math.pi * int(sensor[k]) / 8,
                    range=float(rng.uniform(0.5, 4.0)), beam_width=PHI) for k in range(n)]


def test_features_codes_and_confidence_are_the_numpy_formulas_bit_for_bit() -> None:
    # The compiled per-row passes must give exactly what the elementwise numpy formulas of
    # the features, the Table I/source/fate codes and the logistic model give (the oracle).
    method = make_method("evidence", MethodConfig(history_size=120))
    assert isinstance(method, EvidenceMethod)
    post = [r._replace(t=20.0 + r.t) for r in _post_ring(60)]  # crossings
    method.add_many(ReadingBatch.from_readings(_ring_readings(300, 11) + post
                                               + _approach(40.0, 5)))  # repeats
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    h = method.history
    slots = h.slots()
    raw = model.raw(slots)
    has, _, width, _, support, is_atm, crossings, free, runs, _ = raw
    maturity = method.maturity(slots)
    expected = np.column_stack([
        np.minimum(support, 3.0), np.minimum(model.viewpoints[slots], 3.0),
        np.minimum(crossings, 3.0), free,
        np.minimum(model.looked[slots] / model.threshold, 3.0),
        np.minimum(np.maximum(runs - 1.0, 0.0), 3.0), model.occluded[slots],
        (support <= 0.0) * maturity, h.r[slots], width / h.beam_width[slots],
        np.minimum(model.others[slots] / np.maximum(
            model.covering[slots] / method.confidence_model.looks_per_support, 1.0), 1.0),
        np.minimum(model.through[slots], 3.0),
        model.repeated[slots], np.minimum(model.behind[slots], 3.0),
        np.where(model.covering[slots] > 0.0, 0.0, 1.0)])
    features = method.features(slots, raw)
    np.testing.assert_array_equal(features, expected)
    # No column constant, but behind: 0 for every arc in the history (judged as it leaves), and
    # alone: 0 here, every axis point held by another sensor's beam (a beam holds a point at any
    # range; both values: tests/geometry/test_watch.py).
    behind = CONFIDENCE_FEATURES.index("behind")
    alone = CONFIDENCE_FEATURES.index("alone")
    assert all(len(np.unique(column)) > 1
               for column in np.delete(features, [behind, alone], axis=1).T)
    np.testing.assert_array_equal(features[:, alone], 0.0)
    np.testing.assert_array_equal(features[:, behind], 0.0)
    cm = method.confidence_model
    fitted = np.full(len(slots), cm.intercept)
    for column, weight in zip(expected.T, cm.weights(), strict=True):
        fitted = fitted + column * weight
    logistic = 1.0 / (1.0 + np.exp(-(cm.fresh + maturity * (fitted - cm.fresh))))
    np.testing.assert_array_equal(cm.confidence(features, maturity), logistic)
    est = model.estimates(slots)
    processed = model.touched[slots] | (model.counts[slots] > 0) | (model.status[slots] != 0)
    source = np.where(is_atm, 2, np.where(width < h.beam_width[slots] - 1e-12, 1, 0))
    np.testing.assert_array_equal(est.processed, processed)
    np.testing.assert_array_equal(est.source, source)
    np.testing.assert_array_equal(est.fate, np.where(has, 0, 2))
    assert set(source.tolist()) == {0, 1, 2}


def test_confidence_refuses_features_of_the_wrong_width() -> None:
    model = ConfidenceModel()
    with pytest.raises(ConfigError, match="features must have shape"):
        model.confidence(np.zeros((3, len(model.weights()) - 1)))


def _repeat_only_run(sideways: bool, repeat_weight: float) -> tuple[np.ndarray, Any]:
    # A model that looks at the repeat alone: σ(-2 + w repeated), every arc mature after 1 ms;
    # the newest arc, 0 s old when the log ends, has the fresh confidence σ(-1) < 0.5.
    weights = np.zeros(len(evidence_module.CONFIDENCE_FEATURES))
    weights[evidence_module.CONFIDENCE_FEATURES.index("repeated")] = repeat_weight
    model = ConfidenceModel.from_weights(-2.0, weights, fresh=-1.0, maturity_time=1e-3)
    method = EvidenceMethod(confidence_model=model)
    method.add_many(ReadingBatch.from_readings(_approach(0.0, 8, sideways=sideways)))
    return _model(method).repeated[method.history.slots()].copy(), method.finish()


def test_a_sensor_driving_at_a_wall_has_repeats_and_they_raise_its_confidence() -> None:
    # Driving at the wall every echo repeats another: all 7 mature ones kept at σ(-2 + 4).
    repeated, points = _repeat_only_run(sideways=False, repeat_weight=4.0)
    np.testing.assert_array_equal(repeated, 1.0)
    assert len(points) == 7
    np.testing.assert_allclose(points.confidence, 1.0 / (1.0 + math.exp(-2.0)), rtol=1e-12)
    # Driving past it no echo repeats: all at σ(-2) < 0.5, none kept.
    repeated, points = _repeat_only_run(sideways=True, repeat_weight=4.0)
    np.testing.assert_array_equal(repeated, 0.0)
    assert len(points) == 0
    # The repeats with a weight of 0 (the feature off): none kept either.
    assert len(_repeat_only_run(sideways=False, repeat_weight=0.0)[1]) == 0


def test_repeats_give_the_same_confidence_in_blocks_and_one_reading_at_a_time() -> None:
    # The repeat of an arc can arrive in its own block or a later one, its partner can have
    # wrapped in the ring: every arc must leave with the features (and so the confidence)
    # that one add() per reading gives it. Two sensors drive at walls among random echoes.
    readings = sorted(_ring_readings(400, 5) + _approach(0.0, 20, sensor=20)
                      + _approach(3.0, 20, sensor=21), key=lambda r: r.t)
    committed = []
    for blocks in (1, 13, 97):
        method = make_method("evidence", MethodConfig(history_size=40))
        assert isinstance(method, EvidenceMethod)
        rows: list[np.ndarray] = []
        method.add_commit_listener(lambda _h, slots, _e, m=method, rows=rows: rows.append(
            m.features(slots)))
        for start in range(0, len(readings), blocks):
            method.add_many(ReadingBatch.from_readings(readings[start : start + blocks]),
                            first_id=start)
        points = method.finish()
        committed.append((np.vstack(rows), points))
    column = evidence_module.CONFIDENCE_FEATURES.index("repeated")
    one, _ = committed[0]
    assert 0 < np.count_nonzero(one[:, column]) < len(one)  # the case holds repeats
    for features, points in committed[1:]:
        np.testing.assert_array_equal(features, one)
        np.testing.assert_array_equal(points.reading_id, committed[0][1].reading_id)
        np.testing.assert_array_equal(points.confidence, committed[0][1].confidence)


@pytest.mark.parametrize("value", [0, -1, 1.5, True, "3"])
def test_min_atm_crossings_must_be_a_whole_number_of_at_least_one(value: object) -> None:
    with pytest.raises(ConfigError, match="min_atm_crossings"):
        EvidenceOptions(min_atm_crossings=value)  # type: ignore[arg-type]


def _crossed_wall(crossings: int, **options: Any) -> tuple[str, float]:
    """A wall at x = 2 heard head-on from the origin (sensor 0), then ``crossings`` other
    sensors' echoes through the wall point at bearing 0.12, each crossing the first arc at a
    wide angle (one ATM crossing each). Returns the first echo's point source and bound."""
    method = EvidenceMethod(min_confidence=0.0, options=EvidenceOptions(**options))
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0))
    target = (2.0 * math.cos(0.12), 2.0 * math.sin(0.12))
    for k, (ox, oy) in enumerate(((0.8, -1.2), (0.9, -1.1), (0.7, 1.3))[:crossings]):
        method.add(_reading(0.1 + 0.05 * k, ox, oy, math.atan2(target[1] - oy, target[0] - ox),
                            math.hypot(target[0] - ox, target[1] - oy), sensor=1 + k))
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    assert int(model.counts[int(method.history.slots()[0])]) == crossings
    local = method.local_map()
    row = local.reading_id.tolist().index(0)
    return PointSource(int(local.source[row])).label, float(local.max_error[row])


def test_two_crossings_do_not_place_the_point_by_default_three_do() -> None:
    # ATM's median of two crossings is their mean, which one ghost moves anywhere: by default
    # (min_atm_crossings 3) the uncut beam keeps its middle; from three, ATM's median.
    assert _crossed_wall(2)[0] == "centerline"
    assert _crossed_wall(3)[0] == "atm"


def test_min_atm_crossings_reaches_the_placement() -> None:
    # Asked for 1 (the rule before), two crossings are enough; asked for 4, three are not.
    assert _crossed_wall(2, min_atm_crossings=1)[0] == "atm"
    assert _crossed_wall(3, min_atm_crossings=4)[0] == "centerline"


def test_the_options_reach_the_model_unchanged() -> None:
    options = EvidenceOptions(posterior_placement=False, uncut_posterior=True,
                              located_placement=False, min_atm_crossings=5)
    assert _model(EvidenceMethod(options=options)).options is options


def test_the_models_defaults_are_the_methods() -> None:
    # EvidenceModel is public: built on its own it must place points as the method does.
    alone = EvidenceModel(SonarHistory(10), 24, 0.05, 0.8, 0.35, 0.0254)
    assert alone.options == _model(EvidenceMethod()).options == EvidenceOptions()
    assert EvidenceOptions().min_atm_crossings == 3
    assert EvidenceOptions().posterior_placement is True
    assert EvidenceOptions().uncut_posterior is False


def test_widening_the_range_tolerance_leaves_the_support_tolerance_at_5_cm() -> None:
    # Measured (SensorModel's docstring): a support band as wide as a widened ε costs spurious
    # removal, so ε_s stays where it is when a user widens ε for a noisy sensor.
    for tolerance in (0.05, 0.10, 0.15):
        assert _model(EvidenceMethod(range_tolerance=tolerance)).params.support_tolerance == 0.05


def test_an_echo_read_8_cm_long_does_not_support_the_wall_when_epsilon_is_10_cm() -> None:
    # A wall at x = 2 heard head-on by sensor 0, then by sensor 1 beside it reading 8 cm long:
    # with ε = 10 cm its free space ends 2 cm short of the wall (no free evidence) and its echo
    # lies beyond ε_s = 5 cm of it (no support); an ε_s following ε would support the wall.
    method = EvidenceMethod(range_tolerance=0.10)
    model = _model(method)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0, sensor=0))
    method.add(_reading(0.05, 0.0, 0.05, 0.0, 2.08, sensor=1))
    first = int(method.history.slots()[0])
    assert model.support[first].max() == 0.0
    assert model.free[first].max() == 0.0


def test_the_kernels_get_each_bundles_arrays_in_field_order() -> None:
    """The model hands the kernels its arrays as plain tuples (``arrays.plain``), which the
    kernels name by position: a swapped pair would weigh the wrong arrays without an error.
    Every field is the model's (or the history's) attribute of that name; two scratch
    arrays keep their older attribute names."""
    method = EvidenceMethod(history_size=10)
    model = method.models[0]
    assert isinstance(model, EvidenceModel)
    state, scratch, _, _ = model._bundles()
    bundles = (ReadingRows, ArcShapes, BinEvidence, ArcEvidence, CrossingArrays)
    assert EvidenceState._fields == ("readings", "shapes", "evidence", "arcs", "crossings")
    sources = (method.history, model, model, model, model)
    for bundle, part, source in zip(bundles, state, sources, strict=True):
        assert len(part) == len(bundle._fields)
        for field, array in zip(bundle._fields, part, strict=True):
            assert array is getattr(source, field), field
    renamed = {"entries": "scratch", "depth": "behind_scratch"}
    for field, array in zip(AddScratch._fields, scratch, strict=True):
        assert array is getattr(model, renamed.get(field, field)), field
