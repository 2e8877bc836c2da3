"""The sensitivity experiment: planning and its sentences on hand-made numbers."""

from __future__ import annotations

from sonarcarve.lab.experiments.sensitivity import SWEEP_METHODS, _psi_sentence, plan
from sonarcarve.lab.plan import Settings


def test_each_sweep_runs_the_methods_it_matters_to() -> None:
    settings = Settings.make(quick=True)
    jobs = plan(settings)
    for param, values in settings.sweeps:
        mine = [job for job in jobs if job.key[1] == param]
        assert len(mine) == len(values) * len(SWEEP_METHODS[param][0])
    history = [job for job in jobs if job.key[1] == "history"]
    assert {job.config.history_size for job in history} == {50, 250}
    # The history changes no simulation: every history run shares one scenario.
    assert len({job.scenario for job in history}) == 1


def test_psi_sentence_says_whether_atm_error_is_monotone() -> None:
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
