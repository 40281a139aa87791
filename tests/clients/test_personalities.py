"""The fixed-assignment measure behind the personality search (rsvo_env.training.personalities): one
batch of assignments x seeds equals the episodes run one at a time."""

import numpy as np

from rsvo_env.cli.episode import run
from rsvo_env.training.personalities import PAPER_GAME, alternating, evaluate, objective


def test_the_batch_equals_single_runs_of_the_paper_game():
    stats = evaluate([alternating(6), [1.0] * 6, [1, 3, 9, 2, 5, 4]], [0], **PAPER_GAME)
    for k, theta in enumerate([alternating(6), [1.0] * 6, [1, 3, 9, 2, 5, 4]]):
        single = run("circular_swap", theta=[float(t) for t in theta], **PAPER_GAME)
        assert stats["completed"][k, 0] == single["completed"]
        assert stats["resolution"][k, 0] == single["deadlock_resolved"] - single["deadlock_onset"]
        assert stats["collision_steps"][k, 0] == 0 == single["n_collision_steps"]
        assert stats["min_distance"][k, 0] == single["min_distance"]
    # equal scores are the symmetric weighting: the same episode
    sym = evaluate([alternating(6)], [0], weighting="symmetric", **PAPER_GAME)
    assert sym["completed"][0, 0] == stats["completed"][1, 0]


def test_seeds_and_assignments_are_independent_in_the_batch():
    theta = np.array([[1.0, 4.0, 2.0, 8.0, 1.5], [3.0, 1.0, 1.0, 2.0, 9.0]])
    kwargs = {"num_agents": 5, "max_steps": 400}
    both = evaluate(theta, [4, 9], "crowd", **kwargs)
    for k in range(2):
        for j, seed in enumerate([4, 9]):
            one = evaluate(theta[k : k + 1], [seed], "crowd", **kwargs)
            for key, value in one.items():
                assert np.array_equal(value[0, 0], both[key][k, j], equal_nan=True), key


def test_the_objective_counts_an_unfinished_episode_as_twice_the_cap():
    stats = {"completed": np.array([[100.0, -1.0], [50.0, 70.0]])}
    assert objective(stats, 300).tolist() == [350.0, 60.0]


def test_a_right_hand_rule_first_fired_after_the_resolution_resolved_no_deadlock():
    """Routed R-ORCA's right-hand rule waits 5 s of no progress, so in crowds it can first fire
    after every agent has passed its midpoint: no deadlock was resolved then (NaN), never a
    negative time; where it fired first, the time is resolved - onset."""
    kwargs = {
        "num_agents": 12,
        "dt": 0.05,
        "gamma": 20.0,
        "max_steps": 4000,
        "theta_range": [1.0, 10.0],
    }
    seeds = list(range(1000, 1040))
    stats = evaluate(None, seeds, "crowd", **kwargs)
    res = stats["resolution"][0]
    assert np.isnan(res).any() and not (res < 0).any()
    at_once = evaluate(None, seeds, "crowd", rh_hold=0.0, **kwargs)["resolution"][0]
    assert np.isfinite(at_once).any() and not (at_once < 0).any()
