"""Determinism, the collision signal, metrics and bad input of RSVOParallelEnv."""

import ast
import random
from pathlib import Path

import numpy as np
import pytest

import rsvo_env
from rsvo_env import wrappers

ROOT = Path(__file__).resolve().parents[2]


def assert_same(a, b, path="root"):
    """Bit-identical nested structures of dicts, lists, arrays and scalars."""
    assert type(a) is type(b), path
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        for k in a:
            assert_same(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_same(x, y, f"{path}[{i}]")
    elif isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape, path
        assert np.array_equal(a, b, equal_nan=True), path
    elif isinstance(a, float) and np.isnan(a):
        assert np.isnan(b), path
    else:
        assert a == b, path


def run_episode(make, seed, action_seed, steps=400):
    env = make()
    out = [env.reset(seed=seed)]
    rng = np.random.default_rng(action_seed)
    for _ in range(steps):
        if not env.agents:
            break
        actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        out.append(env.step(actions))
    return out


@pytest.mark.parametrize("name", ["position_swap", "circular_swap", "ramp_merge", "crowd"])
@pytest.mark.parametrize("filtered", [False, True])
def test_full_episode_determinism(name, filtered):
    def make():
        env = rsvo_env.parallel_env(name, max_steps=400)
        return wrappers.RCBFSafetyFilter(env) if filtered else env

    a = run_episode(make, seed=7, action_seed=3)
    b = run_episode(make, seed=7, action_seed=3)
    assert len(a) > 1
    assert_same(a, b)


def test_nominal_episode_is_deterministic_to_the_end():
    def episode():
        env = rsvo_env.parallel_env("crowd", num_agents=8)
        env.reset(seed=11)
        trace = []
        while env.agents:
            trace.append(env.step(env.unwrapped.nominal_actions()))
        return trace

    a, b = episode(), episode()
    assert_same(a, b)
    last = a[-1][4]["agent_0"]
    assert "episode" not in last and last["episode_steps"] == len(a)


def test_per_agent_episode_values_are_the_batched_flat_values():
    """The single env's per-agent ``episode_*`` infos hold the same values and types as the
    core's (E,) ``flat()`` arrays, at every step of an episode with collisions and arrivals."""
    from rsvo_env.sim.metrics import FLAT_FIELDS

    env = rsvo_env.parallel_env("position_swap", theta=(1.0, 1.0), safety_filter=False)
    env.reset(seed=0)
    while env.agents:
        infos = env.step(env.unwrapped.nominal_actions())[4]
        flat = env.unwrapped.sim.metrics.flat()
        for name, dtype in FLAT_FIELDS:
            got = infos["agent_1"][f"episode_{name}"]
            want = flat[f"episode_{name}"][0]
            assert got == want and type(got) is type(dtype(want).item()), name
    assert infos["agent_0"]["episode_collision_steps"] > 0
    assert infos["agent_0"]["episode_success"] is True


def test_seeds_change_crowd_layouts():
    env = rsvo_env.parallel_env("crowd", num_agents=10)
    env.reset(seed=1)
    x1 = env.unwrapped.world.positions.copy()
    env.reset(seed=2)
    x2 = env.unwrapped.world.positions.copy()
    env.reset(seed=1)
    x3 = env.unwrapped.world.positions.copy()
    assert not np.allclose(x1, x2)
    np.testing.assert_array_equal(x1, x3)
    # an unseeded reset continues the env's own generator: a new layout
    env.reset()
    assert not np.allclose(env.unwrapped.world.positions, x1)


def test_no_global_random_state_is_touched():
    np.random.seed(123)  # noqa: NPY002 - the global state is what this test watches
    random.seed(123)
    np_state = np.random.get_state()[1].copy()  # noqa: NPY002
    py_state = random.getstate()
    env = rsvo_env.parallel_env("crowd", num_agents=6)
    env.reset(seed=0)
    env.reset()
    for _ in range(20):
        env.step(env.unwrapped.nominal_actions())
    assert np.array_equal(np.random.get_state()[1], np_state)  # noqa: NPY002
    assert random.getstate() == py_state


def test_package_source_never_uses_global_rng():
    allowed = {"default_rng", "Generator", "SeedSequence", "PCG64"}
    offenders = []
    for folder in ("rsvo_env", "wrappers"):
        for path in (ROOT / folder).rglob("*.py"):
            tree = ast.parse(path.read_text())
            for node in ast.walk(tree):
                if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Attribute):
                    if node.value.attr == "random" and node.attr not in allowed:
                        offenders.append(f"{path}:{node.lineno} np.random.{node.attr}")
                if isinstance(node, (ast.Import, ast.ImportFrom)):
                    names = (
                        [a.name for a in node.names]
                        if isinstance(node, ast.Import)
                        else [node.module or ""]
                    )
                    if "random" in names:
                        offenders.append(f"{path}:{node.lineno} import random")
    assert not offenders, offenders


def test_circular_swap_without_filter_collides():
    # the paper's move-to-goal (R-ORCA, the default, avoids by itself)
    env = rsvo_env.parallel_env("circular_swap", nominal="move_to_goal", safety_filter=False)
    env.reset(seed=0)
    costs, dists = [], []
    while env.agents:
        _, _, _, _, infos = env.step(env.unwrapped.nominal_actions())
        costs += [i["cost"] for i in infos.values()]
        dists += [i["min_distance"] for i in infos.values()]
    R = env.unwrapped.world.safety_radius
    assert max(costs) > 0
    assert min(dists) < R
    assert env.unwrapped.episode_metrics["n_collision_steps"] > 0
    assert infos["agent_0"]["episode_collision_steps"] > 0


def test_circular_swap_with_filter_does_not():
    env = rsvo_env.parallel_env("circular_swap")
    env.reset(seed=0)
    while env.agents:
        _, _, _, _, infos = env.step(env.unwrapped.nominal_actions())
        assert all(i["cost"] == 0.0 for i in infos.values())
    m = env.unwrapped.episode_metrics
    assert (
        infos["agent_0"]["episode_success"]
        and infos["agent_0"]["episode_completed"] == m["completed"]
    )
    assert m["success"] and m["min_distance"] >= 1.0 - 1e-9
    assert m["deadlock_onset"] < m["deadlock_resolved"] < m["completed"]
    assert m["path_length"].shape == (6,) and np.all(m["path_length"] > 9.9)


def test_rewards_progress_and_goal_bonus():
    env = rsvo_env.parallel_env(
        "position_swap",
        deadlock_resolution="none",
        start=((-4.0, -4.0), (4.0, -4.0)),
        safety_filter=False,
    )
    env.reset(seed=0)
    total = {a: 0.0 for a in env.agents}
    while env.agents:
        _, rewards, *_ = env.step(env.unwrapped.nominal_actions())
        for a, r in rewards.items():
            total[a] += r
    # straight-line distance 8, plus the goal bonus, minus the time cost
    steps = env.unwrapped.metrics.steps
    for a in total:
        assert total[a] == pytest.approx(8.0 + 10.0 - 0.01 * steps, abs=0.06)


# ---- bad input ----


def test_unknown_scenario_kwarg_is_named():
    with pytest.raises(TypeError, match=r"\['bogus', 'speed'\]"):
        rsvo_env.parallel_env("crowd", bogus=1, speed=2)
    with pytest.raises(ValueError, match="unknown scenario"):
        rsvo_env.parallel_env("highway")


@pytest.mark.parametrize(
    "kwargs,pattern",
    [
        ({"safety_radius": 0.0}, r"safety_radius = 0.0"),
        ({"safety_radius": -1.0}, r"safety_radius = -1.0"),
        ({"u_max": np.nan}, r"u_max = nan"),
        ({"max_steps": 0}, r"max_steps = 0"),
        ({"theta": [1.0, -2.0]}, r"theta\[1\] = -2.0.*agent 1"),
        ({"deadlock_resolution": "left"}, r"deadlock_resolution = 'left'"),
    ],
)
def test_bad_scenario_parameters(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        rsvo_env.parallel_env("position_swap", **kwargs)


def test_overlapping_start_names_the_pair():
    env = rsvo_env.parallel_env("position_swap", start=((0.0, 0.0), (0.5, 0.0)))
    with pytest.raises(ValueError, match=r"agents 0 and 1 overlap: distance 0.5"):
        env.reset(seed=0)


def test_bad_theta_option():
    env = rsvo_env.parallel_env("circular_swap")
    with pytest.raises(ValueError, match=r"theta\[3\] = nan.*agent 3"):
        env.reset(seed=0, options={"theta": [1, 1, 1, np.nan, 1, 1]})
    with pytest.raises(ValueError, match="expected 6"):
        env.reset(seed=0, options={"theta": [1, 1]})


@pytest.mark.parametrize("filtered", [False, True])
@pytest.mark.parametrize(
    "mutate,pattern",
    [
        (lambda a: a.update(agent_1=np.array([np.nan, 0.0])), r"agent 'agent_1' = \[nan, 0.0\]"),
        (lambda a: a.update(agent_0=np.array([np.inf, 0.0])), r"agent 'agent_0' = \[inf, 0.0\]"),
        (lambda a: a.update(agent_2=np.zeros(3)), r"agent 'agent_2' has shape \(3,\)"),
        (lambda a: a.pop("agent_4"), r"no action given for agent 'agent_4'"),
        (lambda a: a.update(agent_9=np.zeros(2)), r"unknown agent name 'agent_9'"),
        (
            lambda a: a.update(agent_0="fast"),
            r"action of agent 'agent_0' must be real numbers.*'fast'",
        ),
    ],
)
def test_bad_actions_leave_state_unchanged(filtered, mutate, pattern):
    def make():
        env = rsvo_env.parallel_env("circular_swap")
        return wrappers.RCBFSafetyFilter(env) if filtered else env

    env, clean = make(), make()
    env.reset(seed=0)
    clean.reset(seed=0)
    for _ in range(50):
        env.step(env.unwrapped.nominal_actions())
        clean.step(clean.unwrapped.nominal_actions())
    bad = dict(env.unwrapped.nominal_actions())
    mutate(bad)
    with pytest.raises(ValueError, match=pattern):
        env.step(bad)
    # the env behaves as if the bad call never happened
    for _ in range(20):
        a = env.step(env.unwrapped.nominal_actions())
        b = clean.step(clean.unwrapped.nominal_actions())
        assert_same(a, b)


def test_step_after_end_and_before_reset():
    env = rsvo_env.parallel_env("position_swap", max_steps=2)
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})
    env.reset(seed=0)
    env.step(env.unwrapped.nominal_actions())
    env.step(env.unwrapped.nominal_actions())
    assert env.agents == []
    with pytest.raises(RuntimeError, match="episode is over"):
        env.step({})


def test_refused_reset_leaves_the_generator_as_it_was():
    env, clean = (
        rsvo_env.parallel_env("crowd", num_agents=6),
        rsvo_env.parallel_env("crowd", num_agents=6),
    )
    env.reset(seed=4)
    clean.reset(seed=4)
    with pytest.raises(ValueError, match=r"theta\[0\] = -1.0"):
        env.reset(options={"theta": [-1, 1, 1, 1, 1, 1]})
    with pytest.raises(ValueError, match="unknown"):
        env.reset(options={"weighting": "selfish"})
    env.reset()
    clean.reset()
    np.testing.assert_array_equal(env.unwrapped.world.positions, clean.unwrapped.world.positions)
