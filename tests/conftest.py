"""Test-wide settings."""

import os

from hypothesis import settings

# No "compiling kernels" line on stderr (sonarcarve.cli.compile_notice): whether a command
# compiles depends on the cache's state, and many tests check a command's exact stderr.
# Inherited by the subprocesses tests start; tests of the notice set it back.
os.environ["SONARCARVE_COMPILE_NOTICE"] = "0"

# Property tests explore many cases but must not flake in CI: the same examples on every run
# (derandomize), and no per-example deadline (the first call of a numba kernel compiles it).
settings.register_profile("sonarcarve", derandomize=True, deadline=None)
settings.load_profile("sonarcarve")
