"""The RESULTS.md section writer: only the span between the markers changes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.lab.experiments import ExperimentResults
from sonarcarve.lab.experiments.appendix_base import AppendixError
from sonarcarve.lab.experiments.filters import FiltersResult
from sonarcarve.lab.output import json_ready
from sonarcarve.lab.report import APPENDIX_BEGIN_MARKER as APPENDIX_BEGIN
from sonarcarve.lab.report import APPENDIX_END_MARKER as APPENDIX_END
from sonarcarve.lab.report import (
    BEGIN_MARKER,
    END_MARKER,
    ReportError,
    check_results_md,
    replace_section,
    result_json,
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


def _filters_result() -> FiltersResult:
    """A filters result with one variant of one method (numbers made up)."""
    entry = {"readings_dropped": 1.0, "points_before_map_filter": 9.0, "points_dropped": 0.0,
             "points": 9.0, "spurious_removed_by_filters": 10.0,
             "direct_removed_by_filters": 0.0, "spurious_removed": 20.0,
             "direct_removed": 5.0, "spurious_points": 4.0,
             "error": {"median": 0.02, "p90": None, "mean": 0.03}}
    return FiltersResult(
        scenario={"tour_m": 40.0, "seeds": 1, "whole_tour": False, "readings": 10.0,
                  "spurious_percent": 30.0},
        filters={"max_range_m": 3.81, "jump_threshold_m": 0.5, "outlier_radius_m": 0.3,
                 "outlier_neighbours": 2, "max_error_m": 0.14},
        variants={"none": "none"}, methods={"combined": {"none": entry}})


def test_typed_results_nest_under_their_json_key() -> None:
    data = result_json(_filters_result())
    assert set(data) == {"appendix_filters"}
    assert set(data["appendix_filters"]) == {"scenario", "filters", "variants", "methods"}
    # A missing value is null in JSON and the one marker in the Markdown.
    strict = json_ready(data)
    assert strict["appendix_filters"]["methods"]["combined"]["none"]["error"]["p90"] is None


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
    results = ExperimentResults(results={"filters": _filters_result()})
    write_outputs(results, tmp_path / "out", command="cmd", results_md=md)
    text = md.read_text()
    assert f"{END_MARKER}\n\ntail\n\n{APPENDIX_BEGIN}\n" in text
    assert text.endswith(f"{APPENDIX_END}\n")
    assert "### Appendix B: reading filters and map filters" in text
    assert "| combined | none | 1 | 0 | 10.0 / 20.0 | 0.0 / 5.0 | 9 | 4.0 | 2.0 cm / n/a |" \
        in text
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
