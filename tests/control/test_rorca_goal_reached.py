"""R-ORCA's goal rule in the crowd: an agent that has reached its goal yields as parked within
the rule's reach (``rorca_goal_reached``, ``rsvo_env.control.rorca.scripted``)."""

import numpy as np

from rsvo_env.training import config


def test_an_agent_that_has_reached_its_goal_yields_as_parked_within_the_goal_rules_reach():
    """The crowd of 1,000 as the learned residual's evaluation runs its scripted controller
    (``python -m benchmarks.studies.liveness --learned``: the crowd config's env, dt 0.1, gamma dt =
    1, theta 1..10, R-ORCA), seed 1008, with the crowd's horizon at 1.25 s: agent 289, an egoist
    parked on its goal in the path of agent 344, stepped off the goal's tolerance to yield and back
    in a 0.9 s cycle; back on its goal its clock restarted, so the goal rule's 1 s hold never fired,
    it pressed back as an agent en route, and 344 stood 2.4 m short for the rest of the 300 s. In
    the crowd an agent that has reached its goal now yields as parked within the rule's reach
    (``rorca_goal_reached``): every agent is home at once by step 1,500 (1,126 measured)."""
    cfg = config.load("crowd")
    for assignment in ("env.nominal=rorca", "env.num_agents=1000", "stall_gate=5"):
        config.set_value(cfg, assignment)
    # the evaluation's scripted run (training.seeded_episodes.run_episodes): the config's env
    env = config.make_env(cfg, num_envs=1, action="direct", max_steps=1500)
    env.reset(seed=1008)
    for _ in range(1500):
        _, _, term, trunc, info = env.step(env.nominal_actions())
        assert info["min_distance"].min() >= 1.0 - 1e-9
        if term.any() or trunc.any():
            break
    short = np.nonzero(~info["at_goal"][0])[0].tolist()
    assert term[0], f"agents {short} not at their goals after {int(info['episode_steps'][0])} steps"
