from pathlib import Path

import numpy as np
import pytest

from sonarcarve.cli import main
from sonarcarve.io import read_readings_csv, read_robond

POSES = "1000 0 0 0\n1200 50 0 0\n1400 100 0 900\n"
MEASUREMENTS = "1000 5110 800 5110 5110 5110 5110 5110 1500\n" \
               "1200 5110 800 5110 5110 5110 5110 5110 1400\n" \
               "1400 5110 700 5110 5110 5110 5110 2000 1400\n"


def test_convert_writes_the_readings_csv(tmp_path: Path,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "log"
    folder.mkdir()
    (folder / "poses.txt").write_text(POSES)
    (folder / "measurement.txt").write_text(MEASUREMENTS)
    out = tmp_path / "readings.csv"
    assert main(["convert", "roboND", str(folder), "--out", str(out)]) == 0
    assert out.read_text().splitlines()[0] == "t,sensor,x,y,theta,range,beam_width"
    batch = read_readings_csv(out)
    # r0: s1 800, s7 1500; r1: s1 stale, s7 1400 new; r2: s1 700, s6 2000 new, s7 stale.
    assert batch.sensor.tolist() == [1, 7, 7, 1, 6]
    np.testing.assert_allclose(batch.range, [0.8, 1.5, 1.4, 0.7, 2.0])
    np.testing.assert_allclose(batch.t, [1.0, 1.0, 1.2, 1.4, 1.4])
    np.testing.assert_allclose(batch.theta[-1], np.radians(90 + 37.5))
    text = capsys.readouterr().out
    assert "stale echoes (dropped)" in text
    assert "readings written" in text


def test_convert_defaults_to_the_bundled_log(tmp_path: Path) -> None:
    out = tmp_path / "r.csv"
    assert main(["convert", "roboND", "--out", str(out), "--beam-width", "25"]) == 0
    batch = read_readings_csv(out)
    assert len(batch) == read_robond().report.readings
    np.testing.assert_allclose(batch.beam_width, np.radians(25))


@pytest.mark.parametrize(("args", "text"), [
    (["convert", "nonsense", "--out", "x.csv"], "unknown format 'nonsense'"),
    (["convert", "roboND", "--out", "x.csv", "--beam-width", "0"], "--beam-width must lie"),
    (["convert", "roboND", "/nonexistent/folder", "--out", "x.csv"], "no such file"),
])
def test_convert_errors_are_one_line(args: list[str], text: str, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str],
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(args) == 2
    err = capsys.readouterr().err.strip()
    assert text in err
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "x.csv").exists()
