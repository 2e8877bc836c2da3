"""``benchmarks/fit_confidence.py --only``: one weight fitted, every other part of the model held
(the way evidence carving's ``behind`` weight was fitted, so the live map stays as it was)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from types import ModuleType

import numpy as np
import pytest

from sonarcarve.methods.evidence import CONFIDENCE_FEATURES, ConfidenceModel


@pytest.fixture(scope="module")
def fit_confidence(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    """``benchmarks/fit_confidence.py`` as a module."""
    return benchmark_script("fit_confidence")


def test_only_recovers_the_one_weight_and_holds_the_rest(fit_confidence: ModuleType) -> None:
    # Labels drawn from the default model with behind's weight set to -0.8: fitting behind
    # alone from the default (its own weight there is not -0.8) must find -0.8 within the
    # sampling noise, and leave every other field exactly as it was.
    rng = np.random.default_rng(3)
    n = 40_000
    features = rng.uniform(0.0, 1.0, (n, len(CONFIDENCE_FEATURES)))
    behind = CONFIDENCE_FEATURES.index("behind")
    features[:, behind] = rng.uniform(0.0, 3.0, n)
    base = dataclasses.replace(ConfidenceModel(), behind=0.3)
    truth = dataclasses.replace(base, behind=-0.8)
    logit = truth.intercept + sum(features[:, k] * w for k, w in enumerate(truth.weights()))
    labels = (rng.uniform(size=n) < 1.0 / (1.0 + np.exp(-logit))).astype(float)
    fitted = fit_confidence.fit_only(features, labels, ("behind",), base, ridge=0.0)
    assert fitted.behind == pytest.approx(-0.8, abs=0.06)
    assert dataclasses.replace(fitted, behind=base.behind) == base


def test_only_is_an_option_of_the_script(fit_confidence: ModuleType) -> None:
    # An unknown feature is refused by the command line (before any simulation runs).
    with pytest.raises(SystemExit):
        fit_confidence.main(["--only", "no-such-feature"])
