"""The thread policy (``rsvo_env/threads.py``, ``docs/threads.md``): one thread unless a process
opts in, parallel kernels only over enough work, the same results either way, and bad counts
refused by name."""

import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from rsvo_env import threads
from rsvo_env.vector import BatchedEnv

ROOT = Path(__file__).resolve().parents[1]
POOL = numba.config.NUMBA_NUM_THREADS


def test_one_thread_unless_opted_in():
    assert threads.get_num_threads() == int(os.environ.get(threads.ENV_VAR, "1"))
    with threads.using(1):
        assert not threads.parallel(10**6)
    if POOL > 1:
        with threads.using(2):
            assert threads.get_num_threads() == 2
            assert threads.parallel(threads.PARALLEL_THRESHOLD)
            assert numba.get_num_threads() == 2
            assert not threads.parallel(threads.PARALLEL_THRESHOLD - 1)
    assert threads.get_num_threads() == int(os.environ.get(threads.ENV_VAR, "1"))


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "two", None, POOL + 1, np.float64(2.0)])
def test_bad_counts_are_refused_by_name_and_change_nothing(bad):
    before = threads.get_num_threads()
    with pytest.raises(ValueError, match="threads") as err:
        threads.set_num_threads(bad)
    assert repr(bad) in str(err.value) or str(bad) in str(err.value)
    assert threads.get_num_threads() == before


def run(code: str, value: str) -> subprocess.CompletedProcess:
    env = {**os.environ, threads.ENV_VAR: value, "NUMBA_NUM_THREADS": "2"}
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=env, capture_output=True, text=True
    )


def test_the_environment_variable_opts_a_process_in():
    code = "import rsvo_env.threads as t; print(t.get_num_threads(), t.parallel(10**4))"
    assert run(code, "2").stdout.split() == ["2", "True"]
    bad = run(code, "abc")
    assert bad.returncode != 0 and "RSVO_NUM_THREADS" in bad.stderr and "'abc'" in bad.stderr


def test_parallel_kernels_give_the_serial_results_bit_for_bit():
    """A filtered crowd batch (8 x 64 = 512 QPs a step) stepped with the pool and with one
    thread: the same trajectories, rows solved in any order by any thread."""

    def episode(n_threads: int) -> list[np.ndarray]:
        with threads.using(n_threads):
            env = BatchedEnv(
                "crowd", num_envs=8, num_agents=64, safety_filter=True, nominal="move_to_goal"
            )
            env.reset(seed=4)
            out = []
            for _ in range(30):
                out.append(env.step(env.nominal_actions())[0])
            return out

    for a, b in zip(episode(1), episode(POOL), strict=True):
        np.testing.assert_array_equal(a, b)
