"""Regression tests of the reliability campaign's findings: each one failed before its fix."""

import copy
import pickle
import warnings

import numpy as np
import pytest

import rsvo_env
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.qp import exact, reference


def test_1_a_single_corner_polygon_is_feasible():
    """The capability split's clip makes rows through a box corner: the corner is the answer."""
    A = np.array([[[-6.552450358867645e-04, -3.547957456709048e01]]])
    b = np.array([[-709.6045962425274]])
    u, feasible, _, violation = exact.solve_batch(
        np.array([[2.5, -17.7]]), A, b, np.ones((1, 1), bool), np.full(2, -20.0), np.full(2, 20.0)
    )
    assert feasible[0] and violation[0] == 0.0
    assert A[0, 0] @ u[0] <= b[0, 0] + 1e-9 * 20
    np.testing.assert_allclose(u[0], [20.0, 20.0], rtol=0, atol=1e-5)


def test_2_nearly_parallel_rows_in_millimetres():
    """A nearly parallel pair in a 3000 mm box: feasible, the clarabel answer, no collision."""
    f = SafetyFilter(FilterConfig(gamma=100.0, safety_radius=1000.0, u_max=3000.0, dt=0.01))
    x = np.array([[0, 0], [-4000, -2.9e-12], [-1000.0000000000001, 0], [0, 1020.0]])
    nominal = np.array([[-3000, 3000], [0, 0], [0, 0], [0, 0.0]])
    res = f.filter(x, nominal, [1, 0, 0.25, 1])
    assert res.feasible.all()
    np.testing.assert_allclose(res.actions[0], [0.0, 990.196078], rtol=0, atol=1e-3)
    after = x + 0.01 * res.actions
    gaps = np.linalg.norm(after[:, None] - after[None], axis=-1) + np.eye(4) * 1e9
    assert gaps.min() >= 1000.0 * (1 - 1e-9)


def test_4_the_reference_never_passes_a_vertex_off_as_the_projection(monkeypatch):
    """When a solver fails, the reference asks clarabel for the projection (or raises)."""
    rng = np.random.default_rng(0)
    A = rng.normal(size=(5, 2))
    b = np.abs(rng.normal(size=5)) + 0.5
    lo, hi = np.full(2, -2.0), np.full(2, 2.0)
    nominal = np.array([3.0, -2.5])
    want, _, _ = reference.solve_one(nominal, A, b, lo, hi, "clarabel")
    real_qp = reference._qp

    def failing(nom, A_, b_, lo_, hi_, solver, opts):
        return None if solver == "daqp" else real_qp(nom, A_, b_, lo_, hi_, solver, opts)

    monkeypatch.setattr(reference, "_qp", failing)
    got, feasible, _ = reference.solve_one(nominal, A, b, lo, hi, "daqp")
    assert feasible
    np.testing.assert_allclose(got, want, atol=1e-6)
    monkeypatch.setattr(reference, "_qp", lambda *args: None)
    with pytest.raises(RuntimeError, match="found no projection"):
        reference.solve_one(nominal, A, b, lo, hi, "daqp")


@pytest.mark.parametrize("barrier", ["braking", "hocbf"])
def test_5_coincident_double_integrators_are_flagged(barrier):
    f = SafetyFilter(
        FilterConfig(dynamics="double_integrator", u_max=5.0, gamma=1.0, dt=0.01, barrier=barrier)
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # and no NaN warning on the way
        res = f.filter(
            [[0, 0], [0, 0], [9, 9]],
            [[1, 0], [-1, 0], [0, 0]],
            [1, 1, 1],
            velocities=[[1, 0], [-1, 0], [0, 0]],
        )
    assert res.feasible.tolist() == [False, False, True]
    assert (res.max_violation[:2] > 0).all() and np.isfinite(res.actions).all()


def test_6_the_weight_matrix_is_read_on_every_call():
    f = SafetyFilter(FilterConfig())
    x, nominal = [[0.0, 0.0], [2.5, 0.0]], [[3.0, 0.0], [-3.0, 0.0]]
    W = np.array([[0.0, 0.5], [0.5, 0.0]])
    first = f.filter(x, nominal, [1, 1], omega=W).actions.copy()
    W[0, 1], W[1, 0] = 0.9, 0.1  # in place: the filter must see it
    assert not np.allclose(f.filter(x, nominal, [1, 1], omega=W).actions, first)
    W[0, 1] = np.nan
    with pytest.raises(ValueError, match=r"omega\[0, 1\] = nan"):
        f.filter(x, nominal, [1, 1], omega=W)


@pytest.mark.parametrize(
    "action,pattern",
    [
        (["1.0", "0.5"], "must be real numbers"),
        ([True, False], "must be real numbers"),
        (np.array([True, False]), "must be real numbers"),
        (np.array([1 + 1j, 0]), "must be real numbers"),
    ],
)
def test_7_actions_that_are_not_real_numbers_are_refused(action, pattern):
    env = rsvo_env.parallel_env("position_swap")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=rf"action of agent 'agent_0' {pattern}"):
        env.step({"agent_0": action, "agent_1": np.zeros(2, dtype=np.float32)})


@pytest.mark.parametrize(
    "make,pattern",
    [
        (lambda: rsvo_env.parallel_env("crowd", num_agents=2.7), r"num_agents = 2.7"),
        (lambda: rsvo_env.parallel_env("crowd", num_agents="4"), r"num_agents = '4'"),
        (lambda: FilterConfig(gamma="12"), r"FilterConfig.gamma = '12'"),
        (lambda: FilterConfig(gamma=True), r"FilterConfig.gamma = True"),
        (lambda: rsvo_env.parallel_env("ramp_merge", v0=float("nan")), r"ramp_merge.v0 = nan"),
        (
            lambda: rsvo_env.parallel_env("circular_swap", circle_radius=float("nan")),
            r"circular_swap.circle_radius = nan",
        ),
        (lambda: rsvo_env.parallel_env("position_swap", start=((0, 0), (1, "x"))), "start"),
        (
            lambda: SafetyFilter(FilterConfig()).filter(np.zeros((0, 2)), np.zeros((0, 2)), []),
            "positions has no agents",
        ),
        (lambda: FilterConfig(u_min=(0.5, -3.0), u_max=3.0), "box must contain 0"),
        (lambda: rsvo_env.parallel_env("crowd").reset(options={"theta": ["1"] * 12}), "theta"),
        (lambda: rsvo_env.parallel_env("crowd").reset(options={"theta": [True] * 12}), "theta"),
    ],
)
def test_7_bad_values_are_refused_naming_the_field(make, pattern):
    with pytest.raises(ValueError, match=pattern):
        make()


def test_8_the_aec_env_refuses_a_bad_action_when_it_is_submitted():
    env = rsvo_env.env("position_swap")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"agent 'agent_0' = \[nan, 0.0\] is not finite"):
        env.step(np.array([np.nan, 0.0], dtype=np.float32))
    for _ in range(6):  # the episode goes on
        env.step(np.zeros(2, dtype=np.float32))
    assert env.agents


def test_9_a_huge_finite_action_keeps_its_direction():
    env = rsvo_env.parallel_env("position_swap")
    env.reset(seed=0)
    u = env.unwrapped.action_to_control(np.array([[1e200, 0.0], [-1e300, 1e300]]))
    np.testing.assert_allclose(u, [[2.0, 0.0], [-np.sqrt(2.0), np.sqrt(2.0)]])


def test_10_a_rendering_env_can_be_copied_and_pickled():
    env = rsvo_env.parallel_env("circular_swap", render_mode="rgb_array", render_size=100)
    env.reset(seed=0)
    env.render()
    twin = copy.deepcopy(env)
    again = pickle.loads(pickle.dumps(env))
    for other in (twin, again):
        assert other.render().shape == env.render().shape  # each draws anew
        other.step(other.nominal_actions())
