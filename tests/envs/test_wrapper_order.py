"""Safety does not depend on wrapper order: the filter is a stage of the core's step, so whatever
sits between ``RCBFSafetyFilter`` and the base env, the control it certifies is the control
integrated, and ``u_safe`` in the infos is exactly that control."""

import numpy as np
import pytest
from pettingzoo.utils import BaseParallelWrapper

import rsvo_env
from rsvo_env import wrappers


class Recorder(BaseParallelWrapper):
    """Innermost: records every base step's positions before and after, and its infos."""

    def __init__(self, env):
        super().__init__(env)
        self.log = []

    def step(self, actions):
        before = self.env.unwrapped.world.positions.copy()
        out = self.env.step(actions)
        self.log.append((before, self.env.unwrapped.world.positions.copy(), out[4]))
        return out


class ActionRepeat(BaseParallelWrapper):
    """Steps the inner env twice with the same actions (a common RL wrapper)."""

    def step(self, actions):
        out = self.env.step(actions)
        if self.env.agents:
            out = self.env.step(actions)
        return out


class ActionNoise(BaseParallelWrapper):
    """Adds seeded Gaussian noise to every action."""

    def __init__(self, env, seed):
        super().__init__(env)
        self.rng = np.random.default_rng(seed)

    def step(self, actions):
        noisy = {a: v + self.rng.normal(0, 0.5, 2).astype(np.float32) for a, v in actions.items()}
        return self.env.step(noisy)


def stack(kind, seed):
    bare = rsvo_env.parallel_env("crowd", num_agents=12, max_steps=150, safety_filter=False)
    rec = Recorder(bare)
    if kind == "repeat_inside":
        return wrappers.RCBFSafetyFilter(ActionRepeat(rec)), rec
    if kind == "noise_inside":
        return wrappers.RCBFSafetyFilter(ActionNoise(rec, seed)), rec
    if kind == "two_filters":
        return wrappers.RCBFSafetyFilter(wrappers.RCBFSafetyFilter(rec, gamma=5.0)), rec
    if kind == "weighting_outside":
        return wrappers.ResponsibilityWeighting(wrappers.RCBFSafetyFilter(rec), "symmetric"), rec
    return wrappers.RCBFSafetyFilter(wrappers.ResponsibilityWeighting(rec, "symmetric")), rec


KINDS = ["repeat_inside", "noise_inside", "two_filters", "weighting_outside", "weighting_inside"]


@pytest.mark.parametrize("kind", KINDS)
def test_safe_and_truthful_in_any_order(kind):
    """100 seeded crowds per stack, every agent rushing the centre at full speed."""
    worst_gap, worst_mismatch = np.inf, 0.0
    for seed in range(100):
        env, rec = stack(kind, seed)
        env.reset(seed=seed, options={"theta": np.random.default_rng(seed).uniform(0, 10, 12)})
        base = env.unwrapped
        R, dt = base.world.safety_radius, base.dt
        while env.agents:
            x = base.world.positions
            to_centre = -x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-12)
            env.step({a: to_centre[i].astype(np.float32) for i, a in enumerate(env.agents)})
        for before, after, infos in rec.log:
            u_safe = np.stack([infos[a]["u_safe"] for a in base.possible_agents])
            worst_mismatch = max(worst_mismatch, np.abs((after - before) / dt - u_safe).max())
            gaps = np.linalg.norm(after[:, None] - after[None], axis=-1) + np.eye(12) * 1e9
            worst_gap = min(worst_gap, gaps.min())
            assert all(i["feasible"] and i["cost"] == 0.0 for i in infos.values())
        assert base.episode_metrics["n_collision_steps"] == 0
    assert worst_gap >= R - 1e-9, worst_gap
    assert worst_mismatch <= 1e-12, worst_mismatch


def test_stacked_filters_report_what_is_applied():
    """Two filters with different gains: the reported u_safe is the control integrated (the
    old side channel reported the outer filter's [-3, 0] while [-1.26, 0] was applied)."""
    rec = Recorder(rsvo_env.parallel_env("position_swap", max_steps=400, safety_filter=False))
    env = wrappers.RCBFSafetyFilter(wrappers.RCBFSafetyFilter(rec, gamma=1.0), gamma=5.0)
    env.reset(seed=0, options={"theta": [1.0, 1.0]})
    while env.agents:
        env.step(env.unwrapped.nominal_actions())
    dt = env.unwrapped.dt
    for before, after, infos in rec.log:
        u_safe = np.stack([infos[a]["u_safe"] for a in env.possible_agents])
        np.testing.assert_allclose((after - before) / dt, u_safe, rtol=0, atol=1e-12)
    assert env.unwrapped.episode_metrics["min_distance"] >= 1.0 - 1e-9


def test_unwrapped_filter_stage_cannot_be_bypassed_by_inner_wrappers():
    """Without the filter, the same action-repeat stack collides (the test can fail)."""
    rec = Recorder(rsvo_env.parallel_env("position_swap", max_steps=400, safety_filter=False))
    env = ActionRepeat(rec)
    env.reset(seed=0, options={"theta": [1.0, 1.0]})
    while env.agents:
        env.step(env.unwrapped.nominal_actions())
    assert env.unwrapped.episode_metrics["min_distance"] < 1.0
