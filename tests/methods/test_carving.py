"""The arc carving method (paper, sections 3 and 5-A), on hand-made scenes and a random stream."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve import (
    DEFAULT_BEAM_WIDTH,
    ArcFate,
    CarvingMethod,
    MethodConfig,
    PointSource,
    Reading,
    ReadingBatch,
    carve_arc,
    make_method,
)
from sonarcarve.cli import main
from sonarcarve.errors import ConfigError
from sonarcarve.geometry import NO_INCIDENCE_LIMIT
from sonarcarve.io import read_map_csv, write_readings_csv
from sonarcarve.methods.base import Estimates, SlotArray

PHI = DEFAULT_BEAM_WIDTH


def _reading(t: float, x: float, y: float, theta: float, r: float,
             width: float = math.nan) -> Reading:
    return Reading(t=t, sensor=0, x=x, y=y, theta=theta, range=r, beam_width=width)


def _exact(range_tolerance: float = 0.0, history_size: int = 250) -> CarvingMethod:
    return CarvingMethod(history_size=history_size, range_tolerance=range_tolerance)


def test_freespace_covering_an_older_arc_fully_carves_it() -> None:
    method = _exact()
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 1.0))
    method.add(_reading(1.0, 0.0, 0.0, 0.0, 2.0))  # same beam, longer: arc 0 is all freespace
    assert method.local_map().reading_id.tolist() == [1]
    measures = method.measures()
    assert (measures.fully_carved, measures.split) == (1, 0)
    assert method.finish().reading_id.tolist() == [1]


def test_a_split_arc_is_dropped_and_counted_as_split() -> None:
    method = _exact()
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 2.0))  # arc on r = 2, bearings ±φ/2
    # A narrow beam from (1, 0) along +x crosses that arc in its middle, nowhere near its ends.
    method.add(_reading(1.0, 1.0, 0.0, 0.0, 5.0, width=0.05))
    assert method.local_map().reading_id.tolist() == [1]
    measures = method.measures()
    assert (measures.fully_carved, measures.split) == (0, 1)


def test_overlapping_beam_shrinks_the_arc_to_the_rest() -> None:
    method = _exact()
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 1.0))  # [-φ/2, φ/2]
    method.add(_reading(1.0, 0.0, 0.0, PHI / 2, 2.0))  # freespace bearings [0, φ]
    local = method.local_map()
    assert local.reading_id.tolist() == [0, 1]
    # Arc 0 keeps [-φ/2, 0]: its point is at -φ/4 (eq. 3.6), width φ/2 (5.1), bound eq. 5.3.
    assert local.xy[0] == pytest.approx([math.cos(-PHI / 4), math.sin(-PHI / 4)], abs=1e-12)
    assert local.width[0] == pytest.approx(PHI / 2, abs=1e-12)
    assert local.max_error[0] == pytest.approx(2.0 * math.sin(PHI / 8), abs=1e-12)
    assert local.source.tolist() == [PointSource.CARVED, PointSource.CENTERLINE]
    # Arc 1 is the centerline point (eq. 3.3).
    assert local.xy[1] == pytest.approx([2 * math.cos(PHI / 2), 2 * math.sin(PHI / 2)])
    assert method.measures().unprocessed_share == 0.5


def test_the_newer_arc_is_never_carved_by_older_freespace() -> None:
    method = _exact()
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 5.0))
    method.add(_reading(1.0, 0.0, 0.0, 0.0, 1.0))  # inside reading 0's freespace, but newer
    local = method.local_map()
    assert local.reading_id.tolist() == [0, 1]
    assert local.source.tolist() == [PointSource.CENTERLINE] * 2
    assert method.measures().unprocessed_share == 1.0


def test_range_tolerance_spares_echoes_within_it() -> None:
    older = _reading(0.0, 0.0, 0.0, 0.0, 1.0)
    newer = _reading(1.0, 0.0, 0.0, 0.0, 1.03)
    for tolerance, kept in ((0.0, [1]), (0.05, [0, 1])):
        method = _exact(tolerance)
        method.add(older)
        method.add(newer)
        assert method.local_map().reading_id.tolist() == kept


def test_removed_arcs_count_as_processed_and_report_why() -> None:
    method = _exact()
    fates: dict[int, int] = {}

    def record(history: object, slots: SlotArray, est: Estimates) -> None:
        assert est.fate is not None
        ids = method.history.reading_id[slots].tolist()
        fates.update(zip(ids, est.fate.tolist(), strict=True))

    method.add_commit_listener(record)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 1.0))
    method.add(_reading(1.0, 0.0, 0.0, 0.0, 2.0))
    assert method.measures().unprocessed_share == 0.5  # arc 0 removed (processed), arc 1 fresh
    method.finish()
    assert fates == {0: ArcFate.FULLY_CARVED, 1: ArcFate.ALIVE}


def test_retired_arcs_are_not_carved() -> None:
    method = _exact(history_size=1)
    method.add(_reading(0.0, 0.0, 0.0, 0.0, 1.0))
    method.add(_reading(1.0, 0.0, 0.0, 0.0, 2.0))  # arc 0 has left the history already
    assert method.finish().reading_id.tolist() == [0, 1]
    assert method.measures().fully_carved == 0


@pytest.mark.parametrize("tolerance", [-0.01, math.nan, math.inf, 1.001, 1e9])
def test_bad_range_tolerance_is_rejected(tolerance: float) -> None:
    with pytest.raises(ConfigError, match=r"^range_tolerance must lie in \[0, 1\] metres"):
        CarvingMethod(range_tolerance=tolerance)


@pytest.mark.parametrize("tolerance", [0.0, 1.0])
def test_range_tolerance_bounds_are_accepted(tolerance: float) -> None:
    assert CarvingMethod(range_tolerance=tolerance).range_tolerance == tolerance


def test_factory_reads_the_config() -> None:
    method = make_method("carve", MethodConfig(history_size=7, range_tolerance=0.07))
    assert isinstance(method, CarvingMethod)
    assert method.history.capacity == 7
    assert method.models[0].range_tolerance == 0.07
    assert method.models[0].max_incidence == NO_INCIDENCE_LIMIT  # the paper by default
    for name in ("carve", "combined"):
        method = make_method(name, MethodConfig(max_incidence=0.3))
        assert method.models[0].max_incidence == 0.3


# -- specular-aware carving (beyond the paper) ----------------------------------------------------

# A wall along x = 1. Reading 0 hears it head-on from the origin. Reading 1, from (0, 0.9), aims
# its beam 40° off the wall's normal (bearing -0.7): on a specular wall (critical angle 17.5°)
# it hears nothing there and reports a far echo at 3 m, whose sector covers arc 0.
HEAD_ON = _reading(0.0, 0.0, 0.0, 0.0, 1.0)
GLANCING = _reading(1.0, 0.0, 0.9, -0.7, 3.0)


def test_paper_mode_carves_a_wall_a_glancing_reading_missed() -> None:
    for method in (_exact(), CarvingMethod(range_tolerance=0.0, max_incidence=math.pi / 2)):
        method.add_many(ReadingBatch.from_readings([HEAD_ON, GLANCING]))
        assert method.local_map().reading_id.tolist() == [1]
        assert method.measures().fully_carved == 1


@pytest.mark.parametrize("degrees", [17.5, 30.0])
def test_specular_mode_keeps_the_wall(degrees: float) -> None:
    # Seen from (0, 0.9) the wall points of arc 0 lie at incidences of 37°-47° (the angle
    # between the radius from the origin and the line of sight from (0, 0.9)).
    tau = np.linspace(-PHI / 2, PHI / 2, 101)
    sight = np.arctan2(np.sin(tau) - 0.9, np.cos(tau))
    assert np.all(np.abs(tau - sight) > math.radians(36.0))
    method = CarvingMethod(range_tolerance=0.0, max_incidence=math.radians(degrees))
    method.add_many(ReadingBatch.from_readings([HEAD_ON, GLANCING]))
    local = method.local_map()
    assert local.reading_id.tolist() == [0, 1]
    assert local.xy[0] == pytest.approx([1.0, 0.0])  # untouched: the centerline point
    assert local.source[0] == PointSource.CENTERLINE


def test_specular_mode_still_carves_from_in_front() -> None:
    # The same wall seen again head-on from farther back with a longer range: incidence 0, so
    # the newer reading's free space is evidence against arc 0 at any critical angle.
    method = CarvingMethod(range_tolerance=0.0, max_incidence=math.radians(17.5))
    method.add_many(ReadingBatch.from_readings([HEAD_ON, _reading(1.0, -0.5, 0.0, 0.0, 2.0)]))
    assert method.local_map().reading_id.tolist() == [1]


@pytest.mark.parametrize("incidence", [-0.01, math.nan, 1.6])
def test_bad_max_incidence_is_rejected(incidence: float) -> None:
    with pytest.raises(ConfigError, match=r"^max_incidence must lie in \[0, pi/2\] radians"):
        CarvingMethod(max_incidence=incidence)


def test_cli_max_incidence(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    readings = tmp_path / "r.csv"
    write_readings_csv(ReadingBatch.from_readings([HEAD_ON, GLANCING]), readings)
    kept = {}
    for extra in ([], ["--max-incidence", "90"], ["--max-incidence", "17.5"]):
        out = tmp_path / f"map{len(kept)}.csv"
        args = ["process", str(readings), "-m", "carve", "--range-tolerance", "0", "-o", str(out)]
        assert main([*args, *extra]) == 0
        kept[" ".join(extra)] = read_map_csv(out).reading_id.tolist()
    assert kept == {"": [1], "--max-incidence 90": [1], "--max-incidence 17.5": [0, 1]}
    capsys.readouterr()
    assert main(["process", str(readings), "-o", str(tmp_path / "x.csv"),
                 "--max-incidence", "91"]) == 2
    # Checked in degrees, as typed (the config's rule, [0, pi/2] radians).
    assert "--max-incidence must lie in [0, 90] degrees, got 91" in capsys.readouterr().err


# -- against a slow reference: the paper's procedure (section 5-A) with the scalar carve_arc ------


def _random_batch(seed: int, n: int) -> ReadingBatch:
    rng = np.random.default_rng(seed)
    return ReadingBatch.from_arrays(
        t=np.arange(n, dtype=float), sensor=rng.integers(0, 16, n),
        x=rng.uniform(0.0, 2.0, n), y=rng.uniform(0.0, 2.0, n), theta=rng.uniform(-7, 7, n),
        range=rng.uniform(0.3, 3.0, n),
    )


def _reference(batch: ReadingBatch, history_size: int, tolerance: float,
               max_incidence: float = NO_INCIDENCE_LIMIT) -> dict[int, tuple]:
    """Final ``(alive, lo, hi, carved)`` of every reading, by the letter of section 5-A."""
    lo = batch.theta - PHI / 2
    hi = batch.theta + PHI / 2
    alive = np.ones(len(batch), dtype=bool)
    carved = np.zeros(len(batch), dtype=bool)
    for k in range(len(batch)):
        for i in range(max(0, k - history_size + 1), k):
            if not alive[i]:
                continue
            status, lo[i], hi[i] = carve_arc(
                batch.x[i], batch.y[i], batch.range[i], lo[i], hi[i], batch.x[k], batch.y[k],
                batch.range[k], batch.theta[k] - PHI / 2, batch.theta[k] + PHI / 2, tolerance,
                max_incidence)
            alive[i] = status in (ArcFate.UNCHANGED, ArcFate.SHRUNK)
            carved[i] |= status != ArcFate.UNCHANGED
    return {k: (bool(alive[k]), lo[k], hi[k], bool(carved[k])) for k in range(len(batch))}


@pytest.mark.parametrize(("seed", "history_size", "tolerance", "incidence_deg"),
                         [(0, 10, 0.0, 90.0), (1, 25, 0.05, 90.0), (2, 300, 0.0, 90.0),
                          (3, 25, 0.05, 30.0), (4, 300, 0.0, 17.5)])
def test_method_matches_the_sequential_reference(seed: int, history_size: int,
                                                 tolerance: float, incidence_deg: float) -> None:
    batch = _random_batch(seed, 250)
    incidence = math.radians(incidence_deg)
    method = CarvingMethod(history_size=history_size, range_tolerance=tolerance,
                           max_incidence=incidence)
    method.add_many(batch)
    global_map = method.finish()
    expected = _reference(batch, history_size, tolerance, incidence)
    survivors = [k for k, (alive, *_) in expected.items() if alive]
    assert global_map.reading_id.tolist() == survivors
    assert len(survivors) < len(batch)  # the scene does carve
    lo = np.array([expected[k][1] for k in survivors])
    hi = np.array([expected[k][2] for k in survivors])
    r = batch.range[survivors]
    mid = 0.5 * (lo + hi)
    xy = np.column_stack((batch.x[survivors] + r * np.cos(mid),
                          batch.y[survivors] + r * np.sin(mid)))
    np.testing.assert_allclose(global_map.xy, xy, atol=1e-12)
    np.testing.assert_allclose(global_map.width, hi - lo, atol=1e-12)
    # eq. 5.2-5.3 written out: E_m = θd/2, E_s = 2 r sin(E_m/2) (not the library's chord_error)
    np.testing.assert_allclose(global_map.max_error, 2.0 * r * np.sin((hi - lo) / 4.0),
                               atol=1e-12)
    carved = [expected[k][3] for k in survivors]
    assert (global_map.source == PointSource.CARVED).tolist() == carved
    assert 0 < sum(carved) < len(carved)
