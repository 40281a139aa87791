"""Residual actions: the scripted command plus a learned correction, gated near the goal and
held to the speed limit; the same in the batched env as behind the ParallelEnv wrapper."""

import numpy as np
import pytest

import rsvo_env
import wrappers
from rsvo_env.vector import BatchedEnv


def test_a_zero_residual_is_the_scripted_controller():
    """To the float32 precision of the scripted actions (nominal_actions() returns float32; the
    residual mode adds to the float64 command)."""
    scripted = wrappers.RCBFSafetyFilter(rsvo_env.parallel_env("circular_swap"))
    residual = wrappers.ResidualAction(
        wrappers.RCBFSafetyFilter(rsvo_env.parallel_env("circular_swap"))
    )
    theta = {"theta": [2, 1, 2, 1, 2, 1]}
    scripted.reset(seed=0, options=theta)
    residual.reset(seed=0, options=theta)
    zero = {a: np.zeros(2, dtype=np.float32) for a in residual.possible_agents}
    while scripted.agents:
        scripted.step(scripted.unwrapped.nominal_actions())
        residual.step(zero)
        np.testing.assert_allclose(
            residual.unwrapped.world.positions, scripted.unwrapped.world.positions, atol=1e-5
        )
    assert (
        residual.unwrapped.episode_metrics["completed"]
        == (scripted.unwrapped.episode_metrics["completed"])
    )


def test_the_residual_is_gated_near_the_goal_and_held_to_the_speed_limit():
    env = wrappers.ResidualAction(rsvo_env.parallel_env("position_swap"), gate_radius=0.5)
    env.reset(seed=0)
    base = env.unwrapped
    rng = np.random.default_rng(0)
    gated = 0
    while env.agents:
        near = np.linalg.norm(base.world.positions - base.world.goals, axis=1) < 0.5
        scripted = base.sim.scenario.nominal(base.sim.state)[0]
        actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        _, _, _, _, infos = env.step(actions)
        for i, a in enumerate(base.possible_agents):
            u = infos[a]["u_nominal"]
            assert np.linalg.norm(u) <= 2.0 * (1 + 1e-12)  # u_max of position_swap
            if near[i]:
                gated += 1
                np.testing.assert_allclose(u, scripted[i], atol=1e-12)
    assert gated > 0


@pytest.mark.parametrize("name", ["circular_swap", "ramp_merge"])
def test_batched_residuals_equal_the_wrapper(name):
    E = 2
    venv = BatchedEnv(name, num_envs=E, action="residual", gate_radius=0.5, max_steps=60)
    singles = [
        wrappers.ResidualAction(
            wrappers.RCBFSafetyFilter(rsvo_env.parallel_env(name, max_steps=60))
        )
        for _ in range(E)
    ]
    obs, _ = venv.reset(seed=4)
    for e, env in enumerate(singles):
        env.reset(seed=4 + e)
    rng = np.random.default_rng(1)
    agents = singles[0].possible_agents
    for _ in range(100):
        actions = rng.uniform(-1, 1, (E, len(agents), 2)).astype(np.float32)
        obs, reward, term, trunc, _ = venv.step(actions)
        for e, env in enumerate(singles):
            o, r, te, tr, _ = env.step({a: actions[e, i] for i, a in enumerate(agents)})
            if te[agents[0]] or tr[agents[0]]:
                o, _ = env.reset()
            assert np.array_equal(obs[e], np.stack([o[a] for a in agents]))
            assert np.array_equal(reward[e], [r[a] for a in agents])


def test_bad_residual_settings_are_refused():
    with pytest.raises(ValueError, match="action = 'delta'"):
        BatchedEnv("crowd", num_envs=2, action="delta")
    with pytest.raises(ValueError, match="gate_radius = -1"):
        wrappers.ResidualAction(rsvo_env.parallel_env("crowd"), gate_radius=-1)
    with pytest.raises(ValueError, match="gate_radius"):
        BatchedEnv("crowd", num_envs=2, action="residual", gate_radius=float("nan"))


@pytest.mark.parametrize("scale, expected", [(1.0, 0.0), (2.0, -1.0)])
def test_the_residual_scale_decides_whether_a_full_speed_command_can_reverse(scale, expected):
    """A residual straight against a full-speed scripted command: at scale 1 it cancels it, at
    scale 2 it reverses it (to the speed limit)."""
    venv = BatchedEnv(
        "position_swap", action="residual", residual_scale=scale, safety_filter=False,
        deadlock_resolution="none",
    )  # fmt: skip
    venv.reset(seed=0)
    x0 = venv.sim.state.positions.copy()
    toward = venv.sim.state.goals - x0
    toward /= np.linalg.norm(toward, axis=-1, keepdims=True)
    venv.step(-toward)
    moved = venv.sim.state.positions - x0
    u_max, dt = venv.scenario.u_max, venv.scenario.params["dt"]
    np.testing.assert_allclose(moved, expected * u_max * dt * toward, atol=1e-12)


@pytest.mark.parametrize("scale", [0.0, -1.0, float("nan"), "2"])
def test_a_bad_residual_scale_is_refused(scale):
    with pytest.raises(ValueError, match="residual scale"):
        BatchedEnv("crowd", num_agents=3, action="residual", residual_scale=scale)
