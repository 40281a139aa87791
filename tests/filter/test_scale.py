"""Large crowds: memory that does not grow with the episode or as N^2 temporaries, 10,000 agents
kept apart, the smallest barrier over all pairs, and double-integrator crowds whose every
infeasible step is flagged."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env.control.nominal import move_to_goal
from rsvo_env.dynamics import double_integrator_step
from rsvo_env.dynamics.barriers import pair_rows
from rsvo_env.envs.rendering import TRAIL
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.geometry import pairs
from rsvo_env.qp import exact
from rsvo_env.responsibility import svo as responsibility
from rsvo_env.scenarios import Crowd
from rsvo_env.util.neighbors import nearest_distance


def test_history_is_bounded_unless_kept():
    steps = TRAIL + 50
    for keep, expected in ((False, TRAIL), (True, steps + 1)):
        env = rsvo_env.parallel_env("crowd", keep_history=keep, render_mode="rgb_array")
        env.reset(seed=0)
        for _ in range(steps):
            env.step({a: np.zeros(2, dtype=np.float32) for a in env.agents})
        assert len(env.unwrapped.history) == expected
        assert env.render().ndim == 3
    with pytest.raises(ValueError, match="keep_history"):
        rsvo_env.parallel_env("crowd", keep_history="yes")


def test_ten_thousand_agents_keep_their_distance():
    """The crowd's own starts and goals, theta spread over 1..10, the filter on plain arrays."""
    n, dt = 10_000, 0.05
    sc = Crowd(num_agents=n)
    x, _, goals = sc.initial_state(np.random.default_rng(0))
    theta = np.random.default_rng(1).uniform(1, 10, n)
    p = sc.params
    flt = SafetyFilter(
        FilterConfig(gamma=p["gamma"], safety_radius=p["safety_radius"], u_max=p["u_max"], dt=dt)
    )
    for _ in range(40):
        res = flt.filter(x, move_to_goal(x, goals, p["k"], p["u_max"]), theta)
        assert res.feasible.all()
        x = x + dt * res.actions
        assert nearest_distance(x).min() >= p["safety_radius"] * (1 - 1e-9)
    assert res.rows.n_pairs < 10 * n  # the search grows like N, not N^2


def test_crowd_starts_are_spaced_for_many_agents():
    sc = Crowd(num_agents=30_000)
    start, _, goals = sc.initial_state(np.random.default_rng(3))
    spacing = sc.params["spacing_factor"] * sc.params["safety_radius"]
    assert nearest_distance(start).min() >= spacing
    assert nearest_distance(goals).min() >= spacing


@pytest.mark.parametrize("seed", range(6))
def test_min_barrier_is_over_all_pairs(seed):
    """Beyond the dense size the nearest pair may lie outside every agent's search."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(65, 400))
    x = Crowd(num_agents=n, side_factor=4.0, spacing_factor=1 + rng.uniform(0, 1.5))._spread(rng)
    theta = rng.uniform(1, 10, n)
    res = SafetyFilter(FilterConfig(gamma=10.0, u_max=2.0)).filter(x, np.zeros((n, 2)), theta)
    d = np.linalg.norm(x[:, None] - x[None], axis=-1) + np.where(np.eye(n), np.inf, 0.0)
    assert res.min_h == pytest.approx(d.min() ** 2 - 1.0, rel=1e-12)


def test_weight_matrix_in_blocks_is_the_whole_formula(monkeypatch):
    theta = np.random.default_rng(0).uniform(0, 10, (2, 37))
    theta[0, 3] = 0.0
    whole = responsibility.weight_matrix(theta)
    monkeypatch.setattr(responsibility, "BLOCK_ENTRIES", 50)  # blocks of one row
    blocked = responsibility.weight_matrix(theta)
    np.testing.assert_array_equal(blocked, whole)
    upper = np.triu(np.ones((37, 37), dtype=bool), 1)
    direct = responsibility.pair_omega(theta[:, :, None], theta[:, None, :])
    np.testing.assert_array_equal(blocked[:, upper], direct[:, upper])
    np.testing.assert_array_equal(blocked[:, upper.T], 1.0 - np.swapaxes(direct, 1, 2)[:, upper.T])
    off = np.where(np.eye(37, dtype=bool), np.inf, whole)
    np.testing.assert_array_equal(responsibility.smallest_weight(whole), off.min(axis=(1, 2)))


def test_double_integrator_crowd_flags_every_infeasible_step():
    """No user radius: each step equals the all-pairs filter (actions and flags), and every
    agent left unflagged satisfies every row of every pair."""
    n, dt, a_max = 200, 0.05, 1.0
    sc = Crowd(num_agents=n)
    p, _, goals = sc.initial_state(np.random.default_rng(4))
    v = np.zeros_like(p)
    theta = np.random.default_rng(5).uniform(1, 10, n)
    cfg = FilterConfig(
        gamma=2.0, u_max=a_max, dt=dt, dynamics="double_integrator", barrier="braking"
    )
    flt = SafetyFilter(cfg)
    I, J = pairs.all_pairs(n)
    w = flt.pair_weights(theta, None, I, J)
    flagged = 0
    for _ in range(60):
        nominal = np.clip(2.0 * (move_to_goal(p, goals, 2.0, 2.0) - v), -a_max, a_max)
        res = flt.filter(p, nominal, theta, velocities=v)
        rows = pair_rows.double_integrator_rows(
            p,
            v,
            w,
            I,
            J,
            pair_rows.BarrierSpec(cfg.gamma, cfg.safety_radius, cfg.lo, cfg.hi, dt=dt),
            cull=False,
        )
        ref, feasible = exact.solve_batch(nominal, rows.A, rows.b, rows.mask, cfg.lo, cfg.hi)[:2]
        np.testing.assert_array_equal(res.feasible, feasible)
        np.testing.assert_allclose(res.actions, ref, atol=1e-12 * a_max)
        slack = np.einsum("nkd,nd->nk", rows.A, res.actions) - rows.b
        scale = np.abs(rows.A).sum(axis=-1) * a_max + np.abs(rows.b)
        ok = np.where(rows.mask, slack <= 1e-9 * scale, True).all(axis=-1)
        assert (ok | ~res.feasible).all()
        assert (res.max_violation[~res.feasible] > 0).all()
        flagged += int((~res.feasible).sum())
        p, v = double_integrator_step(p, v, res.actions, dt)
    assert flagged > 0  # the crowd is dense enough to test the flags


def run_batch(steps, setup):
    from rsvo_env.envs.vector import BatchedEnv

    venv = BatchedEnv("crowd", num_envs=2, num_agents=90, theta_range=(1.0, 10.0), max_steps=30)
    venv.reset(seed=3)
    setup(venv)
    out, rng = [], np.random.default_rng(0)
    for _ in range(steps):
        obs, reward, _, _, info = venv.step(rng.uniform(-1, 1, (2, 90, 2)).astype(np.float32))
        out.append((obs, reward, info["u_safe"], info["feasible"]))
    return venv, out


def halves(theta):
    return np.where(np.eye(len(theta)), 0.0, 0.5)


@pytest.mark.parametrize("env1_mode", ["asymmetric", "symmetric", "callable"])
def test_weights_from_scores_are_the_matrix(monkeypatch, env1_mode):
    """Beyond sizes.WEIGHT_MATRIX_MAX_AGENTS agents the core keeps no weight matrix: observations,
    safe actions and rewards are those of the matrix, through auto-resets, and world.omega is
    still the matrix."""
    from rsvo_env.envs.world import World
    from rsvo_env.util import sizes

    callable_mode = halves if env1_mode == "callable" else None
    mode = callable_mode or env1_mode

    def setup(venv):
        venv.sim.set_weighting(1, mode)  # env 1 differs from env 0 (asymmetric)

    kept, kept_out = run_batch(70, setup)
    monkeypatch.setattr(sizes, "WEIGHT_MATRIX_MAX_AGENTS", 50)
    lazy, lazy_out = run_batch(70, setup)
    assert kept.sim.weights.matrix is not None
    # only a callable weighting makes the core keep its matrix
    assert (lazy.sim.weights.matrix is None) == (callable_mode is None)
    for a, b in zip(kept_out, lazy_out, strict=True):
        for x, y in zip(a, b, strict=True):
            np.testing.assert_array_equal(x, y)
    for e in range(2):
        world_kept, world_lazy = World(kept.sim, e).omega, World(lazy.sim, e).omega
        np.testing.assert_array_equal(world_kept, world_lazy)
