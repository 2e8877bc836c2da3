"""The confidence's use of other sensors' support (methods/evidence.py): ``others`` per
``looks_per_support`` looks of other sensors, and ``alone``.

Expected values are worked out by hand from the definitions in ``ConfidenceModel``'s docstring.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.errors import ConfigError
from sonarcarve.methods.evidence import CONFIDENCE_FEATURES, ConfidenceModel, EvidenceMethod
from sonarcarve.readings import ReadingBatch

OTHERS = CONFIDENCE_FEATURES.index("others")
ALONE = CONFIDENCE_FEATURES.index("alone")


def _method(model: ConfidenceModel) -> EvidenceMethod:
    """Evidence carving with ``model`` after four readings of four sensors (their arcs'
    per-arc sums are then set by hand)."""
    method = EvidenceMethod(history_size=10, min_confidence=0.0, confidence_model=model)
    method.add_many(ReadingBatch.from_arrays(
        t=np.arange(4.0), sensor=np.arange(4), x=np.zeros(4), y=np.zeros(4),
        theta=np.array([0.0, 1.5, 3.0, 4.5]), range=np.full(4, 2.0),
        beam_width=np.full(4, math.radians(22.5))))
    return method


@pytest.mark.parametrize(("looks_per_support", "expected"), [
    # others 2, 0.5, 3, 0.25 from 64, 8, 0, 48 looks of other sensors. 16 looks per unit of
    # support: 2 / 4 = 0.5; 8 looks count as 16 (at least one unit): 0.5; no look: 3, capped
    # at 1; 0.25 / 3.
    (16.0, [0.5, 0.5, 1.0, 0.25 / 3.0]),
    # inf (the default): the support alone, capped at 1.
    (math.inf, [1.0, 0.5, 1.0, 0.25]),
    # 4 looks per unit: 2 / 16, 0.5 / 2, 3 capped, 0.25 / 12.
    (4.0, [0.125, 0.25, 1.0, 0.25 / 12.0]),
])
def test_others_is_support_per_looks_of_other_sensors(looks_per_support: float,
                                                      expected: list[float]) -> None:
    method = _method(ConfidenceModel(looks_per_support=looks_per_support))
    model = method.models[0]
    slots = method.history.slots()
    model.others[slots] = [2.0, 0.5, 3.0, 0.25]  # type: ignore[attr-defined]
    model.covering[slots] = [64.0, 8.0, 0.0, 48.0]  # type: ignore[attr-defined]
    features = method.features(slots)
    np.testing.assert_allclose(features[:, OTHERS], expected, rtol=1e-15)
    np.testing.assert_array_equal(features[:, ALONE], [0.0, 0.0, 1.0, 0.0])


def test_alone_adds_its_weight_to_the_logit() -> None:
    # Two arcs alike but for alone: their fitted logits differ by the weight (maturity 1).
    model = ConfidenceModel(alone=0.7)
    features = np.zeros((2, len(CONFIDENCE_FEATURES)))
    features[1, ALONE] = 1.0
    logit = np.log(1.0 / model.confidence(features) - 1.0)
    assert logit[0] - logit[1] == pytest.approx(0.7, abs=1e-12)


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan])
def test_looks_per_support_must_be_positive(value: float) -> None:
    with pytest.raises(ConfigError, match="looks_per_support must be > 0"):
        ConfidenceModel(looks_per_support=value)


def test_the_default_does_not_normalise() -> None:
    assert ConfidenceModel().looks_per_support == math.inf
