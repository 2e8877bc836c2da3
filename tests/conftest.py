"""Test-wide settings, and a fixture that loads a benchmark script as a module."""

import importlib.util
import os
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest
from hypothesis import settings

# No "compiling kernels" line on stderr (sonarcarve.cli.compile_notice): whether a command
# compiles depends on the cache's state, and many tests check a command's exact stderr.
# Inherited by the subprocesses tests start; tests of the notice set it back.
os.environ["SONARCARVE_COMPILE_NOTICE"] = "0"

# Property tests explore many cases but must not flake in CI: the same examples on every run
# (derandomize), and no per-example deadline (the first call of a numba kernel compiles it).
settings.register_profile("sonarcarve", derandomize=True, deadline=None)
settings.load_profile("sonarcarve")


@pytest.fixture(scope="session")
def benchmark_script() -> Callable[[str], ModuleType]:
    """``load(name)``: ``benchmarks/<name>.py`` imported as the module ``name`` (benchmarks/ is
    not a package; the module is registered in ``sys.modules`` because dataclasses look their
    module up by name; the folder goes on ``sys.path``, as for a script run from it, so that a
    script's ``from commits import ...`` finds its sibling)."""
    folder = Path(__file__).resolve().parents[1] / "benchmarks"

    def load(name: str) -> ModuleType:
        if str(folder) not in sys.path:
            sys.path.append(str(folder))
        spec = importlib.util.spec_from_file_location(name, folder / f"{name}.py")
        assert spec is not None
        assert spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        return module

    return load
