"""The appendix experiments: sharpness measure, polling bound, odometry drift, outputs."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from sonarcarve.io.roboND import read_robond
from sonarcarve.lab.appendix import (
    BEGIN_MARKER,
    END_MARKER,
    AppendixError,
    AppendixSettings,
    appendix_markdown,
    latest_firing,
    line_spread,
    polling_experiment,
    reference_picture,
    replace_appendix_section,
    run_appendix,
    write_appendix_section,
)
from sonarcarve.lab.appendix_odometry import _pose_corrected
from sonarcarve.polling import poll_readings, simulate_polls
from sonarcarve.robot import load_robot
from sonarcarve.sim.motion import Trajectory, follow_waypoints
from sonarcarve.sim.simulate import simulate
from sonarcarve.sim.world import load_world


@pytest.fixture(scope="module")
def quick(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    out = tmp_path_factory.mktemp("appendix")
    return run_appendix(out, quick=True), out


# -- the sharpness measure ---------------------------------------------------------------------

def test_points_on_a_line_have_no_spread() -> None:
    s = np.linspace(0.0, 5.0, 200)
    angle = 0.7
    xy = np.column_stack((30.0 + s * math.cos(angle), -12.0 + s * math.sin(angle)))
    spread = line_spread(xy, radius=0.2, min_points=5)
    assert np.all(np.isfinite(spread.spread))
    np.testing.assert_allclose(spread.spread, 0.0, atol=1e-7)


def test_noisy_line_spread_is_sigma() -> None:
    rng = np.random.default_rng(3)
    sigma = 0.02
    s = np.linspace(0.0, 20.0, 4000)
    angle = -0.4
    normal = np.array([-math.sin(angle), math.cos(angle)])
    xy = np.column_stack((s * math.cos(angle), s * math.sin(angle)))
    xy += rng.normal(0.0, sigma, s.shape)[:, None] * normal
    spread = line_spread(xy, radius=0.25, min_points=5)
    assert float(np.median(spread.spread)) == pytest.approx(sigma, rel=0.1)


def test_line_spread_matches_a_slow_eigen_reference() -> None:
    rng = np.random.default_rng(8)
    xy = rng.uniform(0.0, 2.0, (150, 2))
    radius, k = 0.3, 4
    fast = line_spread(xy, radius, k)
    for i in range(len(xy)):
        near = xy[np.hypot(*(xy - xy[i]).T) <= radius]
        assert fast.neighbours[i] == len(near)
        if len(near) < k:
            assert math.isnan(fast.spread[i])
            continue
        centred = near - near.mean(axis=0)
        smallest = np.linalg.eigvalsh(centred.T @ centred)[0]
        assert fast.spread[i] == pytest.approx(math.sqrt(max(smallest, 0.0) / (len(near) - 2)),
                                               rel=1e-6, abs=1e-9)


def test_line_spread_rejects_bad_parameters() -> None:
    with pytest.raises(AppendixError, match="radius"):
        line_spread(np.zeros((3, 2)), radius=0.0)
    assert line_spread(np.zeros((0, 2)), radius=1.0).spread.shape == (0,)


# -- sonar polling -----------------------------------------------------------------------------

def test_polling_stamps_are_within_their_bound_on_a_short_run() -> None:
    """Direct check, independent of the experiment code: every polled reading's true firing
    (same sensor, same value, nearest in time) lies within the stamp's error bound."""
    world, robot = load_world("office"), load_robot("scout2")
    assert world.tour is not None
    trajectory = follow_waypoints(world.tour[:3])
    sim = simulate(world, robot, trajectory, seed=1)
    fired = sim.firings
    rng = np.random.default_rng(0)
    poll_t = np.cumsum(rng.uniform(0.08, 0.12, int(trajectory.duration / 0.08) + 2))
    poll_t = poll_t[poll_t <= trajectory.t[-1]]
    log = simulate_polls(fired.t, fired.sensor, sim.echoes.range, poll_t, robot.n_sensors,
                         pose_at=trajectory.pose_at)
    mounts = np.column_stack((robot.mount_x, robot.mount_y, robot.bearing))
    polled = poll_readings(log, robot.firing_order, robot.firing_period, mounts,
                           min_interval=robot.firing_period)
    assert len(polled.batch) > 0.95 * len(sim.readings)
    b = polled.batch
    errors = []
    for k in range(len(b)):
        same = np.flatnonzero((fired.sensor == b.sensor[k]) & (sim.echoes.range == b.range[k]))
        errors.append(np.min(np.abs(fired.t[same] - b.t[k])))
    assert np.all(np.asarray(errors) <= polled.stamp_error + 1e-9)


def test_polling_experiment_bound_holds_and_polling_beats_naive() -> None:
    settings = AppendixSettings(quick=True, seeds=1, tour_length=25.0, poll_rates=(10.0,),
                                figure_rate=10.0)
    res, art = polling_experiment(settings)
    run = res["appendix_polling"]["rates"]["10"]
    assert run["polled"]["time"]["within_percent"] == 100.0
    assert run["polled"]["position"]["within_percent"] == 100.0
    assert run["matched_percent"] == 100.0
    assert run["contradictions"] == 0
    # The naive host stamps late by up to a poll interval (0.1 s +- 20 %) and misses repeats.
    assert 0.0 < run["naive"]["time"]["mean"] <= 0.12
    assert run["readings"]["naive"] < run["readings"]["polled"] <= run["readings"]["true"]
    assert run["map_error"]["polled"]["median"] <= run["map_error"]["naive"]["median"]
    assert set(art["maps"]) == {"naive", "polled"}


def test_latest_firing_by_hand() -> None:
    t = [0.0, 0.1, 0.2, 0.3, 0.4]
    s = [0, 1, 0, 1, 0]
    assert latest_firing([1, 0, 1, 0], [0.05, 0.25, 0.3, 10.0], t, s).tolist() == [-1, 2, 3, 4]


# -- odometry ----------------------------------------------------------------------------------

def test_pose_correction_undoes_a_known_pose_error() -> None:
    t = np.array([0.0, 1.0, 2.0])
    truth = Trajectory(t, np.array([0.0, 1.0, 2.0]), np.zeros(3), np.zeros(3))
    # Believed: shifted 1 m in y and turned 90° about the believed position.
    belief = Trajectory(t, truth.x.copy(), np.ones(3), np.full(3, math.pi / 2))
    # A point 2 m ahead of the robot at t = 1: believed at (1, 1) + 2 (0, 1) = (1, 3).
    out = _pose_corrected(np.array([[1.0, 3.0]]), np.array([1.0]), truth, belief)
    np.testing.assert_allclose(out, [[3.0, 0.0]], atol=1e-12)


def test_odometry_error_grows_with_distance(quick: tuple[dict[str, Any], Path]) -> None:
    res = quick[0]["appendix_odometry"]
    pose = [v for v in res["pose_error_by_distance"]["median"] if v is not None]
    assert pose[-1] > 3.0 * pose[0]
    for entry in res["methods"].values():
        shift = [v for v in entry["drift_shift"]["by_distance"]["median"] if v is not None]
        raw = [v for v in entry["odometry"]["by_distance"]["median"] if v is not None]
        assert shift[-1] > 3.0 * shift[0]
        assert raw[-1] > raw[0]
        # Removing the pose error brings the map back to the accuracy of true poses.
        assert entry["odometry_corrected"]["error"]["median"] < entry["odometry"]["error"][
            "median"]
        assert entry["odometry_corrected"]["error"]["median"] == pytest.approx(
            entry["true_poses"]["error"]["median"], abs=0.02)


# -- the real log ------------------------------------------------------------------------------

def test_reference_picture_is_registered_with_the_log() -> None:
    picture = reference_picture()
    assert picture.extent == pytest.approx((-5.95, 24.05, -10.05, 4.95))
    h, w = picture.image.shape[:2]
    left, right, bottom, top = picture.extent
    batch = read_robond().batch
    # origin="lower": row 0 is at the bottom of the extent.
    col = ((batch.x - left) / (right - left) * w).astype(int)
    row = ((batch.y - bottom) / (top - bottom) * h).astype(int)
    rgb = picture.image[row, col, :3]
    free = (rgb[:, 0] > 0.8) & (rgb[:, 1] < 0.2) & (rgb[:, 2] < 0.2)  # red: free cells
    assert np.mean(free) > 0.95
    assert len(picture.occupied) > 1000


# -- the whole thing, quick --------------------------------------------------------------------

def test_quick_run_produces_every_key_and_figure(quick: tuple[dict[str, Any], Path]) -> None:
    res, out = quick
    assert {"appendix_polling", "appendix_filters", "appendix_real_log", "appendix_odometry",
            "appendix_meta"} <= set(res)
    real = res["appendix_real_log"]
    assert set(real["methods"]) == {"centerline", "carving", "atm", "combined"}
    for m in real["methods"].values():
        assert m["points"] + round(m["removed_percent"] / 100 * real["log"]["readings"]) == \
            real["log"]["readings"]
        assert m["spread"]["defined"] <= m["points"]
    assert real["methods"]["centerline"]["removed_percent"] == 0.0
    assert real["methods"]["carving"]["removed_percent"] > 0.0
    for name in ("appendix-polling.png", "appendix-real-log.png", "appendix-odometry.png"):
        assert (out / name).stat().st_size > 10_000
    # The numbers live in `sonarcarve experiments`' results.json only: no second JSON here.
    assert not list(out.glob("*.json"))
    json.dumps(res, allow_nan=False)  # strict JSON all the same


def test_markdown_section_and_replacement(quick: tuple[dict[str, Any], Path],
                                          tmp_path: Path) -> None:
    md = appendix_markdown(quick[0], "cmd", ["figures/appendix-polling.png"])
    assert md.startswith(BEGIN_MARKER)
    assert md.endswith(END_MARKER)
    for title in ("Appendix A, Fig. 14", "Appendix B", "roboND", "Fig. 7"):
        assert title in md
    path = tmp_path / "RESULTS.md"
    head = "# Results\n\nkeep me\n<!-- experiments:begin -->\nx\n<!-- experiments:end -->\n"
    path.write_text(head)
    # An existing file without the appendix markers is refused and left as it was.
    with pytest.raises(AppendixError, match=r"RESULTS\.md: has no <!-- appendix:begin -->"):
        write_appendix_section(path, quick[0], "cmd")
    assert path.read_text() == head
    path.write_text(f"{head}\n{BEGIN_MARKER}\nold\n{END_MARKER}\n\ntail\n")
    write_appendix_section(path, quick[0], "cmd")
    first = path.read_text()
    assert first.startswith(f"{head}\n{BEGIN_MARKER}\n")
    assert first.endswith(f"{END_MARKER}\n\ntail\n")
    write_appendix_section(path, quick[0], "cmd2")
    second = path.read_text()
    assert second.count(BEGIN_MARKER) == 1
    assert "cmd2" in second
    assert "`cmd`" not in second
    # A file that does not exist yet is created with the section alone.
    fresh = write_appendix_section(tmp_path / "new.md", quick[0], "cmd")
    assert fresh.read_text() == appendix_markdown(quick[0], "cmd") + "\n"
    with pytest.raises(AppendixError, match="line 2"):
        replace_appendix_section(f"a\n{END_MARKER}\n{BEGIN_MARKER}\n", md)


def test_bad_requests_raise() -> None:
    with pytest.raises(AppendixError, match="figure_rate"):
        AppendixSettings(poll_rates=(10.0,), figure_rate=5.0)
    with pytest.raises(AppendixError, match="unknown appendix experiment"):
        run_appendix("/nonexistent", only=["nope"])
