"""Test-wide settings."""

from hypothesis import settings

# Property tests explore many cases but must not flake in CI: the same examples on every run
# (derandomize), and no per-example deadline (the first call of a numba kernel compiles it).
settings.register_profile("sonarcarve", derandomize=True, deadline=None)
settings.load_profile("sonarcarve")
