"""The office experiment's sentences on hand-made numbers."""

from __future__ import annotations

import pytest

from sonarcarve.lab.experiments.office_text import (
    _combined_sentence,
    _history_effect,
    _mean_between,
)


def test_history_sentence_names_the_smallest_and_largest_history_swept() -> None:
    def sweep(values: list[float], errors: list[float | None]) -> dict[str, object]:
        return {"history": {"values": values, "carving": {"error_median": errors}}}

    quick = _history_effect(sweep([50, 250], [0.059, 0.047]))
    assert "0.059 m with 50 arcs, 0.047 m with 250)" in quick
    shuffled = _history_effect(sweep([250, 2000, 50], [0.05, 0.04, 0.07]))
    assert "0.070 m with 50 arcs, 0.040 m with 2000)" in shuffled
    assert _history_effect(sweep([250], [0.05])) == ""  # one value: nothing to compare
    assert _history_effect(sweep([50, 250], [None, 0.05])) == ""
    assert _history_effect(None) == ""  # no sensitivity run


def test_binned_means_weight_bins_by_count() -> None:
    entry = {"edges": [0.0, 1.0, 2.0, 3.0], "value": [10.0, 40.0, None], "count": [3, 1, 5]}
    assert _mean_between(entry, high=1.0) == pytest.approx(10.0)
    assert _mean_between(entry, 0.0, 2.0) == pytest.approx((3 * 10.0 + 40.0) / 4)
    assert _mean_between(entry, 1.0) == pytest.approx(40.0)  # the empty bin is left out
    assert _mean_between(entry, 2.0) is None


def test_combined_sentence_compares_with_independent_latencies() -> None:
    def curve(values: list[float]) -> dict[str, object]:
        return {"edges": [0.0, 3.0, 6.0], "value": values, "count": [100, 100]}

    r = {"fig10": {"carving": curve([10.0, 50.0]), "atm": curve([20.0, 60.0]),
                   "combined": curve([5.0, 19.0])},
         "table1": {"carving": 30.0, "atm": 40.0, "combined": 12.0}}
    text = _combined_sentence(r["fig10"], r["table1"])
    # Carving leaves 10 + 50 arcs unprocessed per 100 per bin: 50 / 60 of them beyond 3 m.
    assert "here 83 % of the arcs carving leaves unprocessed lie beyond 3 m" in text
    assert "ATM also leaves 60 % unprocessed" in text
    assert "30.0 % × 40.0 % = 12.0 %" in text
    # Per bin: (0.1 * 0.2 + 0.5 * 0.6) / 2 = 16 %.
    assert "range bin 16.0 %; it leaves 12.0 %" in text
    assert "55.59 % × 31.75 % = 17.6 %" in text
    assert _combined_sentence({}, r["table1"]) == ""
