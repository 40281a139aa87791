"""Discrete-time safety of the single integrator: x += dt u with gamma dt <= 1 never collides.

docs/math.md: each pair's rows sum to 2 dx.(u_i - u_j) >= -gamma h, and then
h+ = h + 2 dt dx.(u_i - u_j) + dt^2 |u_i - u_j|^2 >= (1 - gamma dt) h >= 0.
"""

import numpy as np
import pytest

from rsvo_env.filter.safety import FilterConfig, SafetyFilter


def crossing_scenario(rng: np.random.Generator) -> dict:
    """Dense crossing traffic: agents on a ring (or a random cluster) heading through the middle."""
    n = int(rng.integers(2, 31))
    R = float(rng.uniform(0.5, 1.5))
    ring = max(1.2 * R * n / np.pi, 2.0 * R)
    if rng.random() < 0.5:
        angles = np.linspace(0, 2 * np.pi, n, endpoint=False) + rng.uniform(0, 0.2)
        x0 = ring * np.stack([np.cos(angles), np.sin(angles)], axis=1)
        goals = -x0 + rng.normal(scale=0.3 * R, size=(n, 2))
    else:
        x0 = []
        side = 2.0 * np.sqrt(n) * R
        while len(x0) < n:
            p = rng.uniform(-side, side, 2)
            if all(np.linalg.norm(p - q) >= 1.01 * R for q in x0):
                x0.append(p)
        x0 = np.array(x0)
        goals = x0[rng.permutation(n)] * -1.0
    theta = 10.0 ** rng.uniform(-3, 3, n)  # ratios up to 1e6
    theta[rng.random(n) < 0.25] = 0.0
    dt = float(rng.choice([0.01, 0.02, 0.05]))
    gamma = float(rng.uniform(0.2, 1.0)) / dt  # gamma dt in (0.2, 1], 1 included below
    if rng.random() < 0.2:
        gamma = 1.0 / dt
    return dict(
        x0=x0,
        goals=goals,
        theta=theta,
        R=R,
        dt=dt,
        gamma=gamma,
        u_max=float(rng.uniform(0.5, 3.0)),
        k=float(rng.uniform(0.5, 5.0)),
    )


def rollout(sc: dict, steps: int, filter_dt: float | None) -> tuple[float, int]:
    cfg = FilterConfig(gamma=sc["gamma"], safety_radius=sc["R"], u_max=sc["u_max"], dt=filter_dt)
    flt = SafetyFilter(cfg)
    x = sc["x0"].copy()
    min_dist, n_infeasible = np.inf, 0
    i, j = np.triu_indices(len(x), 1)
    for _ in range(steps):
        nominal = -sc["k"] * (x - sc["goals"])
        norm = np.linalg.norm(nominal, axis=1, keepdims=True)
        nominal *= np.minimum(1.0, sc["u_max"] / np.maximum(norm, 1e-12))
        res = flt.filter(x, nominal, sc["theta"])
        n_infeasible += int((~res.feasible).sum())
        x = x + sc["dt"] * res.actions
        min_dist = min(min_dist, float(np.linalg.norm(x[i] - x[j], axis=1).min()))
    return min_dist, n_infeasible


@pytest.mark.parametrize("chunk", range(8))
def test_random_crossing_traffic_never_collides(chunk):
    """200 scenarios (8 chunks of 25), 1,000 steps each."""
    worst = np.inf
    for s in range(25 * chunk, 25 * (chunk + 1)):
        sc = crossing_scenario(np.random.default_rng(s))
        min_dist, n_infeasible = rollout(sc, 1000, sc["dt"])
        assert n_infeasible == 0, s
        assert min_dist >= sc["R"] - 1e-9, (s, min_dist, sc["R"])
        worst = min(worst, min_dist - sc["R"])
    assert np.isfinite(worst)


def test_gamma_dt_above_one_collides():
    """The companion: the same filter with gamma dt = 3 lets two agents overlap, so the test
    above can fail. FilterConfig refuses gamma dt > 1 when given dt, so dt is left out here."""
    sc = dict(
        x0=np.array([[-3.0, 0.0], [3.0, 0.0]]),
        goals=np.array([[3.0, 0.0], [-3.0, 0.0]]),
        theta=np.array([1.0, 1.0]),
        R=1.0,
        dt=0.05,
        gamma=60.0,
        u_max=3.0,
        k=5.0,
    )
    min_dist, _ = rollout(sc, 200, filter_dt=None)
    assert min_dist < sc["R"] - 1e-3
    with pytest.raises(ValueError, match="gamma \\* dt"):
        FilterConfig(gamma=60.0, dt=0.05)


@pytest.mark.parametrize("log_scale", [-3.0, -1.5, 0.0, 1.5, 3.0])
def test_the_guarantee_holds_in_any_units(log_scale):
    """The same crossings in kilometres ... millimetres (lengths and speeds times 10^k): min
    distance >= R (1 - 1e-9) throughout, and no infeasible step."""
    s = 10.0**log_scale
    for seed in range(8):
        sc = crossing_scenario(np.random.default_rng(1000 + seed))
        scaled = {**sc, "x0": sc["x0"] * s, "goals": sc["goals"] * s, "R": sc["R"] * s}
        scaled["u_max"] = sc["u_max"] * s
        min_dist, n_infeasible = rollout(scaled, 300, scaled["dt"])
        assert min_dist >= scaled["R"] * (1 - 1e-9), (seed, log_scale, min_dist / s, sc["R"])
        assert n_infeasible == 0, (seed, log_scale)
