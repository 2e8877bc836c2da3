"""``benchmarks/grid_reads.py --split``: the carved grid's CPU split into compiled kernels and
the rest, found by the kernels' code in a profile."""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType

import pytest

from sonarcarve.grids.carved import kernels
from sonarcarve.warm import warm_stream


@pytest.fixture(scope="module")
def script(benchmark_script: Callable[[str], ModuleType]) -> ModuleType:
    return benchmark_script("grid_reads")


def test_the_kernels_are_known_by_their_code_and_plain_functions_are_not(
    script: ModuleType,
) -> None:
    codes = script._kernel_codes()
    refresh = kernels.refresh_kernel.py_func.__code__
    assert (refresh.co_filename, refresh.co_firstlineno, "refresh_kernel") in codes
    plain = script._run.__code__  # a Python function of the benchmark itself
    assert (plain.co_filename, plain.co_firstlineno, "_run") not in codes


def test_the_split_prints_a_row_per_resolution_with_shares_that_add_up(
    script: ModuleType, capsys: pytest.CaptureFixture[str]
) -> None:
    batch = warm_stream(400)
    script._split(batch, (-3.0, -3.0, 3.0, 3.0), [0.1, 0.2], [0, 5])
    rows = [line for line in capsys.readouterr().out.splitlines()
            if line.startswith("| 0.")]
    assert [row.split("|")[1].strip() for row in rows] == ["0.10", "0.20"]
    for row in rows:
        kernels_share, rest = (int(cell) for cell in row.split("|")[3:5])
        assert kernels_share + rest == 100
        assert 0 < kernels_share < 100  # both parts are there: kernels, and Python between
