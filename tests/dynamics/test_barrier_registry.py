"""A barrier is one module plus its registration: a toy barrier defined here, registered with
one call, is what the filter, the config and a batched env run."""

from __future__ import annotations

import numpy as np
import pytest

from rsvo_env.dynamics import barriers
from rsvo_env.dynamics.barriers import Barrier
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.filter.safety import FilterConfig, SafetyFilter
from rsvo_env.qp.rows import PairFlags, finish


class Halting(Barrier):
    """A toy: ``h = |dp|^2 - Ds^2 + 2 dp.dv / gamma``; each agent's share ``omega`` of
    ``2 dp.(a_i - a_j) >= -gamma (2 |dv|^2 + gamma (2 dp.dv) + gamma^2 h) / 2``, a crude
    second-order condition with no claim of safety: the registry is under test, not the toy."""

    name = "halting"
    calls = 0

    def filter_rows(self, cfg, positions, velocities, weights, I, J, bodies, capsules, n):
        type(self).calls += 1
        dp = positions[I] - positions[J]
        dv = velocities[I] - velocities[J]
        Ds = bodies.radii[I] + bodies.radii[J]
        g = cfg.gamma
        h = (dp * dp).sum(-1) - Ds * Ds + 2.0 * (dp * dv).sum(-1) / g
        rhs = 2.0 * (dv * dv).sum(-1) + g * 2.0 * (dp * dv).sum(-1) + 0.5 * g * g * h
        every = np.ones(len(I), dtype=bool)
        none = np.zeros(len(I), dtype=bool)
        flags = PairFlags(every, none, none)
        rows = finish(len(positions), I, J, -2.0 * dp, weights[:, 0] * rhs,
                      weights[:, 1] * rhs, h, bodies.lo, bodies.hi, flags)  # fmt: skip
        return rows, None

    def culling_radii(self, cfg, omega_floor, velocities, bodies):
        return np.where(np.isfinite(omega_floor), np.inf, 0.0)


@pytest.fixture
def halting():
    barrier = barriers.register(Halting())
    try:
        yield barrier
    finally:
        barriers.BARRIERS.pop("halting")


def test_a_registered_barrier_is_what_the_filter_solves(halting):
    cfg = FilterConfig(dynamics="double_integrator", barrier="halting", dt=0.05, gamma=2.0)
    x = np.array([[0.0, 0.0], [1.5, 0.0], [0.0, 1.6]])
    v = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, -1.0]])
    before = Halting.calls
    out = SafetyFilter(cfg).filter(x, 3.0 * v, [1.0, 2.0, 5.0], velocities=v)
    assert Halting.calls == before + 1
    # the toy's rows hold at the answer, and they bind: the nominal is changed
    rows, _ = halting.filter_rows(
        cfg, x, v, np.full((3, 2), 0.5), *np.triu_indices(3, 1), _bodies(cfg, 3), None, 3
    )
    assert not np.allclose(out.actions, np.clip(3.0 * v, cfg.lo, cfg.hi))
    assert halting.h(cfg, x, v, *np.triu_indices(3, 1), _bodies(cfg, 3)).shape == (3,)
    assert len(rows.flat_b) > 0


def test_a_registered_barrier_runs_in_an_env_and_an_unknown_one_is_refused(halting):
    env = BatchedEnv("circular_swap", num_envs=2, num_agents=4, dynamics="double_integrator",
                     barrier="halting")  # fmt: skip
    before = Halting.calls
    env.reset(seed=0)
    for _ in range(5):
        env.step(env.nominal_actions())
    assert Halting.calls > before
    with pytest.raises(ValueError, match=r"FilterConfig.barrier = 'nope'.*'halting'"):
        FilterConfig(dynamics="double_integrator", barrier="nope")


def test_registering_a_taken_name_or_a_non_barrier_raises(halting):
    with pytest.raises(ValueError, match="'halting' is registered already"):
        barriers.register(Halting())
    with pytest.raises(TypeError, match="register takes a Barrier"):
        barriers.register("segment")  # type: ignore[arg-type]
    assert barriers.register(halting) is halting  # the same instance again is no change


def _bodies(cfg, n):
    from rsvo_env.geometry.bodies import Bodies

    return Bodies.of(cfg, 1, n)
