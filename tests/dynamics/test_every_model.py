"""Every scene for every model (``dynamics=``): the scenes take the model and its own
parameters through every adapter, lay out starts in the model's safe set, and the scripted
controller drives every model (R-ORCA on the unicycle's look-ahead points, tracked by the double
integrator's acceleration)."""

import gymnasium
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pettingzoo.test import parallel_api_test

import rsvo_env
from rsvo_env import dynamics
from rsvo_env.dynamics.unicycle import heading_vectors
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.scenarios import make_scenario
from tests.support.checkers import checked

SCENES = ("crowd", "circular_swap", "doorway", "obstacle_field")
MODELS = dynamics.NAMES
IDS = {
    "crowd": "rsvo/Crowd-v0",
    "circular_swap": "rsvo/CircularSwap-v0",
    "doorway": "rsvo/Doorway-v0",
    "obstacle_field": "rsvo/ObstacleField-v0",
}
SMALL = {"crowd": 6, "circular_swap": 6, "doorway": 4, "obstacle_field": 4}


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("scene", SCENES)
def test_every_scene_takes_every_model_through_every_adapter(scene, model):
    n = SMALL[scene]
    env = rsvo_env.parallel_env(scene, dynamics=model, num_agents=n, max_steps=60)
    assert env.unwrapped.sim.scenario.model.name == model
    env.reset(seed=1)
    for _ in range(60):
        _, _, _, _, infos = env.step(env.unwrapped.nominal_actions())
    assert env.unwrapped.episode_metrics["n_collision_steps"] == 0
    assert all(info["feasible"] for info in infos.values())
    joint = gymnasium.make(IDS[scene], dynamics=model, num_agents=n)
    assert joint.unwrapped.base.sim.scenario.model.name == model
    joint.reset(seed=0)
    joint.step(joint.action_space.sample())
    batched = BatchedEnv(scene, num_envs=3, dynamics=model, num_agents=n)
    batched.reset(seed=[0, 1, 2])
    for _ in range(20):
        _, _, _, _, info = batched.step(batched.nominal_actions())
        assert info["feasible"].all() and (info["cost"] == 0).all()


@pytest.mark.parametrize("model", MODELS)
def test_pettingzoos_checker_passes_every_model_in_the_doorway(model):
    checked(
        parallel_api_test,
        rsvo_env.parallel_env("doorway", dynamics=model, num_agents=4),
        num_cycles=30,
    )


def test_the_models_parameters_belong_to_their_models():
    sc = make_scenario("crowd", dynamics="unicycle", lookahead=0.15, w_max=4.0)
    assert (sc.params["lookahead"], sc.params["w_max"]) == (0.15, 4.0)
    assert make_scenario("doorway", dynamics="double_integrator", a_max=3.0).u_max == 3.0
    with pytest.raises(TypeError, match="crowd.a_max is the double_integrator's parameter"):
        make_scenario("crowd", a_max=2.0)
    with pytest.raises(TypeError, match="doorway.lookahead is the unicycle's parameter"):
        make_scenario("doorway", dynamics="double_integrator", lookahead=0.2)
    with pytest.raises(ValueError, match="obstacle_field.dynamics = 'hovercraft'"):
        make_scenario("obstacle_field", dynamics="hovercraft")
    with pytest.raises(ValueError, match=r"circular_swap.lookahead = -0.2 must be a finite"):
        make_scenario("circular_swap", dynamics="unicycle", lookahead=-0.2)
    with pytest.raises(ValueError, match="crowd: lookahead \\* w_max = 2.5 must be below u_max"):
        make_scenario("crowd", dynamics="unicycle", lookahead=0.5, w_max=5.0)
    with pytest.raises(ValueError, match="crowd.a_max = nan"):
        make_scenario("crowd", dynamics="double_integrator", a_max=float("nan"))
    # the paper's ramp merge keeps its model; the unicycle crowd is the crowd of unicycles
    with pytest.raises(TypeError, match="unknown keyword"):
        make_scenario("ramp_merge", dynamics="single_integrator")
    with pytest.raises(TypeError, match="unknown keyword"):
        make_scenario("unicycle_crowd", dynamics="single_integrator")


@pytest.mark.parametrize("seed", range(20))
def test_unicycle_layouts_start_in_the_filters_safe_set(seed):
    """The crowd of unicycles lays starts 4 look-aheads further apart: each look-ahead point
    (facing its goal) is r_i + r_j + 2 l from every other, checked by the scene itself and
    here."""
    for scene in SCENES:
        sc = make_scenario(
            scene,
            dynamics="unicycle",
            num_agents=SMALL[scene] + 10 * (scene == "crowd"),
            lookahead=0.3,
            w_max=3.0,
        )
        rng = np.random.default_rng(seed)
        start, _, goals = sc.initial_state(rng)
        seg = goals - start
        q = start + 0.3 * seg / np.linalg.norm(seg, axis=1, keepdims=True)
        d = np.linalg.norm(q[:, None] - q[None], axis=-1) + np.diag(np.full(len(q), np.inf))
        r = sc.radii + 0.3
        assert (d >= (r[:, None] + r[None]) * (1 - 1e-12)).all(), scene


def test_a_custom_scene_refuses_unicycles_whose_look_ahead_points_overlap():
    # axles 1.3 apart, both facing the other: the look-ahead points are 0.9 apart < 1.4
    kw = {"starts": [[0.0, 0.0], [1.3, 0.0]], "goals": [[5.0, 0.0], [-4.0, 0.0]]}
    with pytest.raises(ValueError, match="look-ahead points of agents 0 and 1 overlap"):
        rsvo_env.parallel_env("custom", dynamics="unicycle", **kw)
    # facing away from each other they start 2.1 apart: accepted
    kw = {"starts": [[0.0, 0.0], [1.3, 0.0]], "goals": [[-5.0, 0.0], [6.0, 0.0]]}
    assert rsvo_env.parallel_env("custom", dynamics="unicycle", **kw).reset(seed=0)


class _State:
    def __init__(self, headings, clock=None):
        n = len(headings)
        self.positions = np.zeros((1, n, 2))
        self.headings = np.asarray(headings, dtype=float)[None]
        self.no_progress = None if clock is None else np.full((1, n), clock)


PARAMS = {"lookahead": 0.2, "w_max": 3.0, "u_max": 2.0, "dt": 0.05}


@settings(max_examples=300)
@given(st.floats(-np.pi, np.pi), st.floats(-np.pi, np.pi), st.floats(0.0, 2.0))
def test_the_unicycles_tracking_inverts_the_look_ahead_map_or_turns_in_place(hd, angle, speed):
    """Ahead (within 90 degrees): (v, w) gives the look-ahead point the velocity c exactly,
    when the inputs are within bounds; behind: it turns in place toward c at |c| / l."""
    model = dynamics.MODELS["unicycle"]
    c = speed * np.array([[[np.cos(angle), np.sin(angle)]]])
    u = model.track(_State([hd]), c, PARAMS, None)[0, 0]
    e = heading_vectors(np.array(hd))
    along = float(e @ c[0, 0])
    across = float(e[0] * c[0, 0, 1] - e[1] * c[0, 0, 0])
    assert 0.0 <= u[0] <= PARAMS["u_max"] and abs(u[1]) <= PARAMS["w_max"]
    if along >= 0.0 and abs(across) / 0.2 <= 3.0:
        back = u[0] * e + 0.2 * u[1] * np.array([-e[1], e[0]])
        assert np.allclose(back, c[0, 0], atol=1e-12 * (1 + speed))
    elif along < 0.0:
        assert u[0] == 0.0
        assert u[1] == pytest.approx(np.sign(across or 1.0) * min(speed / 0.2, 3.0), rel=1e-12)


def test_a_held_unicycle_turns_left_and_right_by_full_turns():
    """No progress for a full turn's time (2 pi / w_max) and facing away from c: it swings at
    w_max, left then right, a full turn each, whichever way c lies."""
    model = dynamics.MODELS["unicycle"]
    turn_steps = 2 * np.pi / 3.0 / 0.05
    c = np.array([[[0.0, -1.0]]])  # the agent faces +y: c straight behind
    w = [
        float(model.track(_State([np.pi / 2], k), c, PARAMS, None)[0, 0, 1])
        for k in (0, int(turn_steps) + 1, int(2 * turn_steps) + 1, int(3 * turn_steps) + 1)
    ]
    assert abs(w[0]) == 3.0 and w[1:] == [3.0, -3.0, 3.0]  # |c| / l = 5, capped
    # c ahead: a held agent keeps tracking it
    ahead = model.track(_State([np.pi / 2], 10_000), np.array([[[0.0, 1.0]]]), PARAMS, None)
    assert np.allclose(ahead[0, 0], [1.0, 0.0])


@pytest.mark.parametrize("seed", range(3))
def test_the_steered_velocity_is_the_look_ahead_points_own(seed):
    """After a step the state's steered velocities are the look-ahead points' displacement
    over dt: R(theta_0) (v, l w), the velocity each held (the look-ahead hold is exact)."""
    env = BatchedEnv("unicycle_crowd", num_envs=2, num_agents=8)
    env.reset(seed=[seed, seed + 10])
    s = env.sim.state
    assert np.array_equal(s.steered_velocities, np.zeros_like(s.positions))
    for _ in range(5):
        hd = s.headings.copy()
        _, _, _, _, info = env.step(env.nominal_actions())
        u = info["u_safe"]
        e = heading_vectors(hd)
        l = env.sim.scenario.params["lookahead"]
        c = u[..., :1] * e + l * u[..., 1:] * np.stack([-e[..., 1], e[..., 0]], -1)
        assert np.allclose(s.steered_velocities, c, atol=1e-12 * 2.0)


@pytest.mark.parametrize("model", MODELS)
def test_the_scripted_controller_of_a_single_integrator_scene_is_unchanged_by_the_hooks(model):
    """Move-to-goal through the model's tracking: the single integrator's is the velocity
    itself, the double integrator's k_v (v_goal - v) clipped to a_max, v_goal's norm capped at
    sqrt(a_max d), the speed from which braking at a_max / 2 stops at the goal (d away)."""
    env = BatchedEnv("crowd", num_envs=2, num_agents=6, dynamics=model, nominal="move_to_goal")
    env.reset(seed=[0, 1])
    for _ in range(30):
        env.step(env.nominal_actions())
    sim = env.sim
    sc, s = sim.scenario, sim.state
    v_goal = sc.move_to_goal(s, True, sc.speed)
    got = sim.nominal_controls()
    if model == "single_integrator":
        assert np.array_equal(got, v_goal)
    elif model == "double_integrator":
        a_max, k_v = sc.params["a_max"], sc.params["k_v"]
        cap = np.sqrt(a_max * np.linalg.norm(s.goals - s.positions, axis=-1, keepdims=True))
        speed = np.linalg.norm(v_goal, axis=-1, keepdims=True)
        assert (speed > cap).any() and (speed < cap).any()  # the cap and the free approach
        want = v_goal * np.minimum(1.0, cap / speed)
        a = k_v * (want - s.velocities)
        n = np.linalg.norm(a, axis=-1, keepdims=True)
        assert np.allclose(got, a * np.minimum(1.0, a_max / n), atol=1e-12 * a_max)
    else:
        assert got.shape == (2, 6, 2) and (got[..., 0] >= 0).all()


def test_unicycle_crowds_finish_with_r_orca_on_their_look_ahead_points():
    """The crowd of 100 unicycles (dt 0.05, gamma 20, theta 1..10): every agent arrives in
    every seed, with no contact and no infeasible step (move-to-goal left 45 % short)."""
    env = BatchedEnv(
        "unicycle_crowd",
        num_envs=5,
        num_agents=100,
        dt=0.05,
        gamma=20.0,
        theta_range=(1.0, 10.0),
        max_steps=4000,
    )
    env.reset(seed=list(range(5)))
    reached = np.zeros((5, 100), dtype=bool)
    for _ in range(3000):
        _, _, _, _, info = env.step(env.nominal_actions())
        assert info["feasible"].all() and (info["cost"] == 0).all()
        reached |= info["at_goal"]
        if reached.all():
            break
    assert reached.all(), f"agents short by seed: {(~reached).sum(1).tolist()}"
