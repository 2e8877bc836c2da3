"""The weighing kernel's layout (cull of all rows at once, then three passes over an arc's
bins) against the one loop it replaced, bit for bit (the oracle below is that loop, in
Python, calling the kernel's own compiled helpers where this change left them alone; the bin
of a sine, which the change reworked, is searched here in Python)."""

from __future__ import annotations

import bisect
import copy
import math
from typing import Any

import numpy as np
import pytest

from sonarcarve.geometry.bounds import arc_bounding_circle
from sonarcarve.geometry.evidence import EVIDENCE_ALIVE, EVIDENCE_CARVED, evidence_add
from sonarcarve.geometry.evidence.arrays import ArcShapes, CrossingArrays, ReadingRows
from sonarcarve.geometry.evidence.beam import new_beam
from sonarcarve.geometry.evidence.crossings import transversal_crossings
from sonarcarve.geometry.evidence.occlusion import occlude_behind
from sonarcarve.geometry.evidence.transmission import weigh_transmission
from sonarcarve.lab.scenarios import Scenario, run_simulation
from sonarcarve.methods import evidence as evidence_method
from sonarcarve.methods.evidence import EvidenceMethod, EvidenceModel, SensorModel
from sonarcarve.sim.simulate import simulate


def _bin_of_sine(sine: float, edges: Any, bins: int, scale: float) -> int:
    """The largest ``k`` in ``1 .. K - 1`` with ``edges[k] <= sine``, else 0 (NaN: 0): the
    binary search the kernel's guess-and-step replaced (``scale`` is the kernel's hint)."""
    if math.isnan(sine):
        return 0
    return bisect.bisect_right([float(e) for e in edges[1:bins]], sine)


def _incidence(cos_gamma: float, cos_full: float, cos_zero: float, rough: float) -> float:
    if cos_gamma >= cos_full:
        return 1.0
    if cos_gamma <= cos_zero:
        return rough
    return rough + (1.0 - rough) * (cos_gamma - cos_zero) / (cos_full - cos_zero)


def _beyond(cx: float, cy: float, rho: float, beam: Any) -> bool:
    dcx = cx - beam.x
    dcy = cy - beam.y
    if dcx * dcx + dcy * dcy >= (beam.reach + rho) * (beam.reach + rho):
        return True
    below = beam.edge1_x * dcy - beam.edge1_y * dcx < -rho
    return bool(below or dcx * beam.edge2_y - dcy * beam.edge2_x < -rho)


def _init_new_arc(m: EvidenceModel, slot: int) -> None:
    h = m.history
    bins = m.bins
    xj, yj, rj = h.x[slot], h.y[slot], h.r[slot]
    half_j = 0.5 * h.beam_width[slot]
    step_j = h.beam_width[slot] / bins
    m.cos_axis[slot] = math.cos(h.theta[slot])
    m.sin_axis[slot] = math.sin(h.theta[slot])
    m.cos_half[slot] = math.cos(half_j)
    for k in range(bins):
        tau = h.theta[slot] - half_j + (k + 0.5) * step_j
        m.ex[slot, k] = math.cos(tau)
        m.ey[slot, k] = math.sin(tau)
        m.bx[slot, k] = xj + rj * m.ex[slot, k]
        m.by[slot, k] = yj + rj * m.ey[slot, k]
    m.free[slot] = m.support[slot] = m.located[slot] = 0.0
    m.circle[:, slot] = arc_bounding_circle(xj, yj, rj, h.theta[slot] - half_j,
                                            h.theta[slot] + half_j)
    m.status[slot] = EVIDENCE_ALIVE
    m.touched[slot] = False
    m.occluded[slot] = m.viewpoints[slot] = m.looked[slot] = m.others[slot] = 0.0
    if m.trans[2 * bins + 1] != h.beam_width[slot]:
        for k in range(bins + 1):
            m.trans[bins + k] = math.sin(-half_j + k * step_j)
        m.trans[2 * bins + 1] = h.beam_width[slot]
        m.trans[2 * bins + 2] = bins / (m.trans[2 * bins] - m.trans[bins])
    m.trans[:bins] = 0.0
    m.counts[slot] = 0


def _one_loop_add(m: EvidenceModel, slot: int, older: list[int]) -> int:
    """evidence_add as one loop over the arcs and their bins (before the passes); returns the
    spilled rows."""
    h = m.history
    bins = m.bins
    params = m.params
    _init_new_arc(m, slot)
    readings = ReadingRows(h.x, h.y, h.r, h.theta, h.beam_width, h.sensor)
    shapes = ArcShapes(m.cos_axis, m.sin_axis, m.cos_half, m.circle, m.bx, m.by, m.ex, m.ey)
    beam = new_beam(slot, readings, shapes, params)
    edges = m.trans[bins : 2 * bins + 1]
    scale = m.trans[2 * bins + 2]
    threshold = params.threshold
    xj, yj = h.x[slot], h.y[slot]
    cj, sj = beam.cos_axis, beam.sin_axis
    n_passed = spilled = occluding = 0
    top_through = 0.0
    for i in older:
        if m.status[i] != EVIDENCE_ALIVE or _beyond(*m.circle[:, i], beam):
            continue
        if m.options.atm:
            _, spilled = transversal_crossings(
                slot, i, readings, shapes, params.cos_psi,
                CrossingArrays(m.bearings, m.counts, m.spill), spilled)
        ox, oy = h.x[i] - xj, h.y[i] - yj
        other = h.sensor[i] != h.sensor[slot]
        distinct = other or ox * ox + oy * oy >= beam.spacing2
        half_bin_arc = 0.5 * (h.beam_width[i] / bins) * h.r[i]
        alive_bins = 0
        top_support = top_looked = 0.0
        for k in range(bins):
            f = m.free[i, k]
            if f >= threshold:
                continue
            vx, vy = m.bx[i, k] - xj, m.by[i, k] - yj
            d2 = vx * vx + vy * vy
            along = vx * cj + vy * sj
            if d2 >= beam.reach2 or along <= 0.0 or along * along < d2 * beam.cos_half2:
                alive_bins += 1
                continue
            d = math.sqrt(d2)
            if d >= beam.free_r and abs(d - beam.r) > params.support_tolerance:
                alive_bins += 1
                continue
            inv_d = 1.0 / d
            sine = (cj * vy - sj * vx) * inv_d
            u = min(abs(sine) / beam.sin_half, 1.0)
            p_beam = params.max_detect * (1.0 - beam.edge_loss * u * u) / (
                1.0 + d * beam.inv_scale)
            cos_gamma = abs(m.ex[i, k] * vx + m.ey[i, k] * vy) * inv_d
            p = p_beam * _incidence(cos_gamma, beam.cos_full, beam.cos_zero, params.rough)
            if d < beam.free_r:
                m.touched[i] = True
                if distinct:
                    top_looked = max(top_looked, p_beam)
                established = m.support[i, k] >= params.establish and f < 0.5 * threshold
                if d < beam.free_r - params.tolerance:
                    top_through = max(top_through, m.support[i, k])
                if established and d < beam.free_r - params.tolerance:
                    occluding += occlude_behind(slot, math.atan2(cj * vy - sj * vx, along),
                                                 half_bin_arc / d, beam, m.free, threshold)
                    m.touched[slot] = True
                factor = params.protect if established else 1.0
                w = -math.log1p(-p) * factor
                f += w
                m.free[i, k] = f
                if f < threshold:
                    alive_bins += 1
                    if params.transmit > 0.0 and p < p_beam:
                        m.passed[n_passed] = (i, k, _bin_of_sine(sine, edges, bins, scale),
                                              p_beam * cos_gamma, factor, w)
                        n_passed += 1
            else:
                alive_bins += 1
                m.touched[i] = m.touched[slot] = True
                top_support = max(top_support, p)
                m.support[i, k] += p
                kb = _bin_of_sine(sine, edges, bins, scale)
                m.support[slot, kb] += p
                loc = p * abs(m.ex[i, k] * vy - m.ey[i, k] * vx) * inv_d
                m.located[i, k] += loc
                m.located[slot, kb] += loc
                if other:
                    m.trans[kb] += p
        if distinct:
            m.viewpoints[i] += top_support
            m.viewpoints[slot] += top_support
            if top_looked > 0.0:
                m.looked[i] += -math.log1p(-top_looked)
        if other:
            m.others[i] += top_support
            m.others[slot] += top_support
        if alive_bins == 0:
            m.status[i] = EVIDENCE_CARVED
    m.occluded[slot] = occluding / bins
    m.through[slot] = top_through
    weigh_transmission(slot, m.passed, n_passed, m.trans, m.free, m.status, params)
    if occluding >= bins:
        m.status[slot] = EVIDENCE_CARVED
    return spilled


def _one_loop_add_many(m: EvidenceModel, first: int, count: int) -> None:
    h = m.history
    storage = h.storage_size
    for sequence in range(first, first + count):
        live = min(sequence + 1, h.capacity)
        start = sequence + 1 - live
        older = [(start + q) % storage for q in range(live - 1)]
        spilled = _one_loop_add(m, sequence % storage, older)
        if spilled:
            m._take_spill(spilled)


STATE = ("free", "support", "located", "status", "touched", "occluded", "viewpoints", "looked",
         "others", "through", "repeated", "watched", "counts", "bearings", "bx", "by", "ex", "ey",
         "circle")


def _assert_same_state(fast: Any, model: EvidenceModel) -> None:
    """Every array of :data:`STATE` the same in both models, bit for bit (±0 and NaN too)."""
    assert isinstance(fast, EvidenceModel)
    for name in STATE:
        a, b = getattr(fast, name), getattr(model, name)
        assert a.shape == b.shape, name
        assert a.dtype == b.dtype, name
        assert np.array_equal(a.view(np.uint8), b.view(np.uint8)), name


def _log(physics: tuple[tuple[str, str], ...], no_echo: bool) -> Any:
    sim = run_simulation(Scenario("office", 1, max_length=10.0, physics=physics))
    if no_echo:  # silent firings between the echoes: evidence_free reads the same state
        sim = simulate(sim.world, sim.robot, sim.trajectory, sim.seed, sim.physics,
                       sim.odometry, no_echo=True)
    return sim.readings


def _run_both(readings: Any, history: int, bins: int, start: int,
              sensor: SensorModel | None = None) -> tuple[EvidenceModel, bool]:
    """The method and its one-loop twin fed the same readings from ``start`` on, 30 at a time,
    their state compared as bits after every block; the twin's model, and whether any block
    ended with an occluded bin (occlusion is transient)."""
    method = EvidenceMethod(history_size=history, evidence_bins=bins, sensor=sensor)
    method.add_many(readings[:start])  # with start > history the ring wrapped
    oracle = copy.deepcopy(method)
    model = oracle.models[0]
    assert isinstance(model, EvidenceModel)

    def one_loop(first: int, count: int) -> None:  # repeats and watch: not the passes
        model.mark_repeats(first, count)
        _one_loop_add_many(model, first, count)
        model.mark_watch(first, count)

    model.on_add_many = one_loop  # type: ignore[method-assign]
    occluded = False
    for lo in range(start, start + 240, 30):
        method.add_many(readings[lo : lo + 30])
        oracle.add_many(readings[lo : lo + 30])
        _assert_same_state(method.models[0], model)
        occluded |= bool((model.occluded > 0.0).any())
    mine, theirs = method.local_map(), oracle.local_map()
    assert np.array_equal(mine.xy, theirs.xy)
    assert np.array_equal(mine.confidence, theirs.confidence)
    return model, occluded


@pytest.mark.parametrize(("history", "bins", "no_echo"), [
    (2, 7, False), (3, 40, False), (17, 13, True)])
def test_the_passes_match_the_one_loop_from_the_first_reading(history: int, bins: int,
                                                             no_echo: bool) -> None:
    """From an empty history on (no older row, then one), with bin counts that are not a
    multiple of the vector width, and with silent firings in between."""
    _run_both(_log((), no_echo), history, bins, start=0)


@pytest.mark.parametrize(("physics", "history", "bins"), [
    ((), 40, 24), ((("echo_model", "amplitude"),), 25, 16)])
def test_the_passes_give_the_one_loops_bits(physics: tuple[tuple[str, str], ...],
                                             history: int, bins: int) -> None:
    model, occluded = _run_both(_log(physics, False), history, bins, start=270)
    # Every path was taken: bins carved and bins alive, support, occlusion, crossings.
    assert (model.free >= model.threshold).any()
    assert (model.free < model.threshold).any()
    assert np.count_nonzero(model.support)
    assert occluded
    assert model.counts.any()


def test_the_passes_match_the_one_loop_with_a_support_band_narrower_than_the_range_tolerance(
) -> None:
    """With the two tolerances equal (the defaults) no bin lies between the free reach
    ``r_j - ε`` and the support band ``r_j ± ε_s``: the bins there are neither weighed nor
    supported, only counted alive (review revsplit: a ``break`` for that ``continue`` passed
    every other test)."""
    _run_both(_log((), False), 40, 24, start=270, sensor=SensorModel(support_tolerance=0.02))


@pytest.mark.parametrize("group_arcs", [1, 3])
def test_the_passes_in_small_groups_give_the_one_loops_bits(monkeypatch: pytest.MonkeyPatch,
                                                            group_arcs: int) -> None:
    """The kernel gathers the bins to weigh of a group of older arcs before it weighs them;
    groups of one and of three arcs (many groups a reading, a group's last arc anywhere in
    the cull's list) give the one loop's bits too."""
    monkeypatch.setattr(evidence_method, "_GROUP_ARCS", group_arcs)
    model, _ = _run_both(_log((), False), 40, 24, start=270)
    assert model.scratch.shape[1] == group_arcs * 24  # the groups were that small


def test_the_single_reading_kernel_gives_the_block_kernels_bits() -> None:
    """``evidence_add`` (one reading; the block kernel inlines its body) against
    ``evidence_add_many`` over the same readings, blocks of 30, bit for bit. The history is
    longer than the readings: no arc leaves it, whose ``behind`` only the block kernel judges."""
    readings = _log((), False)[:150]
    method = EvidenceMethod(history_size=200, evidence_bins=24)
    twin = copy.deepcopy(method)
    model = twin.models[0]
    assert isinstance(model, EvidenceModel)

    def one_at_a_time(first: int, count: int) -> None:
        model.mark_repeats(first, count)
        storage = model.history.storage_size
        for sequence in range(first, first + count):
            _, _, _, spilled = evidence_add(sequence % storage, 0, sequence, *model._bundles())
            if spilled:
                model._take_spill(spilled)
        model.mark_watch(first, count)

    model.on_add_many = one_at_a_time  # type: ignore[method-assign]
    for lo in range(0, len(readings), 30):
        method.add_many(readings[lo : lo + 30])
        twin.add_many(readings[lo : lo + 30])
    _assert_same_state(method.models[0], model)
    assert (model.free >= model.threshold).any()  # carving happened
    assert model.counts.any()
