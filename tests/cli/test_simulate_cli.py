"""`sonarcarve simulate` in-process: files written, determinism, paths, one-line errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.io import read_readings_csv
from sonarcarve.sim.truth import read_truth_json
from sonarcarve.sim.world import load_world


def run(*args: str) -> int:
    return main(["simulate", *args])


def test_doorway_writes_readings_and_truth(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "door.csv"
    assert run("--world", "doorway", "--seed", "1", "--out", str(out)) == 0
    header = out.read_text().splitlines()[0]
    assert header == "t,sensor,x,y,theta,range,beam_width"
    readings = read_readings_csv(out)
    truth = read_truth_json(tmp_path / "door.truth.json")
    assert len(readings) > 50
    assert truth.kind.shape == (len(readings),)
    np.testing.assert_array_equal(truth.world.segments, load_world("doorway").segments)
    np.testing.assert_allclose(readings.beam_width, np.radians(22.5))
    printed = capsys.readouterr().out
    assert "firings" in printed
    assert "direct" in printed


def test_same_seed_same_bytes_other_seed_differs(tmp_path: Path) -> None:
    outs = [tmp_path / name for name in ("a.csv", "b.csv", "c.csv")]
    for out, seed in zip(outs, ("4", "4", "5"), strict=True):
        assert run("--world", "doorway", "--seed", seed, "--odometry", "--out", str(out)) == 0
    assert outs[0].read_bytes() == outs[1].read_bytes()
    assert (tmp_path / "a.truth.json").read_bytes() == (tmp_path / "b.truth.json").read_bytes()
    assert outs[0].read_bytes() != outs[2].read_bytes()


def test_odometry_changes_the_stamps_not_the_ranges(tmp_path: Path) -> None:
    plain, drift = tmp_path / "plain.csv", tmp_path / "drift.csv"
    assert run("--world", "t-junction", "--robot", "p3dx-front", "--out", str(plain)) == 0
    assert run("--world", "t-junction", "--robot", "p3dx-front", "--odometry",
               "--out", str(drift)) == 0
    a, b = read_readings_csv(plain), read_readings_csv(drift)
    np.testing.assert_array_equal(a.range, b.range)
    assert not np.array_equal(a.x, b.x)


def test_pose_noise_moves_the_stamps_by_about_its_sigma(tmp_path: Path) -> None:
    outs = {name: tmp_path / f"{name}.csv" for name in ("plain", "zero", "noisy", "both")}
    assert run("--world", "t-junction", "--out", str(outs["plain"])) == 0
    assert run("--world", "t-junction", "--pose-noise", "0", "0", "--out", str(outs["zero"])) == 0
    assert run("--world", "t-junction", "--pose-noise", "0.05", "2",
               "--out", str(outs["noisy"])) == 0
    assert run("--world", "t-junction", "--odometry", "--pose-noise", "0.05", "2",
               "--out", str(outs["both"])) == 0
    assert outs["zero"].read_bytes() == outs["plain"].read_bytes()
    plain, noisy = read_readings_csv(outs["plain"]), read_readings_csv(outs["noisy"])
    np.testing.assert_array_equal(plain.range, noisy.range)  # the echoes are the truth's
    # A sensor's offset turns with the heading error, so the origin moves by the position error
    # plus at most mount distance x 2°; over a 20 s drive the wandering error (τ = 1 s) has
    # about 20 independent stretches, so its spread is near σ but not exactly it.
    spread = float(np.std(noisy.x - plain.x))
    assert 0.02 < spread < 0.09
    turn = np.angle(np.exp(1j * (noisy.theta - plain.theta)))
    assert 0.01 < float(np.std(turn)) < 0.07  # 2° = 0.035 rad
    both = read_readings_csv(outs["both"])
    assert not np.array_equal(both.x, noisy.x)  # stacked on the dead-reckoned poses


def test_path_file_is_followed(tmp_path: Path) -> None:
    path = tmp_path / "path.csv"
    path.write_text("x,y\n0,0\n0,2.5\n-2,2.5\n")
    out = tmp_path / "r.csv"
    assert run("--world", "doorway", "--robot", "roboND-8", "--path", str(path),
               "--out", str(out)) == 0
    readings = read_readings_csv(out)
    # roboND-8 sensors sit at the robot centre: every origin lies on the path's two legs.
    on_first = (np.abs(readings.x) < 1e-9) & (readings.y > -1e-9) & (readings.y < 2.5 + 1e-9)
    on_second = (np.abs(readings.y - 2.5) < 1e-9) & (readings.x < 1e-9) & (readings.x > -2 - 1e-9)
    assert np.all(on_first | on_second)
    assert on_second.any()


def test_speed_sets_how_fast_the_path_is_driven(tmp_path: Path) -> None:
    """A straight 2.5 m leg (no turn: the robot starts facing it) takes 5 s at 0.5 m/s and 2 s
    at 1.25 m/s. roboND-8's sensors sit at the robot centre, so a reading's y is where the robot
    was: y = speed * t on this leg."""
    path = tmp_path / "path.csv"
    path.write_text("x,y\n0,0\n0,2.5\n")
    for speed in ("0.5", "1.25"):
        out = tmp_path / f"r{speed}.csv"
        assert run("--world", "doorway", "--robot", "roboND-8", "--path", str(path),
                   "--speed", speed, "--out", str(out)) == 0
        readings = read_readings_csv(out)
        np.testing.assert_allclose(readings.y, float(speed) * readings.t, atol=1e-9)
        assert readings.t.max() <= 2.5 / float(speed) + 1e-9


def test_explore(tmp_path: Path) -> None:
    out = tmp_path / "e.csv"
    assert run("--world", "t-junction", "--explore", "20", "--seed", "2", "--out", str(out)) == 0
    readings = read_readings_csv(out)
    assert readings.t[-1] == pytest.approx(20.0, abs=0.05)


def test_physics_amplitude_is_a_different_sonar(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    spec, amp, again = tmp_path / "s.csv", tmp_path / "a.csv", tmp_path / "b.csv"
    assert run("--world", "doorway", "--seed", "3", "--out", str(spec)) == 0
    for out in (amp, again):
        assert run("--world", "doorway", "--seed", "3", "--physics", "amplitude",
                   "--out", str(out)) == 0
    assert amp.read_bytes() == again.read_bytes()
    assert amp.read_bytes() != spec.read_bytes()
    assert len(read_readings_csv(amp)) > 50
    default = tmp_path / "d.csv"
    assert run("--world", "doorway", "--seed", "3", "--physics", "specular",
               "--out", str(default)) == 0
    assert default.read_bytes() == spec.read_bytes()
    # Small reflectors change only curves (runs of short walls): the doorway has none.
    thin = tmp_path / "t.csv"
    assert run("--world", "doorway", "--seed", "3", "--physics", "amplitude-thin",
               "--out", str(thin)) == 0
    assert thin.read_bytes() == amp.read_bytes()
    capsys.readouterr()


@pytest.mark.parametrize(
    ("args", "problem"),
    [
        (["--world", "doorway", "--physics", "sonic"],
         "choose specular, amplitude or amplitude-thin"),
        (["--world", "atlantis"], "unknown world 'atlantis'"),
        (["--world", "doorway", "--robot", "nomad"], "unknown robot 'nomad'"),
        (["--world", "doorway", "--path", "nowhere.csv"], "no such file"),
        (["--world", "doorway", "--path", "p.csv", "--explore", "5"], "not both"),
        (["--world", "doorway", "--explore", "-3"], "--explore must be a positive"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], problem: str,
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "never.csv"
    assert run(*args, "--out", str(out)) == 2
    err = capsys.readouterr().err.strip()
    assert problem in err
    assert len(err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", ["run.mcap", "run.bag", "run_folder"])
def test_bag_output_is_what_a_robot_records_with_the_truth_beside(tmp_path: Path,
                                                                   name: str) -> None:
    pytest.importorskip("rosbags")
    from sonarcarve.io import read_rosbag

    csv_out, bag = tmp_path / "run.csv", tmp_path / name
    assert run("--world", "doorway", "--seed", "2", "--out", str(csv_out)) == 0
    (tmp_path / "run.truth.json").rename(tmp_path / "csv.truth.json")
    assert run("--world", "doorway", "--seed", "2", "--out", str(bag)) == 0
    # The truth of the bag is the CSV run's, under the bag's name without its ending.
    assert (tmp_path / f"{bag.stem}.truth.json").read_bytes() == (
        tmp_path / "csv.truth.json").read_bytes()
    readings, log = read_readings_csv(csv_out), read_rosbag(bag)
    assert [s.frame for s in log.report.sources] == [f"sonar_{i}" for i in range(16)]
    assert [s.mount for s in log.report.sources] == ["tf"] * 16  # from /tf_static
    np.testing.assert_array_equal(log.batch.sensor, readings.sensor)
    np.testing.assert_allclose(log.batch.range, readings.range, rtol=1e-7)  # float32
    np.testing.assert_allclose(log.batch.x, readings.x, atol=1e-12)
    # Every firing is a message: the heard ones are the readings, the others +Inf (REP 117).
    assert log.report.readings + log.report.no_echo == sum(
        n for topic, n in log.report.messages.items() if topic.startswith("/sonar/"))


def test_bag_output_refuses_to_overwrite_and_unknown_endings(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    old = tmp_path / "old.mcap"
    old.write_bytes(b"precious")
    assert run("--world", "doorway", "--out", str(old)) == 2
    assert "already exists" in capsys.readouterr().err
    assert old.read_bytes() == b"precious"
    assert run("--world", "doorway", "--out", str(tmp_path / "run.txt")) == 2
    assert "unknown ending '.txt'" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.mcap"]


@pytest.mark.parametrize(("waypoints", "problem"), [
    # UX review, finding 6: 1,414 m and 3,535 s in an 8 x 9.5 m world, accepted.
    ("x,y\n0,0\n1000,1000\n", "p.csv: line 3, waypoint (1000, 1000) lies outside world "
                              "'doorway' (x in [-4, 4], y in [-1.5, 8])"),
    # Through the wall at y = 4, beside the door (|x| <= 0.425).
    ("x,y\n# comment\n2,0\n2,6\n", "p.csv: line 3, the leg to the next waypoint (line 4) runs "
                                   "into a wall of world 'doorway' at (2, 4)"),
])
def test_a_path_outside_the_world_or_through_a_wall_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
    waypoints: str, problem: str,
) -> None:
    monkeypatch.chdir(tmp_path)
    Path("p.csv").write_text(waypoints)
    assert run("--world", "doorway", "--path", "p.csv", "--out", "never.csv") == 2
    err = capsys.readouterr().err.strip()
    assert err == f"sonarcarve: error: {problem}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.csv"]


def test_a_path_through_the_door_is_driven(tmp_path: Path) -> None:
    path = tmp_path / "p.json"
    path.write_text("[[0, 0], [0, 6]]")
    assert run("--world", "doorway", "--path", str(path), "--out", str(tmp_path / "s.csv")) == 0


@pytest.mark.parametrize(("args", "problem"), [
    (["--physics", "foo"], "error: --physics foo: unknown model; choose specular, amplitude or "
                           "amplitude-thin"),
    (["--explore", "1e9"], "error: --explore must be at most 500,000 seconds (139 hours, the "
                           "simulator's limit of 10,000,000 poses), got 1e+09"),
    (["--speed", "0"], "error: --speed must be a speed in (0, 10] m/s, got 0"),
    (["--speed", "11"], "error: --speed must be a speed in (0, 10] m/s, got 11"),
    (["--speed", "nan"], "error: --speed must be a speed in (0, 10] m/s, got nan"),
    (["--pose-noise", "-0.01", "1"], "error: --pose-noise takes two standard deviations >= 0, "
                                     "metres and degrees, got -0.01 1"),
    (["--pose-noise", "0.05", "inf"], "error: --pose-noise takes two standard deviations >= 0, "
                                      "metres and degrees, got 0.05 inf"),
    (["--speed", "1e-6"], "(MAX_POSES): at --speed 1e-06 m/s the drive is too long; raise "
                          "--speed or give a shorter --path"),
])
def test_option_errors_name_the_option(capsys: pytest.CaptureFixture[str], tmp_path: Path,
                                       args: list[str], problem: str) -> None:
    assert run("--world", "doorway", *args, "--out", str(tmp_path / "s.csv")) == 2
    err = capsys.readouterr().err
    assert problem in err, err
    assert list(tmp_path.iterdir()) == []


def test_sensors_behind_walls_are_warned_of(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    """The car's bumper sensors reach 2.28 m from its centre, its disc 0.9 m: on the doorway
    world's tour, which stops 1 m short of the wall, the front ones pass through it."""
    assert run("--world", "doorway", "--robot", "car-parking-12",
               "--out", str(tmp_path / "car.csv")) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "came from a sensor on the far side of a wall" in err[0]
    assert "car-parking-12's sensors reach 2.28 m from its centre" in err[0]
    assert run("--world", "doorway", "--out", str(tmp_path / "scout.csv")) == 0
    assert "far side of a wall" not in capsys.readouterr().err


def test_an_explore_that_never_moves_is_warned_of(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    """The car's 0.9 m disc finds no open place to drive to on this generated floor (its planner
    keeps 1.02 m from walls), so it stays where it starts; the Scout2 drives off."""
    world = "random:7:40x30"
    assert run("--world", world, "--robot", "car-parking-12", "--explore", "3",
               "--out", str(tmp_path / "car.csv")) == 0
    err = capsys.readouterr().err
    assert ("the robot did not move in 3 s: --explore found no open place its 0.9 m body could "
            "reach" in err)
    assert "wider than 2.04 m" in err
    assert run("--world", world, "--explore", "3", "--out", str(tmp_path / "scout.csv")) == 0
    assert "did not move" not in capsys.readouterr().err


def test_a_log_whose_truth_file_another_log_shares_says_so(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    # User review: `simulate --out run.csv` then `simulate --world t-junction --out run.mcap`
    # replaced run.truth.json without a word; `view run.csv` then drew the T junction.
    pytest.importorskip("rosbags")
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--world", "doorway", "--out", "run.csv"]) == 0
    assert main(["simulate", "--world", "doorway", "--out", "run.csv"]) == 0  # its own: fine
    assert capsys.readouterr().err == ""
    assert main(["simulate", "--world", "t-junction", "--out", "run.mcap"]) == 0
    assert capsys.readouterr().err == (
        "sonarcarve: warning: run.truth.json was also the truth of run.csv, and now holds "
        "run.mcap's: give logs of different runs different names\n")
    assert read_truth_json(tmp_path / "run.truth.json").world.segments.shape == \
        load_world("t-junction").segments.shape
    assert main(["simulate", "--world", "doorway", "--out", "other.csv"]) == 0
    assert capsys.readouterr().err == ""
