"""theta_range and random_rotation: episodes drawn from the env's own seeded generator."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env.envs.vector import BatchedEnv


def test_theta_range_draws_each_episode_in_range_and_repeats_under_a_seed():
    env = rsvo_env.parallel_env("crowd", num_agents=5, theta_range=(1.0, 10.0))
    env.reset(seed=3)
    first = env.unwrapped.world.theta.copy()
    env.reset()
    second = env.unwrapped.world.theta.copy()
    assert ((first >= 1.0) & (first < 10.0)).all() and not np.array_equal(first, second)
    env.reset(seed=3)
    assert np.array_equal(env.unwrapped.world.theta, first)
    np.random.seed(0)  # noqa: NPY002  (the global generator, to see that it is never drawn)
    state = np.random.get_state()[1].copy()  # noqa: NPY002
    env.reset(seed=4)
    assert np.array_equal(np.random.get_state()[1], state)  # noqa: NPY002
    env.reset(seed=5, options={"theta": [2, 2, 2, 2, 2]})
    assert np.array_equal(env.unwrapped.world.theta, np.full(5, 2.0))  # the option wins


def test_random_rotation_keeps_the_circle_and_antipodal_goals():
    venv = BatchedEnv("circular_swap", num_envs=4, random_rotation=True)
    venv.reset(seed=0)
    x, g = venv.sim.state.positions, venv.sim.state.goals
    assert np.allclose(np.linalg.norm(x, axis=-1), 5.0) and np.allclose(g, -x)
    angles = np.arctan2(x[:, 0, 1], x[:, 0, 0])
    assert len(np.unique(np.round(angles, 6))) == 4  # each env turned by its own angle
    fixed = BatchedEnv("circular_swap", num_envs=1)
    fixed.reset(seed=0)
    assert np.allclose(fixed.sim.state.positions[0, 0], [5.0, 0.0])


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"theta_range": (0.0, 3.0)}, ["theta_range", "0.0"]),
        ({"theta_range": (5.0, 2.0)}, ["theta_range", "5.0"]),
        ({"theta_range": (1.0, np.nan)}, ["theta_range"]),
        ({"theta_range": "ab"}, ["theta_range", "ab"]),
        ({"theta_range": (1.0, 2.0, 3.0)}, ["theta_range"]),
        ({"theta_range": (1.0, 5000.0)}, ["theta_range", "theta_max"]),
        ({"theta_range": (1.0, 2.0), "theta": [1.0] * 6}, ["theta", "theta_range"]),
        ({"random_rotation": 1}, ["random_rotation", "1"]),
        ({"random_rotation": "yes"}, ["random_rotation", "yes"]),
    ],
)
def test_bad_values_name_the_field(kwargs, words):
    with pytest.raises(ValueError) as err:
        rsvo_env.parallel_env("circular_swap", **kwargs)
    assert all(w in str(err.value) for w in words), str(err.value)
