"""The registry: every experiment has the same shape; the runner refuses unknown names."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from sonarcarve.lab.experiments import (
    EXPERIMENTS,
    ExperimentError,
    Settings,
    run_experiments,
)
from sonarcarve.lab.experiments.base import Page
from sonarcarve.lab.report import result_json, settings_json

#: The experiments the issue asks for, by name, with their section of RESULTS.md.
NAMES = {"office": "experiments", "t-junction": "experiments", "openings": "experiments",
         "sensitivity": "experiments", "polling": "appendix", "filters": "appendix",
         "real-log": "appendix", "odometry": "appendix"}


def test_registry_holds_every_experiment_once_by_its_own_name() -> None:
    assert {name: e.section for name, e in EXPERIMENTS.items()} == NAMES
    for name, experiment in EXPERIMENTS.items():
        assert experiment.name == name
        assert experiment.title


def test_bad_requests_raise() -> None:
    with pytest.raises(ExperimentError, match="nope"):
        run_experiments(Settings.make(quick=True), ["nope"])
    with pytest.raises(ExperimentError, match="seeds"):
        Settings.make(seeds=0)


def test_quick_plans_are_small_and_distinct() -> None:
    settings = Settings.make(quick=True)
    for name, experiment in EXPERIMENTS.items():
        jobs = experiment.plan(settings)
        if NAMES[name] == "appendix":  # they run in summarise, with no jobs
            assert jobs == []
            continue
        keys = [job.key for job in jobs]
        assert len(keys) == len(set(keys))
        assert 0 < len(jobs) <= 60
    full = Settings.make()
    assert full.seeds == 3
    assert math.isclose(full.method_config().beam_width, math.radians(22.5))


def test_one_experiment_runs_alone_through_every_stage(tmp_path: Path) -> None:
    settings = Settings.make(quick=True)
    run = run_experiments(settings, ["t-junction"])
    assert list(run.results) == ["t-junction"]
    assert run.jobs == len(EXPERIMENTS["t-junction"].plan(settings))
    result = run.results["t-junction"]
    # The typed result goes to results.json under its own key.
    data = result_json(result)
    assert set(data) == {"t_junction"}
    assert set(data["t_junction"]) == {"points", "radius_m", "all", "refined", "end_distance_m"}
    experiment = EXPERIMENTS["t-junction"]
    written = experiment.figure(result, run.artifacts["t-junction"], tmp_path)
    assert [p.name for p in written] == ["fig04_t_junction.png"]
    page = Page({"fig04_t_junction.png": "figs/fig04_t_junction.png"}, settings, run.results)
    lines = [line for part in experiment.markdown(result, page) for line in part.lines]
    assert lines[0] == "### Fig. 4: T junction, when the facing wall appears"
    assert "![Fig. 4](figs/fig04_t_junction.png)" in lines


def test_settings_json_gives_the_method_config_in_degrees() -> None:
    out = settings_json(Settings.make(quick=True))
    assert out["method_config"]["beam_width_deg"] == pytest.approx(22.5)
    assert out["sweeps"]["history"] == [50, 250]


@pytest.mark.slow
def test_full_size_runs_show_the_papers_qualitative_claims() -> None:
    # Paper Fig. 4: ATM's refined map shows the approaching wall later than carving's (or never).
    # Paper Fig. 2: next to a door, carving's map shows it passable at least as often as
    # centerline's.
    res = run_experiments(Settings.make(seeds=1), ["t-junction", "openings"]).results
    refined = res["t-junction"].refined
    carving_at = refined["carving"]["mean"]
    atm_at = refined["atm"]["mean"]
    assert carving_at is not None
    assert atm_at is None or atm_at < carving_at
    doors = res["openings"].openings_by_world
    door_share = {m: np.mean([v for k, v in doors[m]["1"].items() if k.startswith("doorway")])
                  for m in ("carving", "centerline")}
    assert door_share["carving"] >= door_share["centerline"]
