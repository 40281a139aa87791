"""BatchedEnv as a Gymnasium VectorEnv (``rsvo_env.wrappers.GymnasiumVectorEnv``): Gymnasium's
own vector wrappers on it unchanged, and a CleanRL-style PPO loop training through them."""

import numpy as np
import pytest
import torch
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.wrappers.vector import ClipAction, NormalizeObservation, RecordEpisodeStatistics

from rsvo_env.envs import registration
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.wrappers import GymnasiumVectorEnv

SMALL = {"num_agents": 4, "max_steps": 25}


def test_next_step_mode_plays_the_same_episodes_as_same_step():
    T = SMALL["max_steps"]  # both envs end together, at steps T and 2 T
    same = BatchedEnv("crowd", num_envs=2, **SMALL)
    nxt = BatchedEnv("crowd", num_envs=2, autoreset_mode="next_step", **SMALL)
    same.reset(seed=4)
    nxt.reset(seed=4)
    actions = np.random.default_rng(0).uniform(-1, 1, (2 * T, 2, 4, 2))
    for t, a in enumerate(actions, start=1):
        obs_s, r_s, te_s, tr_s, info_s = same.step(a)
        obs_n, r_n, te_n, tr_n, info_n = nxt.step(a)
        np.testing.assert_array_equal(r_s, r_n)
        np.testing.assert_array_equal(te_s | tr_s, te_n | tr_n)
        np.testing.assert_array_equal(info_s["episode_steps"], info_n["episode_steps"])
        if t % T:
            np.testing.assert_array_equal(obs_s, obs_n)
            continue
        assert (tr_n & info_s["_final_obs"]).all() and "final_obs" not in info_n
        # the ending step's obs is the last one (same step keeps it in final_obs) ...
        np.testing.assert_array_equal(obs_n, info_s["final_obs"])
        # ... and the next step resets, ignoring its actions: reward 0, the new first obs
        obs_n, r_n, te_n, tr_n, info_n = nxt.step(np.ones((2, 4, 2)))
        np.testing.assert_array_equal(obs_n, obs_s)
        assert (r_n == 0).all() and not (te_n | tr_n).any()
        assert (info_n["episode_steps"] == 0).all() and not info_n["u_safe"].any()


def test_gymnasium_vector_wrappers_apply_unchanged():
    env = GymnasiumVectorEnv("crowd", num_envs=2, **SMALL)
    assert isinstance(env, VectorEnv) and env.num_envs == 8
    assert env.metadata["autoreset_mode"] is AutoresetMode.NEXT_STEP
    stats = RecordEpisodeStatistics(env)
    wrapped = ClipAction(NormalizeObservation(stats))
    obs, info = wrapped.reset(seed=0)
    assert obs.shape == (8, env.single_observation_space.shape[0])
    assert info["min_distance"].shape == (8,) and info["_min_distance"].all()
    totals, episodes = np.zeros(8), []
    for _ in range(3 * (SMALL["max_steps"] + 1)):
        obs, reward, term, trunc, info = wrapped.step(wrapped.action_space.sample() * 3)
        assert reward.shape == term.shape == trunc.shape == (8,)
        totals += reward
        if "episode" in info:
            episodes.append(info["episode"])
            ended = info["_episode"]
            np.testing.assert_allclose(info["episode"]["r"][ended], totals[ended], rtol=1e-6)
            totals[ended] = 0.0
    assert len(episodes) == 3
    assert all((ep["l"] == SMALL["max_steps"]).all() for ep in episodes)
    # NormalizeObservation learned the observations' statistics
    assert np.all(np.isfinite(obs)) and abs(float(obs.mean())) < 5.0


def test_same_step_mode_gives_final_observations_per_slot():
    env = RecordEpisodeStatistics(
        GymnasiumVectorEnv(BatchedEnv("crowd", num_envs=2, autoreset_mode="same_step", **SMALL))
    )
    assert env.metadata["autoreset_mode"] is AutoresetMode.SAME_STEP
    env.reset(seed=1)
    for _ in range(SMALL["max_steps"]):
        obs, _, term, trunc, info = env.step(env.action_space.sample())
    assert (term | trunc).all() and info["_final_obs"].all()
    assert info["final_obs"].shape == obs.shape and not np.array_equal(info["final_obs"], obs)
    assert (info["episode"]["l"] == SMALL["max_steps"]).all()


def test_bad_calls_are_refused():
    env = GymnasiumVectorEnv("crowd", num_envs=2, **SMALL)
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=[1, 2])
    env.reset(seed=0)
    with pytest.raises(ValueError, match="shape"):
        env.step(np.zeros((2, 4, 2)))
    with pytest.raises(ValueError, match="autoreset_mode"):
        BatchedEnv("crowd", autoreset_mode="sometimes")
    with pytest.raises(TypeError, match="keywords"):
        GymnasiumVectorEnv(BatchedEnv("crowd"), num_envs=3)


def ppo(env, iterations: int, steps: int, seed: int = 0):
    """A CleanRL-style PPO (continuous actions, GAE, clipped objective) on a Gymnasium VectorEnv;
    returns the mean episodic return of each iteration's finished episodes."""
    torch.manual_seed(seed)
    obs_dim = env.single_observation_space.shape[0]
    act_dim = env.single_action_space.shape[0]
    actor = torch.nn.Sequential(
        torch.nn.Linear(obs_dim, 64), torch.nn.Tanh(), torch.nn.Linear(64, act_dim)
    )
    critic = torch.nn.Sequential(
        torch.nn.Linear(obs_dim, 64), torch.nn.Tanh(), torch.nn.Linear(64, 1)
    )
    log_std = torch.nn.Parameter(torch.full((act_dim,), -0.5))
    params = [*actor.parameters(), *critic.parameters(), log_std]
    opt = torch.optim.Adam(params, lr=3e-3)
    n = env.num_envs
    obs, _ = env.reset(seed=seed)
    returns = []
    for _ in range(iterations):
        buf_o, buf_a, buf_lp, buf_r, buf_d, buf_v, finished = [], [], [], [], [], [], []
        for _ in range(steps):
            o = torch.as_tensor(obs, dtype=torch.float32)
            with torch.no_grad():
                dist = torch.distributions.Normal(actor(o), log_std.exp())
                a = dist.sample()
                buf_lp.append(dist.log_prob(a).sum(-1))
                buf_v.append(critic(o).squeeze(-1))
            obs, r, term, trunc, info = env.step(a.numpy())
            buf_o.append(o)
            buf_a.append(a)
            buf_r.append(torch.as_tensor(r, dtype=torch.float32))
            buf_d.append(torch.as_tensor(term | trunc, dtype=torch.float32))
            if "episode" in info:
                finished.extend(info["episode"]["r"][info["_episode"]].tolist())
        with torch.no_grad():
            next_v = critic(torch.as_tensor(obs, dtype=torch.float32)).squeeze(-1)
        adv, gae = torch.zeros(steps, n), torch.zeros(n)
        for t in reversed(range(steps)):
            v_next = next_v if t == steps - 1 else buf_v[t + 1]
            delta = buf_r[t] + 0.99 * v_next * (1 - buf_d[t]) - buf_v[t]
            gae = delta + 0.99 * 0.95 * (1 - buf_d[t]) * gae
            adv[t] = gae
        O, A = torch.stack(buf_o).reshape(-1, obs_dim), torch.stack(buf_a).reshape(-1, act_dim)
        LP, ADV = torch.stack(buf_lp).reshape(-1), adv.reshape(-1)
        RET = ADV + torch.stack(buf_v).reshape(-1)
        ADV = (ADV - ADV.mean()) / (ADV.std() + 1e-8)
        for _ in range(4):
            dist = torch.distributions.Normal(actor(O), log_std.exp())
            ratio = (dist.log_prob(A).sum(-1) - LP).exp()
            pg = -torch.min(ratio * ADV, ratio.clamp(0.8, 1.2) * ADV).mean()
            vf = ((critic(O).squeeze(-1) - RET) ** 2).mean()
            loss = pg + 0.5 * vf
            assert torch.isfinite(loss)
            opt.zero_grad()
            loss.backward()
            opt.step()
        returns.append(float(np.mean(finished)) if finished else float("nan"))
    return returns


def test_cleanrl_style_ppo_trains_through_the_wrappers():
    torch.set_num_threads(1)
    env = GymnasiumVectorEnv("crowd", num_envs=2, num_agents=4, max_steps=40)
    env = ClipAction(NormalizeObservation(RecordEpisodeStatistics(env)))
    returns = ppo(env, iterations=12, steps=82)
    assert all(np.isfinite(returns))  # every iteration finished episodes (82 > 2 x 41 steps)
    # progress toward the goal is rewarded: the policy learns to move its agents there
    assert np.mean(returns[-3:]) > np.mean(returns[:3])


IDS = sorted(registration.IDS)


@pytest.mark.parametrize("env_id", IDS)
def test_make_vec_vector_entry_point_is_the_sync_vector_of_gymnasium_make(env_id):
    """``make_vec(id, 4, vectorization_mode="vector_entry_point")`` (it raised "doesn't have a
    vector entry point defined") is the batched core with the spaces of ``gymnasium.make(id)``
    and, step by step, the episodes of a ``SyncVectorEnv`` of them: observations, summed
    rewards, flags and ``cost``, through a truncation and Gymnasium's next-step autoreset."""
    import gymnasium

    kwargs = {"max_steps": 6}
    vec = gymnasium.make_vec(env_id, 4, vectorization_mode="vector_entry_point", **kwargs)
    sync = gymnasium.make_vec(env_id, 4, vectorization_mode="sync", **kwargs)
    assert isinstance(vec, VectorEnv) and type(vec).__name__ == "JointVectorEnv"
    assert vec.single_observation_space == sync.single_observation_space
    assert vec.single_action_space == sync.single_action_space
    assert (
        vec.metadata["autoreset_mode"]
        == sync.metadata["autoreset_mode"]
        == (AutoresetMode.NEXT_STEP)
    )
    got, want = vec.reset(seed=3)[0], sync.reset(seed=3)[0]
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-6)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(15):
        a = rng.uniform(-1, 1, vec.action_space.shape).astype(np.float32)
        ours, theirs = vec.step(a), sync.step(a)
        assert vec.observation_space.contains(ours[0])
        np.testing.assert_allclose(ours[0], theirs[0], rtol=0, atol=1e-6)
        np.testing.assert_allclose(ours[1], theirs[1], rtol=1e-9, atol=1e-9)
        np.testing.assert_array_equal(ours[2], theirs[2])
        np.testing.assert_array_equal(ours[3], theirs[3])
        np.testing.assert_allclose(ours[4]["cost"], theirs[4]["cost"])
        assert ours[4]["_cost"].all()
        ended += int((ours[2] | ours[3]).sum())
    assert ended >= 8  # two truncations of every env, autoreset between
    vec.close()
    sync.close()


def test_make_vec_takes_the_filter_switch_and_refuses_drawing():
    import gymnasium

    vec = gymnasium.make_vec(
        "rsvo/Crowd-v0",
        2,
        vectorization_mode="vector_entry_point",
        safety_filter=False,
        num_agents=6,
    )
    assert not vec.unwrapped.env.sim.filters
    assert vec.reset(seed=0)[0].shape == (2, vec.single_observation_space.shape[0])
    with pytest.raises(ValueError, match="render_mode"):
        gymnasium.make_vec(
            "rsvo/Crowd-v0", 2, vectorization_mode="vector_entry_point", render_mode="rgb_array"
        )
    stats = RecordEpisodeStatistics(vec)
    stats.reset(seed=1)
    stats.step(np.zeros(vec.action_space.shape, dtype=np.float32))
