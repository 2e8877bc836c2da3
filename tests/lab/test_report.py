"""The RESULTS.md section writer: only the span between the markers changes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.lab.appendix import BEGIN_MARKER as APPENDIX_BEGIN
from sonarcarve.lab.appendix import END_MARKER as APPENDIX_END
from sonarcarve.lab.appendix import AppendixError
from sonarcarve.lab.experiments import ExperimentResults
from sonarcarve.lab.output import json_ready
from sonarcarve.lab.report import (
    BEGIN_MARKER,
    END_MARKER,
    ReportError,
    _history_effect,
    _mean_between,
    check_results_md,
    replace_section,
    write_outputs,
)

NEW = f"{BEGIN_MARKER}\nnew\n{END_MARKER}"


def test_replaces_only_the_marked_span() -> None:
    text = f"head\n\n{BEGIN_MARKER}\nold 1\nold 2\n{END_MARKER}\n\ntail\n"
    assert replace_section(text, NEW) == f"head\n\n{NEW}\n\ntail\n"


def test_blank_text_becomes_the_section() -> None:
    assert replace_section("", NEW) == f"{NEW}\n"
    assert replace_section("\n \n", NEW) == f"{NEW}\n"


def test_text_without_markers_is_refused_unless_appending() -> None:
    with pytest.raises(ReportError, match=r"^README\.md: has no <!-- experiments:begin -->"):
        replace_section("# My notes\n", NEW, "README.md")
    assert replace_section("# Results\n", NEW, append_missing=True) == f"# Results\n\n{NEW}\n"
    assert replace_section("# Results", NEW, append_missing=True) == f"# Results\n\n{NEW}\n"


def test_is_idempotent() -> None:
    once = replace_section("a\n", NEW, append_missing=True)
    assert replace_section(once, NEW) == once


@pytest.mark.parametrize("text", [
    f"x\n{BEGIN_MARKER}\nno end\n",
    f"x\n{END_MARKER}\n{BEGIN_MARKER}\n",
    f"{BEGIN_MARKER}\n{END_MARKER}\n{BEGIN_MARKER}\n{END_MARKER}\n",
])
def test_broken_markers_raise_naming_the_file(text: str) -> None:
    with pytest.raises(ReportError, match=r"docs/RESULTS.md: line \d+"):
        replace_section(text, NEW, "docs/RESULTS.md")


def test_json_ready_makes_strict_json() -> None:
    data = {"a": math.nan, "b": (1, np.float64(2.5), math.inf), "c": {"d": np.int64(3)},
            "e": True, "f": np.array([1.0, np.nan]), "g": np.bool_(False), 7: "seven"}
    assert json_ready(data) == {"a": None, "b": [1, 2.5, None], "c": {"d": 3}, "e": True,
                                "f": [1.0, None], "g": False, "7": "seven"}


# -- the writer: existing files must hold the markers ------------------------------------------

def test_writer_refuses_a_file_without_markers_before_writing_anything(tmp_path: Path) -> None:
    md = tmp_path / "README.md"
    md.write_text("# My project\n\nHand-written text.\n")
    out = tmp_path / "out"
    with pytest.raises(ReportError, match=r"README\.md: has no") as info:
        write_outputs(ExperimentResults(), out, command="cmd", results_md=md)
    assert len(str(info.value).splitlines()) == 1
    assert md.read_text() == "# My project\n\nHand-written text.\n"
    assert not out.exists()


def test_writer_appends_the_appendix_only_to_a_results_file(tmp_path: Path) -> None:
    # The experiments markers make it a results file: a missing appendix section is appended.
    md = tmp_path / "RESULTS.md"
    md.write_text(f"{BEGIN_MARKER}\n{END_MARKER}\n\ntail\n")
    check_results_md(md)
    results = ExperimentResults(results={"appendix_meta": {}})
    write_outputs(results, tmp_path / "out", command="cmd", results_md=md)
    text = md.read_text()
    assert f"{END_MARKER}\n\ntail\n\n{APPENDIX_BEGIN}\n" in text
    assert text.endswith(f"{APPENDIX_END}\n")
    # Broken appendix markers are refused before anything is written.
    md.write_text(f"{BEGIN_MARKER}\n{END_MARKER}\n{APPENDIX_END}\n")
    with pytest.raises(AppendixError, match=r"RESULTS\.md: line 3"):
        check_results_md(md)
    with pytest.raises(AppendixError):
        write_outputs(results, tmp_path / "out2", command="cmd", results_md=md)
    assert md.read_text() == f"{BEGIN_MARKER}\n{END_MARKER}\n{APPENDIX_END}\n"
    assert not (tmp_path / "out2").exists()
    check_results_md(md, appendix=False)  # the experiments section alone is fine


def test_writer_creates_a_missing_file_and_keeps_text_around_markers(tmp_path: Path) -> None:
    md = tmp_path / "new.md"
    check_results_md(md)
    written = write_outputs(ExperimentResults(), tmp_path / "out", command="cmd-1",
                            results_md=md)
    assert md in written
    first = md.read_text()
    assert first.startswith(BEGIN_MARKER)
    assert first.rstrip().endswith(END_MARKER)
    assert "`cmd-1`" in first
    md.write_text(f"head\n\n{first}\ntail\n")
    write_outputs(ExperimentResults(), tmp_path / "out", command="cmd-2", results_md=md)
    second = md.read_text()
    assert second.startswith("head\n\n" + BEGIN_MARKER)
    assert second.endswith(f"{END_MARKER}\n\ntail\n")
    assert "`cmd-2`" in second
    assert "`cmd-1`" not in second
    assert APPENDIX_BEGIN not in second  # no appendix results, no appendix section
    assert APPENDIX_END not in second


# -- text helpers --------------------------------------------------------------------------------

def test_history_sentence_names_the_smallest_and_largest_history_swept() -> None:
    def sweep(values: list[float], errors: list[float | None]) -> dict[str, object]:
        return {"sensitivity": {"history": {"values": values,
                                            "carving": {"error_median": errors}}}}

    quick = _history_effect(sweep([50, 250], [0.059, 0.047]))
    assert "0.059 m with 50 arcs, 0.047 m with 250)" in quick
    shuffled = _history_effect(sweep([250, 2000, 50], [0.05, 0.04, 0.07]))
    assert "0.070 m with 50 arcs, 0.040 m with 2000)" in shuffled
    assert _history_effect(sweep([250], [0.05])) == ""  # one value: nothing to compare
    assert _history_effect(sweep([50, 250], [None, 0.05])) == ""


def test_binned_means_weight_bins_by_count() -> None:
    entry = {"edges": [0.0, 1.0, 2.0, 3.0], "value": [10.0, 40.0, None], "count": [3, 1, 5]}
    assert _mean_between(entry, high=1.0) == pytest.approx(10.0)
    assert _mean_between(entry, 0.0, 2.0) == pytest.approx((3 * 10.0 + 40.0) / 4)
    assert _mean_between(entry, 1.0) == pytest.approx(40.0)  # the empty bin is left out
    assert _mean_between(entry, 2.0) is None


def test_combined_sentence_compares_with_independent_latencies() -> None:
    from sonarcarve.lab.report import _combined_sentence

    def curve(values: list[float]) -> dict[str, object]:
        return {"edges": [0.0, 3.0, 6.0], "value": values, "count": [100, 100]}

    r = {"fig10": {"carving": curve([10.0, 50.0]), "atm": curve([20.0, 60.0]),
                   "combined": curve([5.0, 19.0])},
         "table1": {"carving": 30.0, "atm": 40.0, "combined": 12.0}}
    text = _combined_sentence(r)
    # Carving leaves 10 + 50 arcs unprocessed per 100 per bin: 50 / 60 of them beyond 3 m.
    assert "here 83 % of the arcs carving leaves unprocessed lie beyond 3 m" in text
    assert "ATM also leaves 60 % unprocessed" in text
    assert "30.0 % × 40.0 % = 12.0 %" in text
    # Per bin: (0.1 * 0.2 + 0.5 * 0.6) / 2 = 16 %.
    assert "range bin 16.0 %; it leaves 12.0 %" in text
    assert "55.59 % × 31.75 % = 17.6 %" in text
    assert _combined_sentence({"table1": r["table1"]}) == ""


def test_psi_sentence_says_whether_atm_error_is_monotone() -> None:
    from sonarcarve.lab.report import _psi_sentence

    def sweep(errors: list[float]) -> dict[str, object]:
        atm = {"error_median": errors, "refined_share": [80.0, 50.0, 40.0],
               "error_median_refined": [0.02, 0.02, 0.02],
               "error_median_fallback": [0.3, 0.2, 0.1],
               "fallback_median_range": [3.5, 2.5, 1.5]}
        return {"min_transversal_deg": {"values": [10.0, 45.0, 60.0], "atm": atm}}

    bumpy = _psi_sentence(sweep([0.03, 0.06, 0.04]))
    assert "is not monotone in ψ: 0.030 m at 10°, largest (0.060 m) at 45°, 0.040 m at 60°" \
        in bumpy
    assert "20 % of its points at 10° and 60 % at 60°" in bumpy
    assert "median range 3.50 m, error 0.300 m" in bumpy
    assert "rises from 0.030 m at 10° to 0.050 m at 60°" in _psi_sentence(
        sweep([0.03, 0.04, 0.05]))
    assert _psi_sentence({}) == ""
