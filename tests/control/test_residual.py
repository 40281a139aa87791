"""Residual actions: the scripted command plus a learned correction, gated near the goal and
held to the speed limit; the same in the batched env as behind the ParallelEnv wrapper."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env import wrappers
from rsvo_env.control.residual import Residual
from rsvo_env.envs.vector import BatchedEnv


@pytest.mark.parametrize("nominal", ["move_to_goal", "rorca"])
def test_a_zero_residual_is_the_scripted_controller(nominal):
    """At every step the control requested is the scripted controller's command for that state,
    exactly; for move-to-goal also the whole episode against the scripted actions, to the
    float32 precision of ``nominal_actions()`` (R-ORCA feeds the velocity back, so that
    rounding grows along an episode: its comparison is the exact one)."""

    def make():
        return rsvo_env.parallel_env("circular_swap", nominal=nominal)

    scripted, residual = make(), wrappers.ResidualAction(make())
    theta = {"theta": [2, 1, 2, 1, 2, 1]}
    scripted.reset(seed=0, options=theta)
    residual.reset(seed=0, options=theta)
    agents = residual.possible_agents
    zero = {a: np.zeros(2, dtype=np.float32) for a in agents}
    while residual.agents:
        expect = residual.unwrapped.nominal_controls()
        _, _, _, _, infos = residual.step(zero)
        got = np.stack([infos[a]["u_nominal"] for a in agents])
        np.testing.assert_allclose(got, expect, rtol=0, atol=1e-12)
        if nominal == "move_to_goal":
            scripted.step(scripted.unwrapped.nominal_actions())
            np.testing.assert_allclose(
                residual.unwrapped.world.positions, scripted.unwrapped.world.positions, atol=1e-5
            )
    if nominal == "move_to_goal":
        assert (
            residual.unwrapped.episode_metrics["completed"]
            == (scripted.unwrapped.episode_metrics["completed"])
        )


def test_the_residual_is_gated_near_the_goal_and_held_to_the_speed_limit():
    env = wrappers.ResidualAction(rsvo_env.parallel_env("position_swap"), gate_radius=0.5)
    env.reset(seed=0)
    base = env.unwrapped
    rng = np.random.default_rng(0)
    gated = 0
    while env.agents:
        near = np.linalg.norm(base.world.positions - base.world.goals, axis=1) < 0.5
        scripted = base.sim.scenario.nominal(base.sim.state)[0]
        actions = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in env.agents}
        _, _, _, _, infos = env.step(actions)
        for i, a in enumerate(base.possible_agents):
            u = infos[a]["u_nominal"]
            assert np.linalg.norm(u) <= 2.0 * (1 + 1e-12)  # u_max of position_swap
            if near[i]:
                gated += 1
                np.testing.assert_allclose(u, scripted[i], atol=1e-12)
    assert gated > 0


@pytest.mark.parametrize(
    "name, yield_radius, interaction_radius",
    [
        ("circular_swap", None, None), ("ramp_merge", None, None), ("crowd", 1.25, None),
        ("crowd", 1.25, 2.0),
    ],
)  # fmt: skip
def test_batched_residuals_equal_the_wrapper(name, yield_radius, interaction_radius):
    E = 2
    radii = {"yield_radius": yield_radius, "interaction_radius": interaction_radius}
    # the paper's controller as the base, as the training configs run it (parked agents then
    # stand still and the yield rule has something to do)
    kw = {"max_steps": 60, "nominal": "move_to_goal"}
    venv = BatchedEnv(name, num_envs=E, action="residual", gate_radius=0.5, **kw, **radii)
    singles = [
        wrappers.ResidualAction(rsvo_env.parallel_env(name, **kw), **radii) for _ in range(E)
    ]
    obs, _ = venv.reset(seed=4)
    for e, env in enumerate(singles):
        env.reset(seed=4 + e)
    rng = np.random.default_rng(1)
    agents = singles[0].possible_agents
    yielded = alone = 0
    for _ in range(100):
        # small residuals: agents reach their goals, and (crowd) parked ones get to yield
        actions = rng.uniform(-0.3, 0.3, (E, len(agents), 2)).astype(np.float32)
        s = venv.sim.state
        acting = venv.sim.residual.open(s.positions, s.goals)
        en_route = np.linalg.norm(s.positions - s.goals, axis=-1) >= 0.5
        yielded += np.sum(acting & ~en_route)
        alone += np.sum(en_route & ~acting)
        obs, reward, term, trunc, _ = venv.step(actions)
        for e, env in enumerate(singles):
            o, r, te, tr, _ = env.step({a: actions[e, i] for i, a in enumerate(agents)})
            if te[agents[0]] or tr[agents[0]]:
                o, _ = env.reset()
            assert np.array_equal(obs[e], np.stack([o[a] for a in agents]))
            assert np.array_equal(reward[e], [r[a] for a in agents])
    assert (yielded > 0) == (yield_radius is not None)
    assert (alone > 0) == (interaction_radius is not None)


def test_bad_residual_settings_are_refused():
    with pytest.raises(ValueError, match="action = 'delta'"):
        BatchedEnv("crowd", num_envs=2, action="delta")
    with pytest.raises(ValueError, match="gate_radius = -1"):
        wrappers.ResidualAction(rsvo_env.parallel_env("crowd"), gate_radius=-1)
    with pytest.raises(ValueError, match="gate_radius"):
        BatchedEnv("crowd", num_envs=2, action="residual", gate_radius=float("nan"))


@pytest.mark.parametrize("scale, expected", [(1.0, 0.0), (2.0, -1.0)])
def test_the_residual_scale_decides_whether_a_full_speed_command_can_reverse(scale, expected):
    """A residual straight against a full-speed scripted command: at scale 1 it cancels it, at
    scale 2 it reverses it (to the speed limit)."""
    venv = BatchedEnv(
        "position_swap",
        action="residual",
        residual_scale=scale,
        safety_filter=False,
        deadlock_resolution="none",
    )
    venv.reset(seed=0)
    x0 = venv.sim.state.positions.copy()
    toward = venv.sim.state.goals - x0
    toward /= np.linalg.norm(toward, axis=-1, keepdims=True)
    venv.step(-toward)
    moved = venv.sim.state.positions - x0
    u_max, dt = venv.scenario.u_max, venv.scenario.params["dt"]
    np.testing.assert_allclose(moved, expected * u_max * dt * toward, atol=1e-12)


@pytest.mark.parametrize("scale", [0.0, -1.0, float("nan"), "2"])
def test_a_bad_residual_scale_is_refused(scale):
    with pytest.raises(ValueError, match="residual scale"):
        BatchedEnv("crowd", num_agents=3, action="residual", residual_scale=scale)


def dense_open(positions, goals, gate, yield_radius, interaction_radius=None):
    """Reference: en route (and, with ``interaction_radius``, closer than it to another agent
    of the same env), or parked and closer than ``yield_radius`` to another agent of the same
    env that is en route (every pair tested)."""
    en_route = np.linalg.norm(positions - goals, axis=-1) >= gate
    d = np.linalg.norm(positions[..., :, None, :] - positions[..., None, :, :], axis=-1)
    n = d.shape[-1]
    d[..., np.arange(n), np.arange(n)] = np.inf
    acting = en_route
    if interaction_radius is not None:
        acting = en_route & (d < interaction_radius).any(-1)
    if yield_radius is None:
        return acting
    return acting | (~en_route & ((d < yield_radius) & en_route[..., None, :]).any(-1))


def layout(n: int, scale: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """4 envs of n agents in the same square (so that pairs across envs would be found), a third
    of them parked on their goals."""
    rng = np.random.default_rng(seed)
    side = 2.5 * np.sqrt(n) * scale
    positions = rng.uniform(0, side, (4, n, 2))
    goals = np.where(rng.random((4, n, 1)) < 0.33, positions, rng.uniform(0, side, (4, n, 2)))
    return positions, goals


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("n", [2, 12, 90])
@pytest.mark.parametrize("yield_radius", [None, 1.25, 3.0])
def test_only_agents_with_someone_near_act_with_an_interaction_radius(n, scale, yield_radius):
    """Against every pair, envs side by side, any units: an agent en route acts only with
    another agent of its env within the interaction radius (yielding unchanged)."""
    positions, goals = layout(n, scale, 7 * n)
    y = None if yield_radius is None else yield_radius * scale
    got = Residual(0.5 * scale, yield_radius=y, interaction_radius=2.0 * scale).open(
        positions, goals
    )
    want = dense_open(positions, goals, 0.5 * scale, y, 2.0 * scale)
    assert np.array_equal(got, want)
    en_route = np.linalg.norm(positions - goals, axis=-1) >= 0.5 * scale
    assert (en_route & ~want).any()  # someone en route and alone is left to the script
    assert want.any()


def test_an_agent_alone_follows_the_script_with_an_interaction_radius():
    """Two agents 10 m apart, each residual cancelling its scripted command: without an
    interaction radius they stay; with one of 2 m, nobody is near, so the script moves them."""
    kw = dict(start=((0.0, 0.0), (10.0, 0.0)), safety_filter=False)
    for radius, moves in ((None, False), (2.0, True)):
        venv = BatchedEnv("position_swap", action="residual", interaction_radius=radius, **kw)
        venv.reset(seed=0)
        before = venv.sim.state.positions.copy()
        venv.step(-venv.nominal_actions())
        moved = np.linalg.norm(venv.sim.state.positions - before, axis=-1)
        assert (moved > 0.01).all() == moves and ((moved < 1e-12).all() != moves)


@pytest.mark.parametrize("scale", [1e-3, 1.0, 1e3])
@pytest.mark.parametrize("n", [2, 12, 90])
def test_yielding_opens_exactly_the_gates_next_to_an_agent_en_route(n, scale):
    """Against every pair, in envs side by side (pairs never cross envs), in any units."""
    rng = np.random.default_rng(n)
    E = 4
    side = 2.5 * np.sqrt(n) * scale
    positions = rng.uniform(0, side, (E, n, 2))
    # a third of the agents parked on their goals; the others anywhere
    goals = np.where(rng.random((E, n, 1)) < 0.33, positions, rng.uniform(0, side, (E, n, 2)))
    # envs on top of one another: a neighbour across envs must not count
    residual = Residual(0.5 * scale, yield_radius=1.25 * scale)
    got = residual.open(positions, goals)
    want = dense_open(positions, goals, 0.5 * scale, 1.25 * scale)
    assert np.array_equal(got, want)
    assert (want & ~(np.linalg.norm(positions - goals, axis=-1) >= 0.5 * scale)).any()
    # without yielding: the plain gate
    plain = Residual(0.5 * scale).open(positions, goals)
    assert np.array_equal(plain, np.linalg.norm(positions - goals, axis=-1) >= 0.5 * scale)


@pytest.mark.parametrize("yield_radius, moves", [(None, False), (1.25, True)])
def test_a_parked_agent_steps_aside_only_when_it_may_yield(yield_radius, moves):
    """Agent 0 parked on its goal, agent 1 pressed against it on its way: a sideways residual
    moves agent 0 only with yielding on."""
    venv = BatchedEnv(
        "position_swap",
        action="residual",
        gate_radius=0.5,
        yield_radius=yield_radius,
        start=((0.0, 0.0), (1.0, 0.0)),
        deadlock_resolution="none",
    )
    venv.reset(seed=0)
    venv.sim.state.goals[0] = [[0.0, 0.0], [5.0, 0.0]]
    venv.step(np.array([[[0.0, 1.0], [0.0, 0.0]]]))
    moved = np.linalg.norm(venv.sim.state.positions[0, 0])
    assert (moved > 0.01) == moves


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), "1", True, 1j])
@pytest.mark.parametrize("name", ["yield_radius", "interaction_radius", "stall_gate"])
def test_a_bad_yield_or_interaction_radius_is_refused(value, name):
    with pytest.raises(ValueError, match=name):
        BatchedEnv("crowd", num_agents=3, action="residual", **{name: value})
    with pytest.raises(ValueError, match=name):
        wrappers.ResidualAction(rsvo_env.parallel_env("crowd"), **{name: value})


def test_yielding_never_reopens_an_agent_en_route():
    """The yield rule is for parked agents: two agents 2 m apart, both far from their goals,
    with yield_radius 3 > interaction_radius 1, are alone as far as the gate goes."""
    positions = np.array([[[0.0, 0.0], [2.0, 0.0]]])
    goals = np.array([[[50.0, 0.0], [-50.0, 0.0]]])
    residual = Residual(0.5, yield_radius=3.0, interaction_radius=1.0)
    assert not residual.open(positions, goals).any()
    # one of them parked: it may yield to the other, which stays alone
    goals[0, 0] = positions[0, 0]
    assert residual.open(positions, goals).tolist() == [[True, False]]


@pytest.mark.parametrize("stall_gate", [None, 1.0])
def test_a_stalled_agent_follows_the_script_with_a_stall_gate(stall_gate):
    """Two agents far apart, each held still by a residual straight against its scripted
    command: with a stall gate of 1 s, an agent whose progress clock has reached 1 s takes the
    scripted step (its residual ignored), which is progress, so the policy acts again; without
    one the agents stay held."""
    venv = BatchedEnv(
        "position_swap",
        action="residual",
        safety_filter=False,
        dt=0.1,
        deadlock_resolution="none",
        stall_gate=stall_gate,
    )
    venv.reset(seed=0)
    s = venv.sim.state
    scripted = 0
    for _ in range(40):
        toward = s.goals - s.positions
        toward /= np.linalg.norm(toward, axis=-1, keepdims=True)
        gated = s.no_progress * 0.1 >= (np.inf if stall_gate is None else stall_gate)
        before = s.positions.copy()
        venv.step(-toward)  # cancels the full-speed scripted command (scale 1)
        step = np.linalg.norm(s.positions - before, axis=-1)
        assert np.array_equal(step > 1e-9, gated)  # moved exactly when the gate closed
        assert (s.no_progress[gated] == 0).all()
        scripted += int(gated.sum())
    assert (scripted > 0) == (stall_gate is not None)


def test_the_residual_settings_have_one_owner():
    """Residual owns every default; BatchedEnv, ResidualAction and a training config take its
    values under one spelling (Residual.ENV_KEYWORDS)."""
    import dataclasses
    import inspect

    from rsvo_env import BatchedEnv
    from rsvo_env.control.residual import ENV_KEYWORDS, Residual
    from rsvo_env.training.config import residual_settings

    defaults = {f.name: f.default for f in dataclasses.fields(Residual)}
    batched = inspect.signature(BatchedEnv).parameters
    wrapper = inspect.signature(wrappers.ResidualAction).parameters
    assert set(wrapper) - {"env"} == set(ENV_KEYWORDS)
    for keyword, name in ENV_KEYWORDS.items():
        assert batched[keyword].default == defaults[name], keyword
        assert wrapper[keyword].default == defaults[name], keyword
    assert residual_settings({}) == Residual()
    given = {"gate_radius": 0.25, "residual_scale": 2.0, "yield_radius": 1.25, "k": 3}
    assert residual_settings(given) == Residual(0.25, scale=2.0, yield_radius=1.25)


@pytest.mark.parametrize("dynamics", ["single_integrator", "double_integrator", "unicycle"])
def test_a_zero_residual_is_the_scripted_command_for_every_model(dynamics):
    """Residual actions are residual for every model: a zero action asks for exactly the
    scripted command (the unicycle's once ignored it and asked for (v, w) = (0, 0))."""
    env = BatchedEnv("doorway", num_envs=2, num_agents=8, dynamics=dynamics, action="residual")
    env.reset(seed=0)
    for _ in range(20):
        expect = env.sim.nominal_controls()
        got = env.sim.to_controls(np.zeros((2, 8, 2)))
        # the sum is held to the bound again, which may round a command at the bound
        np.testing.assert_allclose(got, expect, rtol=1e-15, atol=0)
        env.step(np.zeros((2, 8, 2)))


def test_a_doorway_of_unicycles_behind_zero_residuals_gets_home():
    """The doorway of 8 unicycles with residual actions of zero: every agent home (the unicycle
    once took them as direct (v, w) commands and no agent moved)."""
    env = BatchedEnv("doorway", num_envs=1, num_agents=8, dynamics="unicycle", action="residual")
    env.reset(seed=0)
    for _ in range(env.sim.max_steps):
        _, _, terminated, truncated, info = env.step(np.zeros((1, 8, 2)))
        if terminated[0] or truncated[0]:
            break
    assert info["episode_success"][0] and info["episode_arrived"][0] == 8


LIMITED = dict(starts=[[0.0, 0.0], [10.0, 0.0]], goals=[[0.0, 10.0], [10.0, 10.0]])


@pytest.mark.parametrize("dynamics,limit", [("single_integrator", "u_max"),
                                            ("double_integrator", "a_max"),
                                            ("unicycle", "u_max")])  # fmt: skip
@pytest.mark.parametrize("action", ["residual", "direct"])
def test_each_agent_is_held_to_its_own_limit(dynamics, limit, action):
    """A scene with ``u_max`` (``a_max``) = (0.5, 2), filter off, action (1, 0) for both: the
    first agent's input is held to 0.5 and the second may use 2 (the residual's sum was held to
    the largest limit; the unicycle's forward speed ignored its own limit)."""
    env = BatchedEnv(
        "custom",
        num_envs=1,
        safety_filter=False,
        dynamics=dynamics,
        action=action,
        **{limit: [0.5, 2.0]},
        **LIMITED,
    )
    env.reset(seed=0)
    for _ in range(5):
        u = env.sim.to_controls(np.array([[[1.0, 0.0], [1.0, 0.0]]]))[0]
        size = np.abs(u[:, 0]) if dynamics == "unicycle" else np.hypot(u[:, 0], u[:, 1])
        assert size[0] <= 0.5 * (1 + 1e-12)
        assert size[1] > 0.5
        env.step(np.array([[[1.0, 0.0], [1.0, 0.0]]]))
    speed = np.hypot(*env.sim.state.velocities[0].T)
    assert speed[0] <= 0.5 * (1 + 1e-12) or dynamics == "double_integrator"
