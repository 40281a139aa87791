"""The R-CBF filter wrapper, the weighting toggle and the joint-control env."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env import wrappers


def filtered(name, **kwargs):
    return rsvo_env.parallel_env(name, **kwargs)  # filtered by default


def run(env, seed=0, options=None, policy="nominal", rng=None, check=None):
    env.reset(seed=seed, options=options)
    infos = {}
    while env.agents:
        if policy == "nominal":
            actions = env.unwrapped.nominal_actions()
        else:
            actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        _, _, _, _, infos = env.step(actions)
        if check:
            check(infos)
    return env.unwrapped.episode_metrics


@pytest.mark.parametrize("chunk", range(4))
def test_crowds_rushing_the_centre_stay_safe(chunk):
    """100 seeded crowd episodes of 30 agents (4 chunks of 25), all heading for the centre."""
    for seed in range(25 * chunk, 25 * (chunk + 1)):
        env = filtered("crowd", num_agents=30, max_steps=500)
        env.reset(seed=seed)
        base = env.unwrapped
        R = base.world.safety_radius
        while env.agents:
            x = base.world.positions
            to_centre = -x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-12)
            actions = {a: to_centre[i].astype(np.float32) for i, a in enumerate(env.agents)}
            _, _, _, _, infos = env.step(actions)
            assert all(i["cost"] == 0.0 and i["feasible"] for i in infos.values()), seed
        m = base.episode_metrics
        assert m["min_distance"] >= R - 1e-9, (seed, m["min_distance"])
        assert m["n_infeasible"] == 0 and m["n_collision_steps"] == 0


@pytest.mark.parametrize("name", ["position_swap", "circular_swap", "crowd"])
@pytest.mark.parametrize("policy", ["nominal", "random"])
def test_paper_scenarios_stay_safe(name, policy):
    env = filtered(name)
    for seed in range(3):
        m = run(env, seed=seed, policy=policy, rng=np.random.default_rng(seed))
        R = env.unwrapped.world.safety_radius
        assert m["min_distance"] >= R - 1e-9
        assert m["n_infeasible"] == 0 and m["n_collision_steps"] == 0


@pytest.mark.parametrize("policy", ["nominal", "random"])
def test_ramp_merge_stays_safe(policy):
    env = filtered("ramp_merge")
    for theta in ([1.0, 1.0], [1.0, 4.0], [4.0, 1.0]):
        m = run(env, options={"theta": theta}, policy=policy, rng=np.random.default_rng(1))
        assert m["min_distance"] >= 5.0
        assert m["n_infeasible"] == 0 and m["n_collision_steps"] == 0


def test_info_fields_and_intervention_penalty():
    # the paper's move-to-goal, which the filter corrects (R-ORCA rarely needs it to)
    plain = filtered("circular_swap", nominal="move_to_goal")
    bare = rsvo_env.parallel_env("circular_swap", nominal="move_to_goal", safety_filter=False)
    penal = wrappers.RCBFSafetyFilter(bare, intervention_penalty=0.5)
    plain.reset(seed=0)
    penal.reset(seed=0)
    for _ in range(150):
        _, r1, _, _, i1 = plain.step(plain.unwrapped.nominal_actions())
        _, r2, _, _, i2 = penal.step(penal.unwrapped.nominal_actions())
    info = i1["agent_0"]
    for key in (
        "u_nominal",
        "u_safe",
        "intervention",
        "feasible",
        "active_constraints",
        "min_distance",
        "cost",
        "at_goal",
    ):
        assert key in info
    assert info["intervention"] == pytest.approx(np.linalg.norm(info["u_safe"] - info["u_nominal"]))
    assert any(i["intervention"] > 0.1 for i in i1.values())  # the filter is at work by now
    for a in r1:
        assert r2[a] == pytest.approx(r1[a] - 0.5 * i1[a]["intervention"] ** 2)
    # the applied control is the safe one, not the nominal: (x+ - x) / dt
    before = plain.unwrapped.world.positions.copy()
    _, _, _, _, i1 = plain.step(plain.unwrapped.nominal_actions())
    moved = (plain.unwrapped.world.positions - before) / plain.unwrapped.dt
    np.testing.assert_allclose(moved[0], i1["agent_0"]["u_safe"], rtol=0, atol=1e-12)


def test_infeasible_steps_apply_least_violation_and_are_counted():
    """Start two double-integrator vehicles inside the unsafe set (closing too fast to brake):
    the QP is infeasible, the applied action is not the nominal, and the episode counts it."""
    env = filtered("ramp_merge", v0=40.0, start_distance=12.0, max_steps=30)
    env.reset(seed=0)
    base = env.unwrapped
    _, _, _, _, infos = env.step(base.nominal_actions())
    assert not infos["agent_0"]["feasible"]
    assert infos["agent_0"]["max_violation"] > 0
    assert not np.allclose(infos["agent_0"]["u_safe"], infos["agent_0"]["u_nominal"])
    while env.agents:
        _, _, _, _, infos = env.step(base.nominal_actions())
    assert base.episode_metrics["n_infeasible"] > 0


# ---- symmetric vs asymmetric ----


def distance_before_meeting(weighting):
    """Path length of each agent up to the first step the right-hand rule fires."""
    env = wrappers.ResponsibilityWeighting(filtered("position_swap", keep_history=True), weighting)
    env.reset(seed=0, options={"theta": [1.0, 4.0]})
    base = env.unwrapped
    while env.agents and base.metrics.deadlock_onset is None:
        env.step(base.nominal_actions())
    hist = np.stack(base.history)
    return np.linalg.norm(np.diff(hist, axis=0), axis=2).sum(axis=0)


def test_egoist_travels_farther_before_meeting():
    d = distance_before_meeting("asymmetric")
    assert d[0] > d[1] * 1.05, d


def test_symmetric_toggle_gives_equal_distances():
    d = distance_before_meeting("symmetric")
    assert abs(d[0] - d[1]) <= 1e-9, d


@pytest.mark.parametrize("order", ["filter_outside", "weighting_outside"])
def test_weighting_stacks_in_either_order(order):
    def make(mode):
        env = rsvo_env.parallel_env("circular_swap")
        if order == "filter_outside":
            return wrappers.RCBFSafetyFilter(wrappers.ResponsibilityWeighting(env, mode))
        return wrappers.ResponsibilityWeighting(wrappers.RCBFSafetyFilter(env), mode)

    theta = {"theta": [2, 1, 2, 1, 2, 1]}
    sym = run(make("symmetric"), options=theta)
    asym = run(make("asymmetric"), options=theta)
    assert sym["completed"] != asym["completed"]
    # the per-episode option overrides the wrapper's mode
    forced = run(make("asymmetric"), options={**theta, "weighting": "symmetric"})
    assert forced["completed"] == sym["completed"]


def test_callable_weighting_is_validated():
    env = rsvo_env.parallel_env("position_swap")
    wrappers.ResponsibilityWeighting(env, lambda th: np.array([[0.0, 0.9], [0.1, 0.0]]))
    env.reset(seed=0)
    assert env.unwrapped.world.omega[0, 1] == 0.9
    with pytest.raises(ValueError, match=r"omega\[0, 1\] \+ omega\[1, 0\] = 1"):
        wrappers.ResponsibilityWeighting(env, lambda th: np.full((2, 2), 0.9))
    with pytest.raises(ValueError, match="unknown"):
        wrappers.ResponsibilityWeighting(env, "selfish")


# ---- ramp merge ----


def merge_order(theta, split="capability", barrier="braking"):
    """Who passes the merge point first, under the paper's braking barrier unless told."""
    kw = {} if barrier is None else {"barrier": barrier}
    env = filtered("ramp_merge", split=split, **kw)
    env.reset(seed=0, options={"theta": theta})
    base = env.unwrapped
    passed = [None, None]
    while env.agents:
        _, _, _, _, infos = env.step(base.nominal_actions())
        for i in range(2):
            if passed[i] is None and base.world.positions[i, 1] >= 70.0:
                passed[i] = base.metrics.steps
    return passed, base.episode_metrics


@pytest.mark.parametrize("theta,egoist", [([1.0, 4.0], 0), ([4.0, 1.0], 1)])
def test_egoist_merges_first_with_capability_split(theta, egoist):
    passed, m = merge_order(theta)
    assert passed[egoist] < passed[1 - egoist], passed
    assert m["n_infeasible"] == 0 and m["min_distance"] >= 5.0


def test_equal_theta_keeps_the_safety_distance():
    _, m = merge_order([2.0, 2.0])
    assert m["min_distance"] >= 5.0 and m["n_infeasible"] == 0


@pytest.mark.parametrize("theta,egoist", [([1.0, 4.0], 0), ([4.0, 1.0], 1)])
def test_paper_split_makes_the_egoist_yield(theta, egoist):
    passed, _ = merge_order(theta, split="paper")
    assert passed[egoist] > passed[1 - egoist], passed


@pytest.mark.parametrize("theta,egoist", [([1.0, 4.0], 0), ([4.0, 1.0], 1)])
def test_the_ramp_merge_default_barrier_lets_the_egoist_first(theta, egoist):
    """The scenario's default, the stopping-segment barrier (its start lies in that safe set):
    the egoist first, no infeasible step, never below the safety distance."""
    passed, m = merge_order(theta, barrier=None)
    assert passed[egoist] < passed[1 - egoist], passed
    assert m["n_infeasible"] == 0 and m["min_distance"] >= 5.0


# ---- joint control ----


def test_joint_control_env_sums_and_ends_together():
    env = wrappers.JointControlEnv("position_swap")
    obs, info = env.reset(seed=0)
    assert obs.shape == env.observation_space.shape
    total, done = 0.0, False
    while not done:
        obs, r, term, trunc, info = env.step(env.nominal_action())
        total += r
        done = term or trunc
    assert term and not trunc
    assert info["episode_success"] and "episode" not in info
    assert total > 2 * 10.0  # both goal bonuses


def test_joint_control_bad_action():
    env = wrappers.JointControlEnv("circular_swap")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(3,\), expected \(12,\)"):
        env.step(np.zeros(3))
    a = np.zeros(12)
    a[5] = np.nan
    with pytest.raises(ValueError, match=r"agent 'agent_2' \(index 2\) = \[0.0, nan\]"):
        env.step(a)


def test_wrappers_configure_the_env_they_wrap_in_place():
    """docs/api.md: a wrapper turns on a stage of the wrapped env's core, so the env itself is
    filtered after it is wrapped."""
    import numpy as np

    import rsvo_env

    def interventions(env):
        env.reset(seed=0)
        total = 0.0
        for _ in range(200):  # every agent heads for the centre: the filter must act
            x = env.unwrapped.world.positions
            *_, infos = env.step({a: -x[i] for i, a in enumerate(env.agents)})
            total += sum(infos[a]["intervention"] for a in env.agents)
        return total

    env = rsvo_env.parallel_env("circular_swap", num_agents=6, safety_filter=False)
    assert interventions(env) == 0.0  # bare: nothing filters
    wrapped = wrappers.RCBFSafetyFilter(env)
    assert wrapped.unwrapped is env
    assert interventions(env) > 0.0  # the bare handle now steps through the filter
    assert np.isfinite(interventions(wrapped))
