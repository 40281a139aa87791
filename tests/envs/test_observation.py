"""The compiled observation kernel against a plain numpy reading of the feature table."""

from __future__ import annotations

import numpy as np
import pytest

import rsvo_env
from rsvo_env.sim import observation


def reference(world, k: int, frame: str) -> np.ndarray:
    """(N, D) observations from the env's public state, one feature at a time, in the table's
    order (``observation.OWN_FEATURES`` then K blocks of ``NEIGHBOR_FEATURES``)."""
    x, v, g, theta = world.positions, world.velocities, world.goals, world.theta
    n = len(x)
    if frame == "goal":
        heading = world.goals - world.starts
        angle = np.arctan2(heading[:, 1], heading[:, 0])
    else:
        angle = np.zeros(n)
    c, s = np.cos(-angle), np.sin(-angle)

    def rot(vec: np.ndarray) -> np.ndarray:
        return np.stack([c * vec[:, 0] - s * vec[:, 1], s * vec[:, 0] + c * vec[:, 1]], 1)

    dist = np.linalg.norm(x[:, None] - x[None], axis=-1)
    np.fill_diagonal(dist, np.inf)
    nb = np.argsort(dist, axis=1, kind="stable")[:, :k]
    rows = np.arange(n)[:, None]
    own = {"goal_offset": rot(g - x), "velocity": rot(v), "theta": theta[:, None]}
    blocks = []
    for m in range(k):
        j = nb[:, m]
        rel = rot(x[j] - x)
        features = {
            "rel_position": rel,
            "rel_velocity": rot(v[j] - v),
            "rel_goal": rot(g[j] - x),
            "omega": world.omega[rows[:, 0], j][:, None],
            "theta": theta[j][:, None],
            "gap": np.linalg.norm(rel, axis=1, keepdims=True) - world.safety_radius,
            "present": np.ones((n, 1)),
        }
        blocks += [features[f.name] for f in observation.NEIGHBOR_FEATURES]
    parts = [own[f.name] for f in observation.OWN_FEATURES] + blocks
    return np.concatenate(parts, axis=1)


@pytest.mark.parametrize("frame", ["world", "goal"])
def test_every_feature_is_what_the_table_says(frame):
    k = 4
    env = rsvo_env.parallel_env("crowd", num_agents=9, num_obs_neighbors=k, frame=frame)
    obs, _ = env.reset(seed=3)
    world = env.unwrapped.world
    rng = np.random.default_rng(0)
    for _ in range(30):
        got = np.stack([obs[a] for a in env.possible_agents])
        want = reference(world, k, frame)
        assert got.shape == (9, observation.size(k))
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)
        obs, *_ = env.step({a: rng.uniform(-1, 1, 2) for a in env.agents})
