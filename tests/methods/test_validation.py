"""One validation of a reading and of a method's parameters, whatever the way in.

``SonarMethod.add`` / ``add_many`` and ``ReadingBatch`` refuse the same readings with the same
messages; ``MethodConfig``, the method constructors and the CLI refuse the same parameters. A
refused reading leaves the method exactly as it was.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sonarcarve.errors import ConfigError, ReadingsError, SonarcarveError
from sonarcarve.history import MAX_HISTORY_SIZE
from sonarcarve.methods import (
    METHODS,
    AtmMethod,
    CarvingMethod,
    CenterlineMethod,
    CombinedMethod,
    MethodConfig,
    SonarMethod,
    make_method,
)
from sonarcarve.methods.atm import AtmModel
from sonarcarve.methods.evidence import CONFIDENCE_FEATURES, ConfidenceModel, SensorModel
from sonarcarve.readings import Reading, ReadingBatch

GOOD = Reading(1.0, 0, 0.0, 0.0, 0.0, 2.0)

BAD_BEAM = "must lie in [1e-06, pi) radians (22.5 degrees is 0.39)"

# (field overrides of a reading at t = 2, the column named in the error, the problem).
BAD_READINGS = [
    ({"t": math.nan}, "t", "is NaN or infinite"),
    ({"t": math.inf}, "t", "is NaN or infinite"),
    ({"x": math.nan}, "x", "is NaN or infinite"),
    ({"y": -math.inf}, "y", "is NaN or infinite"),
    ({"theta": math.nan}, "theta", "is NaN or infinite"),
    ({"range": math.inf}, "range", "is infinite but 'max_range' is not given"),
    ({"range": -math.inf}, "range", "is NaN or infinite"),
    ({"range": 2.0, "max_range": 1.5}, "range", "exceeds 'max_range'"),
    ({"range": math.nan}, "range", "is NaN or infinite"),
    ({"range": 0.0}, "range", "must be > 0"),
    ({"range": -1.0}, "range", "must be > 0"),
    ({"sensor": -1}, "sensor", "must be >= 0"),
    ({"sensor": 1.5}, "sensor", "is not a whole number"),
    ({"sensor": 2**31}, "sensor", "must be at most 2147483647"),
    ({"beam_width": 0.0}, "beam_width", BAD_BEAM),
    ({"beam_width": math.radians(225.0)}, "beam_width", BAD_BEAM),
    ({"beam_width": math.pi}, "beam_width", BAD_BEAM),
    ({"beam_width": math.inf}, "beam_width", BAD_BEAM),
    # Underflowing widths: evidence carving divided by zero or indexed out of its bins.
    ({"beam_width": 5e-324}, "beam_width", BAD_BEAM),
    ({"beam_width": 9.9e-7}, "beam_width", BAD_BEAM),
    ({"t": 0.5}, "t", "goes backwards in time"),  # the previous reading is at t = 1
]


def _snapshot(method: SonarMethod) -> tuple[object, ...]:
    local = method.local_map()
    measures = method.measures()
    return (method.readings, len(method.history), local.reading_id.tolist(),
            local.xy.tolist(), measures.unprocessed_share, measures.fully_carved)


@pytest.mark.parametrize("name", sorted(METHODS))
@pytest.mark.parametrize(("change", "column", "problem"), BAD_READINGS)
def test_add_refuses_a_bad_reading_and_changes_nothing(
    name: str, change: dict[str, float], column: str, problem: str
) -> None:
    method = make_method(name, MethodConfig(history_size=5))
    method.add(GOOD)
    before = _snapshot(method)
    bad = GOOD._replace(t=2.0)._replace(**change)
    with pytest.raises(ReadingsError) as caught:
        method.add(bad)
    assert isinstance(caught.value, SonarcarveError)
    assert str(caught.value) == f"reading 1, column {column!r} {problem}"
    assert _snapshot(method) == before
    method.add(GOOD._replace(t=2.0, range=1.0))  # the stream goes on, ids unbroken
    assert method.local_map().reading_id.tolist()[-1] == 1


def test_inf_range_no_longer_poisons_the_combined_map() -> None:
    method = CombinedMethod(history_size=60)
    for i in range(50):
        method.add(Reading(0.1 * i, i % 4, 0.05 * i, 0.0, 1.5, 1.0 + 0.01 * i))
    with pytest.raises(ReadingsError,
                       match="column 'range' is infinite but 'max_range' is not given"):
        method.add(Reading(5.0, 0, 2.5, 0.0, 1.5, math.inf))
    points = method.finish()
    assert len(points) > 0
    assert np.isfinite(points.xy).all()


def test_nan_beam_width_means_the_method_default() -> None:
    method = CenterlineMethod(beam_width=0.3)
    method.add(GOOD)  # beam_width NaN
    assert method.history.beam_width[0] == 0.3
    assert method.local_map().width.tolist() == [0.3]


def test_equal_times_are_accepted() -> None:
    method = CenterlineMethod()
    method.add(GOOD)
    method.add(GOOD._replace(sensor=1))
    assert method.readings == 2


def _raw_batch(**change: list[float]) -> ReadingBatch:
    """A batch built without validation, as a caller could."""
    columns = {"t": [2.0, 3.0, 4.0], "x": [0.0, 0.1, 0.2], "y": [0.0, 0.0, 0.0],
               "theta": [0.0, 0.0, 0.0], "range": [1.0, 1.5, 2.0],
               "beam_width": [math.nan] * 3, **change}
    return ReadingBatch(sensor=np.array([0, 1, 2]),
                        **{k: np.asarray(v, dtype=float) for k, v in columns.items()})


@pytest.mark.parametrize(("change", "message"), [
    ({"range": [1.0, 1.5, -2.0]}, "reading 3, column 'range' must be > 0"),
    ({"theta": [0.0, math.nan, 0.0]}, "reading 2, column 'theta' is NaN or infinite"),
    ({"t": [0.5, 3.0, 4.0]}, "reading 1, column 't' goes backwards in time"),
    ({"t": [2.0, 3.0, 2.5]}, "reading 3, column 't' goes backwards in time"),
    ({"beam_width": [0.3, 4.0, 0.3]}, "reading 2, column 'beam_width' must lie in [1e-06, pi)"),
    ({"beam_width": [0.3, 1e-40, 0.3]}, "reading 2, column 'beam_width' must lie in [1e-06, pi)"),
])
def test_add_many_validates_the_batch_once_and_changes_nothing(
    change: dict[str, list[float]], message: str
) -> None:
    method = CarvingMethod(history_size=5)
    method.add(GOOD)
    before = _snapshot(method)
    with pytest.raises(ReadingsError) as caught:
        method.add_many(_raw_batch(**change))
    assert message in str(caught.value)
    assert _snapshot(method) == before
    method.add_many(_raw_batch())
    assert method.readings == 4


def test_add_many_does_not_check_reading_by_reading(monkeypatch: pytest.MonkeyPatch) -> None:
    import sonarcarve.methods.base as base

    def refuse(*args: object) -> None:
        raise AssertionError("add_many re-validated a reading")

    monkeypatch.setattr(base, "check_reading", refuse)
    method = CenterlineMethod()
    method.add_many(_raw_batch())
    assert method.readings == 3


# The cheap check add_many runs first (methods.base._plainly_valid) may only ever say "valid" to
# a batch ReadingBatch.validate passes: anything else goes to validate, whose error is raised.
_EDGES = {
    "t": [math.nan, math.inf, -math.inf, 1e12, 1e12 + 1e-3, -1e12, -2e12],
    "x": [math.nan, math.inf, 1e6, -1e6, 1e6 * (1 + 1e-15), -2e6],
    "y": [math.nan, -math.inf, 1e6, -1e6 - 1.0],
    "theta": [math.nan, math.inf, 1e6, -1e6, 1e6 + 1.0],
    "range": [math.nan, math.inf, -math.inf, 0.0, -0.0, -1.0, 5e-324, 1e4, 1e4 + 1e-9],
    "beam_width": [math.nan, 0.0, -0.0, 5e-324, math.pi, math.nextafter(math.pi, 0.0), 4.0,
                   math.inf, -math.inf],
    "max_range": [math.nan, math.inf, 0.0, -1.0, 1.0, 1e4, 1e4 + 1e-9, 5e-324],
    "sensor": [-1, 0, 2**31 - 1, 2**31, 2**62],
}


def _validates(batch: ReadingBatch, previous_t: float) -> bool:
    try:
        batch.validate(first_id=0, previous_t=previous_t)
    except ReadingsError:
        return False
    return True


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_cheap_check_says_valid_only_when_validate_passes(seed: int) -> None:
    from sonarcarve.methods.base import _plainly_valid

    rng = np.random.default_rng(seed)
    agreed = 0
    for _ in range(3_000):
        n = int(rng.integers(1, 6))
        columns: dict[str, np.ndarray] = {
            "t": np.sort(rng.uniform(0.0, 10.0, n)), "x": rng.normal(0, 3, n),
            "y": rng.normal(0, 3, n), "theta": rng.uniform(-7, 7, n),
            "range": rng.uniform(0.1, 5.0, n),
            "beam_width": np.where(rng.random(n) < 0.5, math.nan, rng.uniform(0.1, 1.0, n)),
            "max_range": np.where(rng.random(n) < 0.5, math.nan, rng.uniform(5.0, 9.0, n)),
            "sensor": rng.integers(0, 16, n).astype(np.int64),
        }
        for _ in range(int(rng.integers(0, 3))):  # zero, one or two cells at an edge
            name = str(rng.choice(list(_EDGES)))
            columns[name][int(rng.integers(0, n))] = rng.choice(_EDGES[name])
        if rng.random() < 0.2 and n > 1:  # time going backwards inside the batch
            columns["t"][1:] = columns["t"][:-1] - rng.choice([0.0, 1e-9, 1.0])
        batch = ReadingBatch(**columns)
        previous_t = float(rng.choice([-math.inf, 0.0, columns["t"][0], 20.0]))
        valid = _validates(batch, previous_t)
        cheap = _plainly_valid(batch, previous_t)
        assert valid or not cheap, (columns, previous_t)
        agreed += cheap == valid
    assert agreed > 2_500  # it is not "never valid": most batches take the cheap way


def test_the_cheap_check_leaves_other_array_types_and_no_echo_rows_to_validate() -> None:
    from sonarcarve.methods.base import _plainly_valid

    good = _raw_batch()
    assert _plainly_valid(good, -math.inf)
    strided = ReadingBatch(**{name: np.repeat(getattr(good, name), 2)[::2]
                              for name in ("t", "sensor", "x", "y", "theta", "range",
                                           "beam_width", "max_range")})
    assert not _plainly_valid(strided, -math.inf)  # not contiguous: no new kernel compiled
    assert _validates(strided, -math.inf)
    as_float = _raw_batch()
    object.__setattr__(as_float, "sensor", as_float.sensor.astype(float))
    assert not _plainly_valid(as_float, -math.inf)
    no_echo = _raw_batch(range=[1.0, math.inf, 2.0])
    object.__setattr__(no_echo, "max_range", np.array([6.0, 6.0, 6.0]))
    assert not _plainly_valid(no_echo, -math.inf)
    assert _validates(no_echo, -math.inf)
    short = _raw_batch()
    object.__setattr__(short, "x", short.x[:2])
    assert not _plainly_valid(short, -math.inf)


def test_a_counting_sink_counts_what_the_points_would_have_given() -> None:
    from sonarcarve.maps import CountingSink

    stream = ReadingBatch.from_readings(
        [GOOD._replace(t=1.0 + 0.01 * k, sensor=k % 8, theta=0.4 * (k % 8),
                       range=1.0 + 0.1 * (k % 5), x=0.01 * k) for k in range(600)])

    class Subclass(CountingSink):  # not the exact type: made the points, as before
        pass

    counted = []
    for sink in (CountingSink(), Subclass()):
        method = make_method("combined", MethodConfig(history_size=50))
        method.set_global_sink(sink)
        method.add_many(stream)
        method.finish()
        counted.append((sink.points, sink.by_source.tolist(), method.committed_points))
    memory = make_method("combined", MethodConfig(history_size=50))
    memory.add_many(stream)
    points = memory.finish()
    by_source = np.bincount(points.source.astype(np.int64), minlength=3)[:3].tolist()
    assert counted[0] == counted[1] == (len(points), by_source, len(points))


# -- parameters --------------------------------------------------------------------------------

BAD_PARAMETERS = [
    ("history_size", 0), ("history_size", -3), ("history_size", 100_001), ("history_size", True),
    ("history_size", 2.5), ("history_size", "10"),
    ("beam_width", 0.0), ("beam_width", math.pi), ("beam_width", -0.1), ("beam_width", math.nan),
    ("beam_width", math.inf), ("beam_width", "wide"),
    ("range_tolerance", -0.01), ("range_tolerance", math.nan), ("range_tolerance", math.inf),
    ("min_transversal", -0.1), ("min_transversal", 0.0), ("min_transversal", 0.5 * math.pi + 1e-9),
    ("min_transversal", math.nan),
    ("range_resolution", -1.0), ("range_resolution", math.inf), ("range_resolution", math.nan),
    ("max_incidence", -0.1), ("max_incidence", 1.6), ("max_incidence", math.nan),
]


@pytest.mark.parametrize(("field", "value"), BAD_PARAMETERS)
def test_method_config_refuses_each_bad_field(field: str, value: object) -> None:
    with pytest.raises(ConfigError) as caught:
        MethodConfig(**{field: value})  # type: ignore[arg-type]
    message = str(caught.value)
    assert isinstance(caught.value, SonarcarveError)
    assert isinstance(caught.value, ValueError)
    assert message.startswith(f"{field} must ")
    assert message.endswith(f"got {value!r}")
    assert "\n" not in message


@pytest.mark.parametrize(("field", "value"), [
    ("history_size", 1), ("history_size", 100_000), ("history_size", np.int64(7)),
    ("beam_width", 1e-6), ("beam_width", 3.14), ("range_tolerance", 0.0),
    ("min_transversal", 1e-9), ("min_transversal", 0.5 * math.pi), ("range_resolution", 0.0),
    ("max_incidence", 0.0), ("max_incidence", 0.5 * math.pi),
])
def test_method_config_accepts_the_edges(field: str, value: object) -> None:
    assert getattr(MethodConfig(**{field: value}), field) == value  # type: ignore[arg-type]


@pytest.mark.parametrize(("cls", "field", "value"), [
    (CenterlineMethod, "beam_width", 4.0),
    (CenterlineMethod, "history_size", 0),
    (CarvingMethod, "range_tolerance", -1.0),
    (CarvingMethod, "max_incidence", 2.0),
    (AtmMethod, "min_transversal", 2.0),
    (AtmMethod, "range_resolution", math.inf),
    (CombinedMethod, "history_size", 10**6),
    (CombinedMethod, "beam_width", 0.0),
])
def test_constructors_refuse_with_the_configs_message(
    cls: type[SonarMethod], field: str, value: object
) -> None:
    with pytest.raises(ConfigError) as from_config:
        MethodConfig(**{field: value})  # type: ignore[arg-type]
    with pytest.raises(ConfigError) as from_constructor:
        cls(**{field: value})  # type: ignore[arg-type]
    assert str(from_constructor.value) == str(from_config.value)


def test_make_method_refuses_an_unknown_name_and_a_dict() -> None:
    with pytest.raises(ConfigError, match=r"^unknown method 'carving'; choose one of "):
        make_method("carving")
    with pytest.raises(ConfigError, match=r"^config must be a MethodConfig, got dict"):
        make_method("carve", {"history_size": 10})  # type: ignore[arg-type]


def test_make_method_passes_every_field_on() -> None:
    config = MethodConfig(history_size=9, beam_width=0.3, range_tolerance=0.02,
                          min_transversal=0.4, range_resolution=0.01, max_incidence=0.7)
    method = make_method("combined", config)
    assert isinstance(method, CombinedMethod)
    assert (method.history.capacity, method.beam_width, method.range_tolerance,
            method.min_transversal, method.range_resolution, method.max_incidence) == (
        9, 0.3, 0.02, 0.4, 0.01, 0.7)


def test_atm_accepts_every_history_with_a_store_that_grows_on_demand() -> None:
    # Room for every possible crossing would be 2n rows x 4(n - 1) float32: 3.2 GB at n =
    # 10,000, 128 GB at the largest history. The store starts small and grows with the
    # crossings actually kept (test_atm.py), so every valid history size is accepted.
    for method in ("atm", "combined"):
        for size in (10_000, MAX_HISTORY_SIZE):
            made = make_method(method, MethodConfig(history_size=size))
            model = next(m for m in made.models if isinstance(m, AtmModel))
            assert model.bearings.nbytes <= 2 * size * 32 * 4
    assert make_method("carve", MethodConfig(history_size=6000)).history.capacity == 6000


@pytest.mark.parametrize(("field", "value"), [
    # 0 divided a brand-new arc's age by 0 (NaN confidence), NaN made every confidence NaN, a
    # negative time left every arc fresh whatever its age.
    ("maturity_time", 0.0), ("maturity_time", -1.0), ("maturity_time", math.nan),
    ("maturity_time", math.inf), ("maturity_time", "2 s"),
    ("intercept", math.nan), ("others", math.inf), ("fresh", -math.inf), ("unheard", None),
])
def test_confidence_model_refuses_each_bad_field(field: str, value: object) -> None:
    with pytest.raises(ConfigError) as caught:
        ConfidenceModel(**{field: value})  # type: ignore[arg-type]
    rule = "be finite and > 0 seconds" if field == "maturity_time" else "be finite"
    assert str(caught.value) == f"ConfidenceModel.{field} must {rule}, got {value!r}"


def test_confidence_model_accepts_any_finite_weight_and_a_short_maturity() -> None:
    model = ConfidenceModel(maturity_time=1e-9, others=-50.0, intercept=0.0)
    # Fresh at age 0, mature (the fitted logit: intercept only, no feature) from 1e-9 s on.
    no_features = np.zeros((2, len(CONFIDENCE_FEATURES)))
    confidence = model.confidence(no_features, model.maturity(np.array([0.0, 1.0])))
    np.testing.assert_allclose(confidence, [1 / (1 + math.exp(-model.fresh)), 0.5])


@pytest.mark.parametrize(("field", "value", "rule"), [
    ("edge_gain", 0.0, "lie in (0, 1]"), ("edge_gain", 1.5, "lie in (0, 1]"),
    ("incidence_full", -0.1, "lie in [0, pi/2) radians"),
    ("incidence_full", 0.5 * math.pi, "lie in [0, pi/2) radians"),
    # The default incidence_full is 10 degrees: the gain's ramp would have no width.
    ("incidence_zero", math.radians(10.0), "lie above incidence_full and at most pi/2 radians"),
    ("incidence_zero", 1.6, "lie above incidence_full and at most pi/2 radians"),
    ("rough", -0.01, "lie in [0, 1]"), ("rough", math.nan, "lie in [0, 1]"),
    ("max_detect", 1.0, "lie in (0, 1)"), ("max_detect", 0.0, "lie in (0, 1)"),
    ("range_scale", 0.0, "be > 0 metres (inf: no fall with range)"),
    ("support_tolerance", math.inf, "be finite and >= 0 metres"),
    ("support_tolerance", -0.01, "be finite and >= 0 metres"),
    ("establish", 0.0, "be > 0 (inf: no bin is ever established)"),
    ("protect", 1.1, "lie in [0, 1]"),
    ("viewpoint_spacing", -0.25, "be finite and >= 0 metres"),
    ("transmit", math.nan, "lie in [0, 1]"),
    ("confirm", 0.0, "be finite and > 0"),
])
def test_sensor_model_refuses_each_bad_field(field: str, value: float, rule: str) -> None:
    with pytest.raises(ConfigError) as caught:
        SensorModel(**{field: value})  # type: ignore[arg-type]
    assert str(caught.value) == f"SensorModel.{field} must {rule}, got {value!r}"


def test_sensor_model_accepts_the_edges() -> None:
    edges = SensorModel(edge_gain=1.0, incidence_full=0.0, incidence_zero=0.5 * math.pi,
                        rough=1.0, max_detect=1e-9, range_scale=math.inf, support_tolerance=0.0,
                        establish=math.inf, protect=0.0, viewpoint_spacing=0.0, transmit=0.0,
                        confirm=1e-9)
    assert edges.range_scale == math.inf
