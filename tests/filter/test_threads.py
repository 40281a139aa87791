"""The thread policy (``rsvo_env/util/threads.py``, ``docs/threads.md``): one thread unless a
process
opts in, parallel kernels only over enough work, the same results either way, and bad counts
refused by name."""

import os
import subprocess
from pathlib import Path

import numba
import numpy as np
import pytest

from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.qp import exact
from rsvo_env.util import sizes, threads
from tests.support.checkout import checkout_env, run_python

ROOT = Path(__file__).resolve().parents[2]
POOL = numba.config.NUMBA_NUM_THREADS


def test_one_thread_unless_opted_in():
    assert threads.get_num_threads() == int(os.environ.get(threads.ENV_VAR, "1"))
    with threads.using(1):
        assert not threads.parallel(10**6)
    if POOL > 1:
        with threads.using(2):
            assert threads.get_num_threads() == 2
            assert threads.parallel(sizes.PARALLEL_MIN_PROBLEMS)
            assert not threads.parallel(sizes.PARALLEL_MIN_PROBLEMS - 1)
    assert threads.get_num_threads() == int(os.environ.get(threads.ENV_VAR, "1"))


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "two", None, POOL + 1, np.float64(2.0)])
def test_bad_counts_are_refused_by_name_and_change_nothing(bad):
    before = threads.get_num_threads()
    with pytest.raises(ValueError, match="threads") as err:
        threads.set_num_threads(bad)
    assert repr(bad) in str(err.value) or str(bad) in str(err.value)
    assert threads.get_num_threads() == before


@pytest.mark.parametrize("caller", [1, POOL])
def test_the_solver_puts_back_the_callers_numba_thread_count(caller):
    """``exact.solve_batch`` over enough problems to run in parallel on 2 threads: numba's count
    for the calling thread is the caller's after it (it was left at the library's)."""
    rng = np.random.default_rng(0)
    n = 4 * sizes.PARALLEL_MIN_PROBLEMS
    A, b = rng.normal(size=(n, 3, 2)), rng.normal(size=(n, 3))
    before = numba.get_num_threads()
    numba.set_num_threads(caller)
    try:
        with threads.using(min(2, POOL)):
            exact.solve_batch(rng.normal(size=(n, 2)), A, b, np.ones((n, 3), bool), -1.0, 1.0)
        assert numba.get_num_threads() == caller
    finally:
        numba.set_num_threads(before)


def run(code: str, value: str) -> subprocess.CompletedProcess:
    env = checkout_env(**{threads.ENV_VAR: value, "NUMBA_NUM_THREADS": "2"})
    return run_python("-c", code, env=env)


def test_the_environment_variable_opts_a_process_in():
    code = "import rsvo_env.util.threads as t; print(t.get_num_threads(), t.parallel(10**4))"
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


def test_one_thread_takes_the_prange_form_from_its_threshold_on_one_thread():
    """Over enough agents even one thread calls a kernel's prange form (faster: numba marks
    its arrays free of aliasing), launched with one thread; the plain loop below that."""
    seen = []

    def serial() -> str:
        return "serial"

    def prange() -> str:
        seen.append(numba.get_num_threads())
        return "prange"

    with threads.using(1):
        assert threads.launch(serial, prange, sizes.PRANGE_FORM_MIN_AGENTS) == "prange"
        assert threads.launch(serial, prange, sizes.PRANGE_FORM_MIN_AGENTS - 1) == "serial"
        assert threads.launch(serial, prange, 10**6) == "prange"
    if POOL > 1:
        with threads.using(2):
            assert threads.launch(serial, prange, sizes.PARALLEL_MIN_PROBLEMS) == "prange"
    assert seen == [1, 1] + ([2] if POOL > 1 else [])


def test_a_step_leaves_the_callers_numba_thread_count_as_it_was():
    """Each launch sets the count for itself only: a user's own parallel code in the same
    thread keeps the count it set, whichever form or thread count the step took."""
    env = BatchedEnv("crowd", num_envs=64, num_agents=4, safety_filter=True, nominal="move_to_goal")
    env.reset(seed=1)
    before = numba.get_num_threads()
    try:
        for count in sorted({1, POOL}):
            numba.set_num_threads(count)
            for n_threads in sorted({1, POOL}):
                with threads.using(n_threads):
                    env.step(env.nominal_actions())  # 256 agents: a prange form every time
                assert numba.get_num_threads() == count
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize(("n", "e"), [(6, 1), (4, 64), (50, 3)])
def test_the_serial_and_prange_forms_agree_bit_for_bit(n, e):
    """The dense filter pass and the CSR solve, each form on the same crowd state."""
    from rsvo_env.filter import dense
    from rsvo_env.qp import exact

    env = BatchedEnv("crowd", num_envs=e, num_agents=n, safety_filter=True, nominal="move_to_goal")
    env.reset(seed=2)
    for _ in range(60):
        env.step(env.nominal_actions())
    sim = env.sim
    flt, s, u = sim.filters[0], sim.state, sim.nominal_controls()
    bodies = next(iter(flt._default_bodies.values()))
    args = (
        s.positions,
        u,
        sim.weights.matrix,
        float(flt.config.gamma),
        bodies.radii,
        bodies.lo,
        bodies.hi,
    )
    rows = flt.apply(s.positions, u, s.theta, None, sim.weights.matrix, with_rows=True).rows
    nominal, lo, hi, _ = exact._batch(u.reshape(-1, 2), bodies.lo, bodies.hi)
    csr = (nominal, rows.flat_A, rows.flat_b, rows.offsets, lo, hi)
    with threads.using(1):
        for serial, prange, inputs, outputs in (
            (dense._serial, dense._parallel, args, lambda: dense._outputs(e, n)),
            (
                exact._solve_csr_serial,
                exact._solve_csr_parallel,
                csr,
                lambda: exact._batch(nominal, lo, hi)[3],
            ),
        ):
            a, b = outputs(), outputs()
            serial(*inputs, *a)
            threads.launch(serial, prange, 10**6, *inputs, *b)  # its prange form, one thread
            assert rows.offsets[-1] > 0  # rows to solve: the forms are compared on work
            for x, y in zip(a, b, strict=True):
                np.testing.assert_array_equal(x, y)
