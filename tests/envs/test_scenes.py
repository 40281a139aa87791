"""Scenes with bodies of their own size and obstacles in the simulator: the user's own scene from
arrays (validated), the doorway and the obstacle field; PettingZoo's seed test; safety of whole
episodes behind the filter, collisions counted on the bodies' true sizes without it."""

from pathlib import Path

import numpy as np
import pytest
from pettingzoo.test import parallel_seed_test

import rsvo_env
from rsvo_env.scenarios import make_scenario
from tests.support.checkout import run_python

ROOT = Path(__file__).resolve().parents[2]


def custom(**kw):
    base = dict(
        starts=[(-6.0, 0.0), (6.0, 0.3), (0.0, -6.0), (0.2, 6.0)],
        goals=[(6.0, 0.0), (-6.0, 0.0), (0.0, 6.0), (0.0, -6.0)],
        radii=[0.3, 0.9, 0.5, 0.7],
        circles=[(0.0, 0.0, 1.0)],
        walls=[((-3.0, 3.0), (-1.0, 5.0))],
        thickness=0.3,
    )
    base.update(kw)
    return base


@pytest.mark.parametrize(
    "name,kwargs",
    [("doorway", {"num_agents": 4}), ("obstacle_field", {"num_agents": 4}), ("custom", custom())],
)
def test_pettingzoo_seed_test(name, kwargs):
    parallel_seed_test(lambda: rsvo_env.parallel_env(name, **kwargs))


def test_obstacles_are_drawn_from_the_episode_seed():
    env = rsvo_env.parallel_env("obstacle_field")
    env.reset(seed=3)
    first = env.unwrapped.sim.state.obstacles.copy()
    env.reset(seed=3)
    assert np.array_equal(first, env.unwrapped.sim.state.obstacles)
    env.reset(seed=4)
    assert not np.array_equal(first, env.unwrapped.sim.state.obstacles)
    assert first.shape == (1, 8, 5)


@pytest.mark.parametrize(
    "name,kwargs",
    [("custom", custom()), ("doorway", {}), ("obstacle_field", {}),
     ("obstacle_field", {"num_agents": 16, "side": 24.0, "num_circles": 12})],
)  # fmt: skip
def test_scripted_episodes_behind_the_filter_never_touch(name, kwargs):
    env = rsvo_env.parallel_env(name, **kwargs)
    for seed in range(3):
        env.reset(seed=seed, options={"theta": np.linspace(0.5, 8.0, env.unwrapped.sim.n)})
        sim = env.unwrapped.sim
        while env.agents:
            _, _, _, _, info = env.step(env.unwrapped.nominal_actions())
            assert all(info[a]["cost"] == 0.0 and info[a]["feasible"] for a in info)
            assert sim.state.contact.min() >= 1.0 - 1e-9
        metrics = env.unwrapped.episode_metrics
        assert metrics["n_collision_steps"] == 0 and metrics["n_infeasible"] == 0


def test_without_the_filter_a_body_in_a_wall_is_a_collision():
    """A straight run into the circle (bare env): cost 1 and a collision step once the body
    (radius 0.3) overlaps it, although its centre is 1.3 m from the circle's."""
    sc = custom(
        starts=[(-4.0, 0.0), (6.0, 6.0)],
        goals=[(4.0, 0.0), (6.0, -6.0)],
        radii=[0.3, 0.3],
        walls=None,
    )
    env = rsvo_env.parallel_env("custom", safety_filter=False, **sc)
    env.reset(seed=0)
    hit = False
    while env.agents and not hit:
        _, _, _, _, info = env.step(env.unwrapped.nominal_actions())
        x = env.unwrapped.sim.state.positions[0, 0]
        inside = np.linalg.norm(x) < 1.3 * (1 - 1e-6)
        assert (info["agent_0"]["cost"] == 1.0) == inside
        hit = inside
    assert hit and env.unwrapped.sim.metrics.collision_steps[0] >= 1


@pytest.mark.parametrize(
    "kw,match",
    [
        ({"starts": [(0.0, 0.0), (0.5, 0.0), (9.0, 9.0), (9.0, -9.0)]},
         r"starting positions of agents (0 and 1|1 and 0) overlap"),
        ({"starts": [(0.5, 0.0), (6.0, 0.3), (0.0, -6.0), (0.2, 6.0)]},
         r"the start of agent 0, \[0.5, 0.0\], is inside obstacle 0"),
        ({"goals": [(6.0, 0.0), (-6.0, 0.0), (0.0, 6.0), (-2.0, 4.0)]},
         r"the goal of agent 3, \[-2.0, 4.0\], is inside obstacle 1"),
        ({"radii": [0.3, -0.9, 0.5, 0.7]}, r"custom.radii\[1\] = -0.9 .*agent 1"),
        ({"radii": [0.3, 0.9]}, r"custom.radii has shape \(2,\), expected \(4,\)"),
        ({"goals": [(6.0, 0.0)]}, r"custom.goals has shape \(1, 2\), expected \(4, 2\)"),
        ({"starts": [(0.0, np.nan), (6.0, 0.3), (0.0, -6.0), (0.2, 6.0)]},
         r"custom.starts\[0\] = \[0.0, nan\] is not finite \(agent 0\)"),
        ({"circles": [(0.0, 0.0, 0.0)]}, r"circles\[0\] has radius 0.0"),
        ({"starts": None}, r"give starts and goals"),
    ],
)  # fmt: skip
def test_a_bad_scene_is_refused_naming_the_agent(kw, match):
    with pytest.raises(ValueError, match=match):
        make_scenario("custom", **custom(**kw))


def test_bodies_and_obstacles_are_drawn_true_size():
    env = rsvo_env.parallel_env("custom", **custom(), render_mode="rgb_array", render_size=300)
    env.reset(seed=0)
    frame = env.render()
    r = env.unwrapped.renderer
    centre = r.to_screen(np.zeros(2)).astype(int)
    assert tuple(frame[centre[1], centre[0]]) == (120, 120, 120)  # inside the circle: grey
    edge = r.to_screen(np.array([1.2, 0.0])).astype(int)
    assert tuple(frame[edge[1], edge[0]]) != (120, 120, 120)  # beyond its radius: not


def test_filters_that_cannot_take_the_scene_are_refused():
    from rsvo_env.filter.safety import FilterConfig, SafetyFilter

    env = rsvo_env.parallel_env("doorway")
    with pytest.raises(ValueError, match="filter dynamics 'double_integrator'"):
        env.unwrapped.sim.add_filter(SafetyFilter(FilterConfig(dynamics="double_integrator")))


def test_observation_sees_the_nearest_obstacle_surfaces_and_true_gaps():
    env = rsvo_env.parallel_env("custom", **custom(), num_obs_neighbors=3)
    obs, _ = env.reset(seed=0)
    sim = env.unwrapped.sim
    k = 3
    base = 5 + 10 * k
    assert env.observation_space("agent_0").shape == (base + 2 * 4,)  # two obstacles, 4 each
    o = obs["agent_1"]  # at (6, 0.3), radius 0.9: the circle (0, 0, 1) is nearest
    x = sim.state.positions[0, 1]
    point = o[base : base + 2]
    expect = -x / np.linalg.norm(x) * (np.linalg.norm(x) - 1.0)
    np.testing.assert_allclose(point, expect, rtol=1e-6)
    assert o[base + 2] == pytest.approx(np.linalg.norm(x) - 1.0 - 0.9, rel=1e-6)
    assert o[base + 3] == 1.0
    # each neighbour's gap is its centre distance less both radii
    nb = sim.state.neighbors[0, 1]
    d = np.linalg.norm(sim.state.positions[0, nb] - x, axis=1)
    gaps = o[5 + 8 : 5 + 10 * k : 10]
    np.testing.assert_allclose(gaps, d - 0.9 - sim.radii[nb], rtol=1e-6)


def test_plain_scenes_keep_their_observation_layout():
    env = rsvo_env.parallel_env("crowd", num_agents=5, num_obs_neighbors=3)
    assert env.observation_space("agent_0").shape == (5 + 10 * 3,)


def test_each_agent_keeps_its_own_speed_limit():
    limits = [0.5, 3.0, 1.0, 2.0]
    env = rsvo_env.parallel_env("custom", **custom(u_max=limits))
    env.reset(seed=0)
    lim = np.array(limits)
    fastest = np.zeros(4)
    while env.agents:
        actions = {a: np.array([1.0, 0.3], np.float32) for a in env.agents}  # full throttle
        _, _, _, _, info = env.step(actions)
        u = np.stack([info[a]["u_safe"] for a in env.possible_agents])
        nominal = np.stack([info[a]["u_nominal"] for a in env.possible_agents])
        assert (np.linalg.norm(nominal, axis=1) <= lim * (1 + 1e-12)).all()
        assert (np.abs(u) <= lim[:, None] * (1 + 1e-12)).all()
        assert all(info[a]["cost"] == 0 for a in info)
        fastest = np.maximum(fastest, np.linalg.norm(u, axis=1))
    # each ran at its own limit, not the others'
    np.testing.assert_allclose(fastest, lim, rtol=1e-6)
    scripted = rsvo_env.parallel_env("custom", **custom(u_max=limits))
    scripted.reset(seed=0)
    speeds = np.linalg.norm(scripted.unwrapped.sim.nominal_controls()[0], axis=1)
    assert (speeds <= lim * (1 + 1e-12)).all() and np.isclose(speeds, lim).any()


def test_a_bad_speed_limit_per_agent_names_the_agent():
    with pytest.raises(ValueError, match=r"custom.u_max\[2\] = -1.0 .*agent 2"):
        make_scenario("custom", **custom(u_max=[1.0, 1.0, -1.0, 1.0]))
    with pytest.raises(ValueError, match=r"custom.u_max has shape \(3,\), expected \(4,\)"):
        make_scenario("custom", **custom(u_max=[1.0, 1.0, 1.0]))


@pytest.mark.parametrize("gap", [3.0, 4.0, 6.0])
def test_the_doorways_script_never_heads_into_the_wall(gap):
    """Before crossing, every agent on its own side heads for a point whose straight line meets
    the wall's face, if at all, inside the band where a body passes (|y| <= gap / 2 - R / 2):
    a grid of positions on both sides, above, within and below the gap (the band was once
    taken about the lane, and agents above it headed into the wall)."""
    # no speed limit to speak of: move-to-goal's velocity is k (target - x), the target exact
    sc = make_scenario("doorway", num_agents=2, gap=gap, nominal="move_to_goal", u_max=1e6)
    p = sc.params
    face = 0.5 * p["thickness"] + 0.5 * p["safety_radius"]
    band = 0.5 * gap - 0.5 * p["safety_radius"]
    xs, ys = np.meshgrid(np.linspace(face + 0.05, 8.0, 25), np.linspace(-6.0, 6.0, 49))
    mine = np.stack([xs.ravel(), ys.ravel()], -1)
    for side in (-1.0, 1.0):  # agents right of the wall head left, and the mirror
        x = mine * [-side, 1.0]
        goals = np.broadcast_to([side * 10.0, 0.0], x.shape)
        state = type(
            "S",
            (),
            {"positions": x[None], "goals": goals[None], "rh_active": np.zeros((1, len(x)), bool)},
        )()
        target = x + sc.nominal(state, right_hand=False)[0] / p["k"]
        # the segment x -> target crosses the own face (x = -side face) where it passes it
        crosses = np.sign(target[:, 0] + side * face) != np.sign(x[:, 0] + side * face)
        s_face = (-side * face - x[:, 0]) / (target[:, 0] - x[:, 0])
        y_face = x[:, 1] + s_face * (target[:, 1] - x[:, 1])
        bad = crosses & (np.abs(y_face) > band + 1e-9)
        assert not bad.any(), x[bad]


def test_a_sparse_crowd_is_laid_out_in_memory_by_agents_not_by_area():
    """Resetting 100 agents with ``side_factor=700`` (a square 7,000 radii wide) costs the
    process no more memory than a default crowd does, in a fresh interpreter after one warm-up
    reset (the layout's grid was (side / spacing)^2 cells: 1.08 GB); ``spacing_factor=1e-4``
    lays out, then the overlapping starts are refused by name (it was a MemoryError)."""
    code = (
        "import resource, rsvo_env\n"
        "rsvo_env.parallel_env('crowd', num_agents=100).reset(seed=0)\n"
        "before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss\n"
        "rsvo_env.parallel_env('crowd', num_agents=100, side_factor=700.0).reset(seed=0)\n"
        "print((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) / 1024)\n"
    )
    out = run_python("-c", code)
    assert out.returncode == 0, out.stderr[-2000:]
    assert float(out.stdout) < 32.0  # MB
    with pytest.raises(ValueError, match="overlap"):
        rsvo_env.parallel_env("crowd", num_agents=100, spacing_factor=1e-4).reset(seed=0)
