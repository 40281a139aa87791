"""BatchedEnv: env e of a batch reset with seed s is, bit for bit, a single RSVOParallelEnv reset
with seed s + e, through every step and auto-reset; its array API and its errors."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env.envs.vector import BatchedEnv

SIGNALS = (
    "u_nominal",
    "u_safe",
    "intervention",
    "feasible",
    "active_constraints",
    "max_violation",
    "min_distance",
    "cost",
    "at_goal",
    "rh_active",
)


def stacked(obs, agents):
    return np.stack([obs[a] for a in agents])


@pytest.mark.parametrize(
    "name",
    ["position_swap", "circular_swap", "ramp_merge", "crowd", "doorway", "obstacle_field",
     "unicycle_crowd"],
)  # fmt: skip
@pytest.mark.parametrize("filtered", [False, True], ids=["bare", "filtered"])
def test_batch_equals_single_envs_bit_for_bit(name, filtered):
    # several episode ends, and so auto-resets, in 300 steps
    check_batch_equals_singles(name, filtered, {"max_steps": 70}, 300)


def test_large_crowd_batch_equals_single_envs_bit_for_bit():
    """Beyond the dense size: the grid search per agent and per score group."""
    kwargs = {"max_steps": 25, "num_agents": 90, "theta_range": (1.0, 10.0)}
    check_batch_equals_singles("crowd", True, kwargs, 80)


def check_batch_equals_singles(name, filtered, kwargs, steps):
    """Env e of a batch seeded s against a single env seeded s + e, random actions of the
    batch's width (theta actions too), every signal, reward, end and final observation."""
    E, seed = 3, 11
    venv = BatchedEnv(name, num_envs=E, safety_filter=filtered, **kwargs)
    singles = [rsvo_env.parallel_env(name, safety_filter=filtered, **kwargs) for _ in range(E)]
    obs, info = venv.reset(seed=seed)
    agents = singles[0].possible_agents
    for e, env in enumerate(singles):
        o, inf = env.reset(seed=seed + e)
        assert np.array_equal(obs[e], stacked(o, agents))
        for key in SIGNALS:
            assert np.array_equal(info[key][e], [inf[a][key] for a in agents]), key
    rng = np.random.default_rng(0)
    ends = 0
    for t in range(steps):
        width = venv.single_action_space.shape[0]
        actions = rng.uniform(-1.2, 1.2, (E, len(agents), width)).astype(np.float32)
        obs, reward, term, trunc, info = venv.step(actions)
        for e, env in enumerate(singles):
            o, r, te, tr, inf = env.step({a: actions[e, i] for i, a in enumerate(agents)})
            where = (name, t, e)
            assert np.array_equal(reward[e], [r[a] for a in agents]), where
            assert term[e] == te[agents[0]] and trunc[e] == tr[agents[0]], where
            for key in (*SIGNALS, "theta") if "theta" in info else SIGNALS:
                assert np.array_equal(info[key][e], [inf[a][key] for a in agents]), (key, where)
            for key in inf[agents[0]]:
                if key.startswith("episode_"):
                    assert info[key][e] == inf[agents[0]][key], (key, where)
            assert info["_final_obs"][e] == (te[agents[0]] or tr[agents[0]]), where
            if info["_final_obs"][e]:
                ends += 1
                assert np.array_equal(info["final_obs"][e], stacked(o, agents)), where
                o, _ = env.reset()
            assert np.array_equal(obs[e], stacked(o, agents)), where
    assert ends >= E * 3


def test_spaces_and_shapes():
    venv = BatchedEnv("crowd", num_envs=4, num_agents=5, num_obs_neighbors=3)
    obs, info = venv.reset(seed=0)
    assert obs.shape == (4, 5, 5 + 10 * 3) and obs.dtype == np.float32
    assert venv.single_observation_space.shape == (5 + 10 * 3,)
    assert venv.single_action_space.shape == (2,)
    assert venv.observation_space.contains(obs)
    assert venv.num_envs == 4 and venv.num_agents == 5
    obs, reward, term, trunc, info = venv.step(venv.nominal_actions())
    assert reward.shape == (4, 5) and term.shape == trunc.shape == (4,)
    assert info["u_safe"].shape == (4, 5, 2) and info["episode_steps"].shape == (4,)
    assert all(isinstance(v, np.ndarray) for v in info.values())


def test_reset_options_hold_for_auto_resets():
    venv = BatchedEnv("position_swap", num_envs=2, max_steps=5)
    venv.reset(seed=0, options={"theta": [[1.0, 4.0], [2.0, 2.0]], "weighting": "symmetric"})
    assert np.allclose(venv.sim.weights.matrix[:, 0, 1], 0.5)
    for _ in range(6):  # past an auto-reset
        venv.step(np.zeros((2, 2, 2)))
    np.testing.assert_array_equal(venv.sim.state.theta, [[1.0, 4.0], [2.0, 2.0]])
    assert np.allclose(venv.sim.weights.matrix[:, 0, 1], 0.5)
    venv.reset(seed=0, options={"theta": [1.0, 4.0]})  # one row for every env
    np.testing.assert_array_equal(venv.sim.state.theta, [[1.0, 4.0], [1.0, 4.0]])


@pytest.mark.parametrize(
    "actions,pattern",
    [
        (np.zeros((2, 3, 2)), r"actions has shape \(2, 3, 2\), expected \(2, 2, 2\)"),
        (np.full((2, 2, 2), "1"), "actions must be real numbers"),
        (np.array([[[0, 0], [0, 0]], [[0, 0], [np.nan, 0]]]), r"actions\[1\]\[1\].*env 1, agent 1"),
    ],
)
def test_bad_actions_name_env_and_agent_and_change_nothing(actions, pattern):
    venv = BatchedEnv("position_swap", num_envs=2)
    venv.reset(seed=0)
    before = venv.sim.state.positions.copy()
    with pytest.raises(ValueError, match=pattern):
        venv.step(actions)
    np.testing.assert_array_equal(venv.sim.state.positions, before)
    assert venv.sim.metrics.steps.tolist() == [0, 0]


def test_step_before_reset_and_bad_construction():
    venv = BatchedEnv("crowd", num_envs=2)
    with pytest.raises(RuntimeError, match="reset"):
        venv.step(np.zeros((2, 12, 2)))
    with pytest.raises(ValueError, match=r"num_envs = 0"):
        BatchedEnv("crowd", num_envs=0)
    with pytest.raises(ValueError, match=r"num_envs = 2.5"):
        BatchedEnv("crowd", num_envs=2.5)
    with pytest.raises(TypeError, match="safety_filter=True"):
        BatchedEnv("crowd", num_envs=2, safety_filter=False, gamma=3.0)
    with pytest.raises(TypeError, match="unknown keyword"):
        BatchedEnv("crowd", num_envs=2, nmu_agents=3)


def test_filtered_batch_is_safe():
    venv = BatchedEnv("crowd", num_envs=16, num_agents=16, max_steps=200)
    venv.reset(seed=3)
    for _ in range(400):
        x = venv.sim.state.positions
        to_centre = -x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-9)
        _, _, _, _, info = venv.step(to_centre)
        assert info["min_distance"].min() >= 1.0 - 1e-9 and info["feasible"].all()


@pytest.mark.parametrize("share", [0.0, 0.5, 1.0])
def test_team_reward_shares_the_env_mean_and_keeps_the_total(share):
    kwargs = {"num_agents": 4, "num_envs": 3}
    own = BatchedEnv("crowd", **kwargs)
    team = BatchedEnv("crowd", reward_team=share, **kwargs)
    own.reset(seed=1)
    team.reset(seed=1)
    for _ in range(5):
        r_own = own.step(own.nominal_actions())[1]
        r_team = team.step(team.nominal_actions())[1]
    np.testing.assert_allclose(r_team.sum(-1), r_own.sum(-1), rtol=1e-12)
    expected = (1 - share) * r_own + share * r_own.mean(-1, keepdims=True)
    np.testing.assert_allclose(r_team, expected, rtol=1e-12, atol=1e-15)
    assert share == 0.0 or not np.allclose(r_team, r_own)  # the test can fail


@pytest.mark.parametrize("share", [-0.1, 1.5, float("nan"), "1", True])
def test_a_bad_team_share_is_refused(share):
    with pytest.raises(ValueError, match="reward_team"):
        BatchedEnv("crowd", num_agents=3, reward_team=share)


@pytest.mark.parametrize(
    "name, kwargs",
    [
        ("position_swap", {"deadlock_resolution": "none", "theta_range": (1.0, 10.0)}),
        ("circular_swap", {"reward_team": 0.5, "max_steps": 150}),
        ("crowd", {"num_agents": 5, "theta_range": (1.0, 10.0), "num_obs_neighbors": 2}),
        (
            "crowd",
            {
                "num_agents": 6,
                "theta_range": (1.0, 10.0),
                "rh_hold": 0.2,
                "rorca_route": False,
                "rorca_goal_hold": 0.5,
            },
        ),
    ],
)
def test_the_fused_after_step_equals_the_hooks_bit_for_bit(name, kwargs):
    """The after-integration stage in one compiled call gives, step for step and across
    auto-resets, exactly what the scenario's hooks called in turn give."""
    runs = []
    for fused in (True, False):
        venv = BatchedEnv(name, num_envs=3, dt=0.1, gamma=10.0, **{"max_steps": 120, **kwargs})
        assert venv.sim.post_step_in_one_call  # the base hooks: the fused stage serves them
        venv.sim.post_step_in_one_call = fused
        obs, _ = venv.reset(seed=5)
        rng = np.random.default_rng(1)
        trace, ended = [obs], 0
        for _ in range(300):
            # env 0 scripted (it arrives), the others perturbed
            noise = rng.normal(0.0, 0.3, (3, venv.num_agents, 2)) * [[[0.0]], [[1.0]], [[1.0]]]
            out = venv.step(venv.nominal_actions() + noise)
            trace += [*out[:4], *(out[4][k] for k in sorted(out[4]))]
            ended += int(out[2].sum())
        trace += [venv.sim.metrics.counts, venv.sim.metrics.sums, venv.sim.state.reached]
        runs.append(trace)
    assert ended > 0  # episodes reached their goals and auto-reset along the way
    for a, b in zip(*runs, strict=True):
        assert np.array_equal(a, b)


def test_a_list_of_seeds_seeds_each_env():
    """Gymnasium's vector form: ``seed[e]`` for env e; the same episode as an int seed gives
    the env of that index; a bad list is refused by name and changes nothing."""
    env = BatchedEnv("crowd", num_envs=3, num_agents=5)
    obs_list, _ = env.reset(seed=[7, 3, None])
    obs_int, _ = BatchedEnv("crowd", num_envs=1, num_agents=5).reset(seed=3)
    assert np.array_equal(obs_list[1], obs_int[0])
    obs_seven, _ = BatchedEnv("crowd", num_envs=2, num_agents=5).reset(seed=6)
    assert np.array_equal(obs_list[0], obs_seven[1])
    before = env.sim.state.positions.copy()
    with pytest.raises(ValueError, match="2 entries, expected 3"):
        env.reset(seed=[1, 2])
    with pytest.raises(ValueError, match=r"seed\[1\] = -1"):
        env.reset(seed=[1, -1, 2])
    assert np.array_equal(env.sim.state.positions, before)
