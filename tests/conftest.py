import os
import sys

from hypothesis import settings

# Rendering tests run headless; tests import the shared instance generator from this folder.
os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
sys.path.insert(0, os.path.dirname(__file__))

# Property tests are deterministic by default: the same examples on every run and machine, so
# the test command (CI's) cannot turn red on a draw. Exploration draws new examples:
#   python -m pytest --hypothesis-profile=explore tests/test_solver_scales.py
settings.register_profile("deterministic", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile("deterministic")
