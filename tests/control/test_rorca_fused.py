"""R-ORCA's scripted step in one compiled call (``rsvo_env.control.rorca.fused``): what a user's
``nominal_actions()`` runs in envs of more than ``sizes.ALL_PAIRS_MAX_AGENTS`` agents gives the
velocities of the calls one by one (move-to-goal, routing, the rules' clocks, the stage), bit for
bit, in every setting it serves, and steps aside where it does not."""

from __future__ import annotations

import numpy as np
import pytest

from rsvo_env.control import Controller
from rsvo_env.control.rorca import fused
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.util import sizes, threads

CASES = [
    {},
    {"rorca_route": False},
    {"rorca_goal_reached": False, "rorca_goal_hold": 0.3},
    {"theta_range": (0.1, 50.0)},
    {"deadlock_resolution": "none"},
    {"dynamics": "unicycle"},
    {"dynamics": "double_integrator"},
]


@pytest.mark.parametrize("kwargs", CASES, ids=lambda k: ",".join(k) or "crowd")
@pytest.mark.parametrize("num_envs", [1, 3])
def test_the_one_call_is_the_calls_one_by_one_bit_for_bit(kwargs, num_envs, monkeypatch):
    served = []
    one_call = fused.nominal
    monkeypatch.setattr(fused, "nominal", lambda *a: served.append(one_call(*a)) or served[-1])
    n = sizes.ALL_PAIRS_MAX_AGENTS + 16
    env = BatchedEnv("crowd", num_envs=num_envs, num_agents=n, **kwargs)
    env.reset(seed=5)
    sc, st = env.sim.scenario, env.sim.state
    if num_envs == 3:
        env.set_weighting("symmetric")  # one weighting for all, then one env apart
        env.sim.set_weighting(1, "asymmetric")
    compared, reached = 0, False
    for step in range(400):
        if step % 40 == 0:
            reached |= bool(st.reached.any() and not st.at_goal[st.reached].all())
            fast = sc.controller.nominal(st, sc, True)
            slow = Controller.nominal(sc.controller, st, sc, True)
            np.testing.assert_array_equal(fast, slow)
            compared += 1
        env.step(env.nominal_actions())
    assert compared == 10 and served and all(v is not None for v in served)
    assert reached or kwargs.get("rorca_goal_reached") is False  # the goal rule's reached part
    assert st.no_progress.max() > 0  # the clocks ran


def test_it_serves_large_envs_on_one_thread_and_steps_aside_elsewhere():
    env = BatchedEnv("crowd", num_envs=1, num_agents=sizes.ALL_PAIRS_MAX_AGENTS + 1)
    env.reset(seed=0)
    sc, st = env.sim.scenario, env.sim.state
    p = sc.params
    pts, vel, extra = sc.model.steered(st, p)
    args = (st, (st.positions, p["k"], None, p["rh_angle_deg"]), pts, vel, sc.radii + extra,
            sc.controller_settings, p["safety_radius"], p["dt"], sc.speed)  # fmt: skip
    assert fused.nominal(*args) is not None
    small = BatchedEnv("crowd", num_envs=1, num_agents=sizes.ALL_PAIRS_MAX_AGENTS)
    small.reset(seed=0)
    s2 = small.sim.state
    pts2, vel2, _ = small.sim.scenario.model.steered(s2, p)
    small_args = (s2, (s2.positions, p["k"], None, p["rh_angle_deg"]), pts2, vel2,
                  small.sim.scenario.radii, *args[5:])  # fmt: skip
    assert fused.nominal(*small_args) is None  # the dense stage's size
    with threads.using(2):
        many = BatchedEnv("crowd", num_envs=4, num_agents=sizes.PARALLEL_MIN_PROBLEMS)
        many.reset(seed=0)
        s3 = many.sim.state
        pts3, vel3, _ = many.sim.scenario.model.steered(s3, p)
        big_args = (s3, (s3.positions, p["k"], None, p["rh_angle_deg"]), pts3, vel3,
                    many.sim.scenario.radii, *args[5:])  # fmt: skip
        assert fused.nominal(*big_args) is None  # a parallel launch
