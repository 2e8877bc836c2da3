"""`sonarcarve experiments --quick` end to end, in-process: keys, invariants, files."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest

from sonarcarve.cli import main
from sonarcarve.lab.report import APPENDIX_BEGIN_MARKER as APPENDIX_BEGIN
from sonarcarve.lab.report import APPENDIX_END_MARKER as APPENDIX_END
from sonarcarve.lab.report import BEGIN_MARKER, END_MARKER

METHODS = ("atm", "carving", "combined", "centerline", "evidence")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any], Path]:
    root = tmp_path_factory.mktemp("experiments")
    md = root / "RESULTS.md"
    md.write_text(f"# Results\n\nLead's text.\n\n{BEGIN_MARKER}\nSTALE-SECTION\n{END_MARKER}"
                  f"\n\nMiddle.\n\n{APPENDIX_BEGIN}\nSTALE-APPENDIX\n{APPENDIX_END}\n\nTail.\n")
    out = root / "out"
    code = main(["experiments", "--quick", "--out", str(out), "--figures", str(root / "figs"),
                 "--results-md", str(md)])
    assert code == 0
    return out, json.loads((out / "results.json").read_text()), md


def test_results_have_the_required_keys(quick_run: tuple[Path, dict[str, Any], Path]) -> None:
    _, res, _ = quick_run
    for key in ("table1", "fully_carved", "openings", "true_error", "fig10", "fig11", "fig12",
                "fig13", "t_junction", "latency_accuracy", "sensitivity", "meta", "command"):
        assert key in res, key
    assert set(res["table1"]) == set(METHODS)
    assert {"share", "spurious_removed", "true_lost"} <= set(res["fully_carved"])
    for m in METHODS:
        assert set(res["openings"][m]) == {"1", "2", "3"}
        assert {"median", "p90"} <= set(res["true_error"][m])


def test_results_obey_the_invariants(quick_run: tuple[Path, dict[str, Any], Path]) -> None:
    _, res, _ = quick_run
    t1 = res["table1"]
    assert t1["centerline"] == 0.0
    # One history, processed by either model: never more unprocessed than the better one.
    assert t1["combined"] <= min(t1["atm"], t1["carving"]) + 1e-9
    for value in t1.values():
        assert 0.0 <= value <= 100.0
    for key in ("share", "spurious_removed", "true_lost"):
        assert 0.0 <= res["fully_carved"][key] <= 100.0
    for m in METHODS:
        for share in res["openings"][m].values():
            assert share is None or 0.0 <= share <= 100.0
        assert res["true_error"][m]["median"] >= 0.0
        assert res["true_error"][m]["p90"] >= res["true_error"][m]["median"]
    # ATM's Fig. 12 bound is eq. 5.4 times the range quantum, for the configured ψ.
    cfg = res["meta"]["settings"]["method_config"]
    psi = math.radians(cfg["min_transversal_deg"])
    expected = cfg["range_resolution_m"] * (1 / math.sin(psi) + 1 / math.tan(psi))
    assert res["fig12"]["atm_bound"] == pytest.approx(expected)


def test_figures_and_markdown_are_written(quick_run: tuple[Path, dict[str, Any], Path]) -> None:
    out, res, md = quick_run
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert "fig10_unprocessed_by_range.png" in pngs
    assert len(pngs) >= 8
    for name in pngs:
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (md.parent / "figs" / name).exists()
    text = md.read_text()
    assert text.startswith("# Results\n\nLead's text.\n\n")
    assert f"{END_MARKER}\n\nMiddle.\n\n{APPENDIX_BEGIN}\n" in text
    assert text.endswith(f"{APPENDIX_END}\n\nTail.\n")
    assert "STALE-SECTION" not in text
    assert "STALE-APPENDIX" not in text
    assert text.count(BEGIN_MARKER) == 1
    assert text.count(APPENDIX_BEGIN) == 1
    assert res["command"] in text
    assert "31.75" in text  # the paper's ATM number sits next to ours
    assert "](figs/fig10_unprocessed_by_range.png)" in text
    # Table I's carving line names both measures: all history rows and live arcs only.
    t1, alive = res["table1"], res["table1_alive_only"]
    assert (f"Arc carving: {t1['carving']:.1f} % of all history rows "
            f"({alive['carving']:.1f} % of live arcs only)") in text
    # The history sweep sentence names the smallest and largest history actually swept.
    hist = res["sensitivity"]["history"]
    lo, hi = min(hist["values"]), max(hist["values"])
    err = dict(zip(hist["values"], hist["carving"]["error_median"], strict=True))
    assert (f"carving's median true error {err[lo]:.3f} m with {lo:g} arcs, "
            f"{err[hi]:.3f} m with {hi:g})") in text


def test_unknown_experiment_is_a_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["experiments", "--only", "nope", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "nope" in err
    assert len(err.splitlines()) == 1
    assert not (tmp_path / "results.json").exists()


def test_help_lists_the_experiments(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["experiments", "--help"]) == 0
    text = capsys.readouterr().out
    for name in ("office", "t-junction", "openings", "sensitivity", "polling", "filters",
                 "real-log", "odometry"):
        assert name in text


def test_only_runs_the_named_experiments(tmp_path: Path) -> None:
    out = tmp_path / "out"
    code = main(["experiments", "--quick", "--only", "real-log", "--only", "odometry,polling",
                 "--out", str(out)])
    assert code == 0
    res = json.loads((out / "results.json").read_text())
    assert res["meta"]["experiments"] == ["real-log", "odometry", "polling"]
    assert {"appendix_real_log", "appendix_odometry", "appendix_polling"} <= set(res)
    assert "table1" not in res
    assert "appendix_filters" not in res
    assert res["meta"]["jobs"] == 0  # the appendix experiments plan no method runs
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert pngs == ["appendix-odometry.png", "appendix-polling.png", "appendix-real-log.png"]
    for name in pngs:
        assert (out / name).stat().st_size > 10_000
    assert sorted(p.name for p in out.glob("*.json")) == ["results.json"]


def test_only_refuses_to_rewrite_the_results_markdown(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    md = tmp_path / "RESULTS.md"
    assert main(["experiments", "--quick", "--only", "polling", "--out", str(tmp_path / "o"),
                 "--results-md", str(md)]) == 2
    assert "without --only" in capsys.readouterr().err
    assert not md.exists()



def test_a_local_cluster_gives_the_numbers_of_this_process(
    quick_run: tuple[Path, dict[str, Any], Path], tmp_path: Path,
) -> None:
    import faulthandler
    import sys

    # The serial numbers: the module's run of every experiment in this process (--quick: one
    # worker); its t-junction results are those of `--only t-junction --workers 1`.
    _, serial, _ = quick_run
    assert serial["meta"]["settings"]["jobs"] == 1
    faulthandler.dump_traceback_later(120, exit=True, file=sys.__stderr__)
    try:
        out = tmp_path / "2"
        assert main(["experiments", "--quick", "--only", "t-junction", "--workers", "2",
                     "--out", str(out)]) == 0
        cluster = json.loads((out / "results.json").read_text())
    finally:
        faulthandler.cancel_dump_traceback_later()
    assert cluster["meta"]["settings"]["jobs"] == 2
    keys = set(cluster) - {"command", "meta"}
    assert keys == {"t_junction"}
    assert {key: cluster[key] for key in keys} == {key: serial[key] for key in keys}
