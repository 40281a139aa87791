"""SB3VecEnv: Stable-Baselines3's VecEnv contract over the batched env, and seeded PPO."""

import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecCheckNan

import rsvo_env
from rsvo_env import wrappers
from rsvo_env.envs.vector import BatchedEnv


def vec(name="crowd", E=3, **kwargs):
    if name == "crowd":
        kwargs.setdefault("num_agents", 4)
    return wrappers.SB3VecEnv(BatchedEnv(name, num_envs=E, **kwargs))


def test_slots_auto_reset_and_truncation_flags():
    env = vec(max_steps=20)
    assert (
        env.num_envs == 12
        and env.observation_space.shape == env.venv.single_observation_space.shape
    )
    env.seed(3)
    obs = env.reset()
    assert obs.shape == (12, env.observation_space.shape[0])
    rng = np.random.default_rng(0)
    for _ in range(20):
        obs, rewards, dones, infos = env.step(rng.uniform(-1, 1, (12, 2)).astype(np.float32))
        assert rewards.shape == (12,) and len(infos) == 12
        assert all({"intervention", "cost", "feasible"} <= set(i) for i in infos)
        assert not any("episode" in i for i in infos)  # reserved for SB3's Monitor
    assert dones.all()  # every env truncated at its 20th step, all agents together
    for k, info in enumerate(infos):
        assert info["TimeLimit.truncated"] is True
        assert info["episode_steps"] == 20
        assert info["terminal_observation"].shape == obs[k].shape
        assert not np.array_equal(info["terminal_observation"], obs[k])  # obs is the new episode's


def test_termination_is_not_truncation():
    env = vec("position_swap", E=2)
    env.seed(0)
    env.reset()
    done = np.zeros(4, dtype=bool)
    while not done.any():
        actions = env.venv.nominal_actions().reshape(4, 2)
        _, _, done, infos = env.step(actions)
    assert done.all() and all(i["TimeLimit.truncated"] is False for i in infos)
    assert all(i["episode_success"] for i in infos)


def test_vec_check_nan_finds_nothing():
    env = VecCheckNan(vec(max_steps=15), raise_exception=True)
    env.seed(1)
    env.reset()
    rng = np.random.default_rng(1)
    for _ in range(40):
        env.step(rng.uniform(-1, 1, (12, 2)).astype(np.float32))


def test_attributes_and_methods_reach_the_batched_env():
    env = vec()
    assert env.get_attr("num_agents") == [4] * 12
    assert env.get_attr("num_envs", indices=[0, 5]) == [3, 3]
    env.set_attr("tag", "x")
    assert env.venv.tag == "x"
    env.reset()
    assert env.env_method("nominal_actions", indices=0)[0].shape == (3, 4, 2)
    assert env.env_is_wrapped(object) == [False] * 12


def test_seeded_ppo_runs_are_identical():
    torch.set_num_threads(1)

    def train():
        env = vec(max_steps=30)
        model = PPO("MlpPolicy", env, n_steps=16, batch_size=96, n_epochs=1, seed=5, verbose=0)
        model.learn(total_timesteps=192)
        return [p.detach().clone() for p in model.policy.parameters()]

    a, b = train(), train()
    assert all(torch.equal(x, y) for x, y in zip(a, b, strict=True))
    c = PPO("MlpPolicy", vec(max_steps=30), n_steps=16, batch_size=96, seed=6)
    c.learn(total_timesteps=192)
    assert not all(
        torch.equal(x, y) for x, y in zip(a, c.policy.parameters(), strict=True)
    )  # another seed, other parameters: the test can fail


def test_single_parallel_env_path_equals_the_batched_one():
    """SB3VecEnv over one filtered ParallelEnv (wrapped, dicts) gives the same slots, values and
    end-of-episode infos as over a BatchedEnv of one env, through an auto-reset."""
    kwargs = {"num_agents": 4, "max_steps": 12}
    single = wrappers.SB3VecEnv(wrappers.ResidualAction(rsvo_env.parallel_env("crowd", **kwargs)))
    batched = wrappers.SB3VecEnv(BatchedEnv("crowd", num_envs=1, action="residual", **kwargs))
    assert single.num_envs == batched.num_envs == 4
    for env in (single, batched):
        env.seed(7)
    assert np.array_equal(single.reset(), batched.reset())
    rng = np.random.default_rng(2)
    ended = 0
    for _ in range(30):
        a = rng.uniform(-1, 1, (4, 2)).astype(np.float32)
        s, b = single.step(a), batched.step(a)
        for x, y in zip(s[:3], b[:3], strict=True):
            assert np.array_equal(x, y)
        for i, j in zip(s[3], b[3], strict=True):
            assert i.keys() == j.keys()
            for key in i:
                assert np.array_equal(i[key], j[key]), key
        ended += int(s[2].all())
    assert ended == 2  # two episodes of 12 steps ended, each with all four slots together
