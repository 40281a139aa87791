"""Third-party clients run unchanged: TorchRL (and so BenchMARL), PettingZoo's SB3 tutorial route
through SuperSuit, Gymnasium's episode statistics, PettingZoo's ``max_cycles_test``."""

import warnings

import numpy as np

import rsvo_env


def filtered(name="position_swap", **kwargs):
    return rsvo_env.parallel_env(name, **kwargs)


def test_pettingzoo_max_cycles_test():
    from pettingzoo.test import max_cycles_test

    max_cycles_test(rsvo_env)


def test_torchrl_wrapper_specs_rollout_and_collector():
    import torch
    import torchrl.collectors
    from torchrl.envs.libs.pettingzoo import PettingZooWrapper
    from torchrl.envs.utils import check_env_specs

    torch.set_num_threads(1)
    env = PettingZooWrapper(filtered(max_steps=30), categorical_actions=False, seed=0)
    check_env_specs(env)
    # 100 steps of 30-step episodes: the rollout goes through at least two episode ends
    td = env.rollout(100, break_when_any_done=False)
    assert td.batch_size[0] == 100
    ends = td["next", "done"].reshape(-1)  # all agents end together: the env's done
    assert int(ends.sum()) >= 2
    assert bool(td["next", "agent", "truncated"][ends].all())
    info = td["next", "agent", "info"]
    assert info["min_distance"].min() >= 1.0 - 1e-9  # behind the filter, through the client
    # torchrl >= 0.14 names its single-process collector Collector (before: SyncDataCollector)
    collectors = torchrl.collectors
    Collector = getattr(collectors, "Collector", None) or collectors.SyncDataCollector
    collector = Collector(env, None, frames_per_batch=40, total_frames=80)
    batches = list(collector)
    collector.shutdown()
    assert len(batches) == 2 and batches[0].numel() == 40


def test_supersuit_route_of_the_pettingzoo_sb3_tutorial():
    import supersuit as ss
    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(1)
    env = filtered("circular_swap", num_agents=4, circle_radius=3.0, max_steps=100)
    env.reset(seed=0)
    vec = ss.pettingzoo_env_to_vec_env_v1(env)
    vec = ss.concat_vec_envs_v1(vec, 2, num_cpus=0, base_class="stable_baselines3")
    model = PPO("MlpPolicy", vec, n_steps=128, batch_size=128, n_epochs=2, verbose=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        model.learn(total_timesteps=3000)
    assert model.num_timesteps >= 3000


def test_gymnasium_record_episode_statistics_on_the_joint_env():
    import gymnasium
    from gymnasium.wrappers import RecordEpisodeStatistics

    env = RecordEpisodeStatistics(gymnasium.make("rsvo/PositionSwap-v0", max_steps=40))
    env.reset(seed=0)
    for _ in range(2):
        total, done = 0.0, False
        while not done:
            _, r, term, trunc, info = env.step(env.unwrapped.nominal_action())
            total += r
            done = term or trunc
        assert info["episode"]["l"] == 40 and np.isclose(info["episode"]["r"], total)
        assert info["episode_steps"] == 40
        env.reset()
