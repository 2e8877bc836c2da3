"""The public API: what ``sonarcarve`` re-exports, and how it refuses wrong Python types.

The README says everything public in the product is re-exported from ``sonarcarve``; the error
classes are part of that (a caller must be able to write ``except sonarcarve.ReadingsError``).
"""

from __future__ import annotations

import importlib
import math
import pkgutil

import pytest

import sonarcarve
from sonarcarve import (
    MethodConfig,
    MethodStateError,
    ProcessError,
    Reading,
    ReadingBatch,
    ReadingTypeError,
    SonarcarveError,
    make_method,
    process_readings,
)

#: Modules whose names are not re-exported (README): the lab, the simulator, the command line,
#: and the fleet / runner / robot modules, whose functions are imported from them directly.
NOT_REEXPORTED = ("sonarcarve.lab", "sonarcarve.sim", "sonarcarve.cli", "sonarcarve.fleet",
                  "sonarcarve.runner", "sonarcarve.robot")


def _product_modules() -> list[str]:
    names = [info.name for info in pkgutil.walk_packages(sonarcarve.__path__, "sonarcarve.")]
    return [name for name in names if not name.startswith(NOT_REEXPORTED)]


def test_every_name_in_all_resolves() -> None:
    for name in sonarcarve.__all__:
        assert getattr(sonarcarve, name) is not None, name


def test_every_public_error_of_the_product_is_reexported() -> None:
    missing = []
    for module_name in _product_modules():
        module = importlib.import_module(module_name)
        for name, value in vars(module).items():
            if (isinstance(value, type) and issubclass(value, SonarcarveError)
                    and value.__module__ == module_name and not name.startswith("_")
                    and getattr(sonarcarve, name, None) is not value):
                missing.append(f"{module_name}.{name}")
    assert missing == []
    assert "SonarcarveError" in sonarcarve.__all__


def test_add_after_finish_is_a_sonarcarve_error_and_still_a_runtime_error() -> None:
    method = make_method("carve", MethodConfig(history_size=10))
    method.add(Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0))
    method.finish()
    with pytest.raises(MethodStateError, match="finished"):
        method.add(Reading(1.0, 0, 0.0, 0.0, 0.0, 1.0))
    assert issubclass(MethodStateError, SonarcarveError)
    assert issubclass(MethodStateError, RuntimeError)


@pytest.mark.parametrize(("reading", "field"), [
    (Reading(2.0, 0, 0.0, 0.0, 0.0, "abc"), "range"),  # type: ignore[arg-type]
    (Reading(2.0, 0, 0.0, 0.0, 0.0, None), "range"),  # type: ignore[arg-type]
    (Reading(2.0, 0, 0.0, 0.0, 0.0, 1 + 2j), "range"),  # type: ignore[arg-type]
    (Reading("2", 0, 0.0, 0.0, 0.0, 1.0), "t"),  # type: ignore[arg-type]
    (Reading(2.0, 0, None, 0.0, 0.0, 1.0), "x"),  # type: ignore[arg-type]
])
def test_a_field_of_the_wrong_type_is_named(reading: Reading, field: str) -> None:
    method = make_method("combined", MethodConfig(history_size=10))
    method.add(Reading(1.0, 0, 0.0, 0.0, 0.0, 1.0))
    with pytest.raises(ReadingTypeError, match=f"reading 1, column '{field}' must be a real"):
        method.add(reading)
    assert method.readings == 1  # nothing stored
    assert issubclass(ReadingTypeError, TypeError)


@pytest.mark.parametrize("thing", [(2.0, 0, 0, 0, 0, 1.0), None, "reading",
                                   (0.0, 0, 0.0, 0.0, 0.0, 1.0, math.nan, math.nan)])
def test_no_reading_at_all_is_refused_by_add(thing: object) -> None:
    method = make_method("centerline")
    with pytest.raises(ReadingTypeError, match="reading 0: expected a Reading"):
        method.add(thing)  # type: ignore[arg-type]
    assert method.readings == 0


def test_add_many_refuses_a_list() -> None:
    with pytest.raises(ReadingTypeError, match="add_many needs a ReadingBatch, got list"):
        make_method("carve").add_many([1, 2, 3])  # type: ignore[arg-type]


def test_process_readings_refuses_a_method_name_and_says_what_to_pass() -> None:
    batch = ReadingBatch.from_readings([Reading(0.0, 0, 0.0, 0.0, 0.0, 1.0)])
    with pytest.raises(ProcessError, match=r"pass make_method\('combined'\)"):
        process_readings(batch, "combined")  # type: ignore[arg-type]
    with pytest.raises(ReadingTypeError, match="needs a ReadingBatch, got list"):
        process_readings([], make_method("carve"))  # type: ignore[arg-type]


def test_a_filter_bound_that_is_no_number_is_named() -> None:
    with pytest.raises(sonarcarve.FilterError, match=r"max_range must be .* got str '3'"):
        sonarcarve.ReadingFilter(max_range="3")  # type: ignore[arg-type]


def test_a_parameter_that_is_no_number_reads_as_english() -> None:
    with pytest.raises(sonarcarve.ConfigError,
                       match=r"min_transversal must be a number and lie in \(0, pi/2\] radians"):
        MethodConfig(min_transversal="x")  # type: ignore[arg-type]
