"""PPO-Lagrangian (training/lagrangian.py): the multiplier's dual ascent, the cost GAE against
SB3's own, and the baseline's command end to end (the issue's acceptance command)."""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rsvo_env.training.lagrangian import Lagrange, gae
from tests.support.checkout import run_python

ROOT = Path(__file__).resolve().parents[2]
# episode costs are means of step counts: tenths, so that a step of lr (cost - limit) registers
costs = st.integers(0, 500).map(lambda k: k / 10)


@given(costs, st.floats(0.0, 5.0), st.floats(1e-3, 1.0), st.lists(costs, min_size=1, max_size=30))
def test_the_multiplier_rises_while_the_cost_exceeds_the_limit_and_falls_otherwise(
    limit, start, lr, episode_costs
):
    lagrange = Lagrange(limit, start, lr)
    for cost in episode_costs:
        before = lagrange.multiplier
        after = lagrange.update(cost)
        assert after >= 0.0
        if cost > limit:
            assert after > before
        elif cost < limit:
            assert after < before or after == before == 0.0
        else:
            assert after == before


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_the_multiplier_refuses_a_cost_that_is_not_finite(bad):
    lagrange = Lagrange(1.0, 0.5, 0.1)
    with pytest.raises(ValueError, match="episode_cost"):
        lagrange.update(bad)
    assert lagrange.multiplier == 0.5


@settings(max_examples=30)
@given(
    st.integers(1, 12),
    st.integers(1, 5),
    st.integers(0, 2**31 - 1),
    st.floats(0.5, 1.0),
    st.floats(0.0, 1.0),
)
def test_the_cost_advantage_is_sb3s_gae(T, S, seed, gamma, lam):
    """The cost's GAE equals what SB3's rollout buffer computes for a reward with the same
    values and episode starts."""
    import gymnasium as gym
    import torch as th
    from stable_baselines3.common.buffers import RolloutBuffer

    rng = np.random.default_rng(seed)
    space = gym.spaces.Box(-1, 1, (2,))
    buf = RolloutBuffer(T, space, space, "cpu", gamma=gamma, gae_lambda=lam, n_envs=S)
    rewards = rng.random((T, S)).astype(np.float32)
    values = rng.random((T, S)).astype(np.float32)
    starts = (rng.random((T, S)) < 0.3).astype(np.float32)
    for t in range(T):
        buf.add(
            np.zeros((S, 2)),
            np.zeros((S, 2)),
            rewards[t],
            starts[t],
            th.as_tensor(values[t]),
            th.zeros(S),
        )
    last, dones = rng.random(S).astype(np.float32), rng.random(S) < 0.3
    buf.compute_returns_and_advantage(th.as_tensor(last), dones)
    adv, ret = gae(rewards, values, starts, last, dones.astype(np.float32), gamma, lam)
    assert np.allclose(adv, buf.advantages, rtol=1e-5, atol=1e-5)
    assert np.allclose(ret, buf.returns, rtol=1e-5, atol=1e-5)


def _train(out: Path, *sets: str) -> list[dict[str, str]]:
    """A short PPO-Lagrangian run without the filter (the checkout under test)."""
    args = [
        sys.executable,
        "-m",
        "rsvo_env.training.train",
        "--scenario",
        "circular_swap",
        "--set",
        "algo=ppo_lagrangian",
        "--set",
        "env.safety_filter=false",
        "--set",
        "ppo.n_steps=8",
        "--set",
        "ppo.batch_size=384",
        "--set",
        "validation.episodes=4",
        "--set",
        "validation.every=24576",
        "--timesteps",
        "24576",
        "--no-progress",
        "--out",
        str(out),
    ]
    for s in sets:
        args += ["--set", s]
    done = run_python(*args[1:], timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    with open(out / "lagrangian.csv") as f:
        return list(csv.DictReader(f))


@pytest.mark.parametrize("limit, direction", [(0.0, 1), (1000.0, -1)])
def test_a_run_logs_the_multiplier_moving_against_its_episode_cost(tmp_path, limit, direction):
    """Without the filter agents touch: with a cost limit of 0 the multiplier climbs at every
    update that saw an episode end, with a limit of 1,000 it falls (to 0 at the least); each
    logged step is dual ascent on the logged episode cost. validation.csv carries OmniSafe's
    columns."""
    out = tmp_path / "run"
    rows = _train(out, f"lagrangian.cost_limit={limit}", "lagrangian.multiplier_lr=0.01")
    assert len(rows) == 24576 // (8 * 6 * 32)
    before, moved = 0.5, 0
    for row in rows:
        cost, lam = float(row["episode_cost"]), float(row["multiplier"])
        if np.isnan(cost):
            assert lam == before
            continue
        assert lam == pytest.approx(max(0.0, before + 0.01 * (cost - limit)), rel=1e-12)
        if direction > 0:
            assert cost > 0 and lam > before
        else:
            assert lam < before or lam == 0.0
        before, moved = lam, moved + 1
    assert moved >= 2
    with open(out / "validation.csv") as f:
        header = next(csv.reader(f))
    assert {"episode_return", "episode_cost", "episode_length"} <= set(header)
    progress = (out / "progress.csv").read_text().splitlines()[0]
    assert "lagrangian/multiplier" in progress and "lagrangian/episode_cost" in progress


def test_a_lagrangian_model_loads_for_evaluation(tmp_path):
    """The saved model (its cost critic in the policy) loads and evaluates as any SB3 model."""
    out = tmp_path / "run"
    _train(out)
    done = run_python(
        "-m", "rsvo_env.training.evaluate", str(out / "model.zip"), "--episodes", "3", timeout=600
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "success" in done.stdout


def test_the_safe_rl_comparison_holds_its_claims():
    """benchmarks/results/safe_rl.json (written with safe_rl.md by
    benchmarks/studies/safe_rl.py): four methods on both scenarios, three training seeds each;
    behind the filter the cost is exactly 0 in training and at evaluation, and each unfiltered
    method paid contacts in training."""
    import json

    results = json.loads((ROOT / "benchmarks/results/safe_rl.json").read_text())
    for scenario in ("circular_swap", "crowd"):
        for method in ("scripted", "residual", "ppo", "ppo_lagrangian"):
            seeds = results[f"{scenario}/{method}"]
            assert len(seeds) == (1 if method == "scripted" else 3), (scenario, method)
            assert all(s["episodes"] == 100 for s in seeds)
            if method in ("scripted", "residual"):
                assert all(s["episode_cost"] == 0 and s["collisions"] == 0 for s in seeds)
            if method != "scripted":
                contacts = [s["train_contacts"] for s in seeds]
                assert all(c == 0 for c in contacts) if method == "residual" else min(contacts) > 0
    text = (ROOT / "benchmarks/results/safe_rl.md").read_text()
    assert "PPO-Lagrangian, no filter" in text and "![training curves](safe_rl.png)" in text
