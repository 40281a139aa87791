import os
import warnings

import pytest
from hypothesis import settings

# Rendering tests run headless; the tests' shared helpers are the package tests.support.
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

# Property tests are deterministic by default: the same examples on every run and machine, so
# the test command (CI's) cannot turn red on a draw. Exploration draws new examples:
#   python -m pytest --hypothesis-profile=explore tests/math/test_solver_scales.py
settings.register_profile("deterministic", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile("deterministic")

# A warning the project's own code raises is a bug in the code or in the test that does not
# expect it (pytest.warns): each test fails on one it leaves unasserted. Others' warnings pass
# through to pytest's summary as before.
PROJECT = tuple(
    os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), part) + os.sep
    for part in ("rsvo_env", "wrappers", "training", "benchmarks")
)


@pytest.fixture(autouse=True)
def no_unasserted_warning_of_ours():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        yield
    # a ResourceWarning comes from the garbage collector, at whatever line ran then: its place
    # says nothing of its cause, so it is left to the summary
    ours = [
        w
        for w in caught
        if os.path.abspath(w.filename).startswith(PROJECT) and w.category is not ResourceWarning
    ]
    for w in caught:
        if w not in ours:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    assert not ours, [f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}" for w in ours]
