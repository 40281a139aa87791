"""The ids in gymnasium's and PettingZoo's registries, checked by their own checkers."""

import warnings

import gymnasium
import numpy as np
import pettingzoo
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from pettingzoo.test import api_test, parallel_api_test
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import rsvo_env  # noqa: F401  (registers the ids)
from rsvo_env.envs.registration import IDS
from tests.support.checkers import checked
from tests.support.checkout import run_python


@pytest.mark.parametrize("env_id", list(IDS))
def test_gymnasium_and_sb3_checkers(env_id):
    env = gymnasium.make(env_id)
    gym_check_env(env.unwrapped, skip_render_check=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error", category=UserWarning)
        sb3_check_env(gymnasium.make(env_id).unwrapped, warn=True)
    env.close()


@pytest.mark.parametrize("env_id", list(IDS))
def test_pettingzoo_registry(env_id):
    env = pettingzoo.make("parallel", env_id)
    assert isinstance(env, rsvo_env.RSVOParallelEnv) and len(env.sim.filters) == 1
    checked(parallel_api_test, env, num_cycles=300)
    checked(api_test, pettingzoo.make("aec", env_id), num_cycles=300)
    bare = pettingzoo.make("parallel", env_id, safety_filter=False)
    assert isinstance(bare, rsvo_env.RSVOParallelEnv) and bare.sim.filters == []


def test_kwargs_pass_through_and_unknown_ones_raise():
    env = gymnasium.make("rsvo/Crowd-v0", num_agents=4, gamma=5.0)
    assert env.action_space.shape == (8,)
    assert env.unwrapped.parallel.sim.filters[0].config.gamma == 5.0
    p = pettingzoo.make("parallel", "rsvo/CircularSwap-v0", num_agents=8)
    assert len(p.possible_agents) == 8
    with pytest.raises(TypeError, match=r"\['warp'\]"):
        gymnasium.make("rsvo/Crowd-v0", warp=9)
    with pytest.raises(TypeError, match=r"\['warp'\]"):
        pettingzoo.make("parallel", "rsvo/Crowd-v0", warp=9)


def test_make_without_prior_import():
    code = (
        "import gymnasium, sys\n"
        "env = gymnasium.make('rsvo_env:rsvo/CircularSwap-v0')\n"
        "obs, _ = env.reset(seed=0)\n"
        "print(obs.shape)\n"
    )
    out = run_python("-c", code)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "(330,)"  # 6 agents x (5 + 10 x 5 neighbours)


def test_gymnasium_env_is_deterministic_under_a_seed():
    def roll():
        env = gymnasium.make("rsvo/Crowd-v0", num_agents=6)
        obs, _ = env.reset(seed=3)
        env.action_space.seed(3)
        out = [obs]
        for _ in range(50):
            obs, r, *_ = env.step(env.action_space.sample())
            out += [obs, np.float64(r)]
        return np.concatenate([np.ravel(o) for o in out])

    np.testing.assert_array_equal(roll(), roll())
