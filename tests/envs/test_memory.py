"""Memory that does not grow with the episode: the per-step series only where asked."""

import numpy as np

import rsvo_env


def run(env, steps):
    env.reset(seed=0)
    for _ in range(steps):
        env.step(env.unwrapped.nominal_actions())
    return env.unwrapped.sim.metrics


def test_the_parallel_env_keeps_no_per_step_series_by_default():
    metrics = run(rsvo_env.parallel_env("circular_swap"), 200)
    assert metrics.min_distance_series == [] and metrics.avg_min_distance_series == []
    assert "avg_min_distance_series" not in metrics.summary(0)


def test_record_series_keeps_one_entry_a_step():
    env = rsvo_env.parallel_env("circular_swap", record_series=True)
    metrics = run(env, 200)
    assert len(metrics.min_distance_series) == 200
    series = metrics.summary(0)["avg_min_distance_series"]
    assert series.shape == (200,) and np.all(series >= metrics.summary(0)["min_distance"])
