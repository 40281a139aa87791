"""Dynamics models are classes found by name or given as instances; nothing outside them
compares a model's name."""

import re
from pathlib import Path

import numpy as np
import pytest

from rsvo_env import dynamics
from rsvo_env.dynamics import DoubleIntegrator, SingleIntegrator
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.filter.safety import FilterConfig, SafetyFilter

ROOT = Path(__file__).resolve().parents[2]


def test_names_and_instances_are_the_same_model():
    for name, cls in (
        ("single_integrator", SingleIntegrator),
        ("double_integrator", DoubleIntegrator),
    ):
        by_name = FilterConfig(dynamics=name, u_max=2.0, dt=0.01)
        by_instance = FilterConfig(dynamics=cls(), u_max=2.0, dt=0.01)
        assert (
            by_name.model == by_instance.model and by_name.dynamics == by_instance.dynamics == name
        )


@pytest.mark.parametrize("bad", ["unicycl", "", 3, None, True])
def test_an_unknown_model_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="dynamics"):
        FilterConfig(dynamics=bad)
    with pytest.raises(ValueError, match="dynamics"):
        dynamics.get(bad)


def test_a_model_of_ones_own_is_used_as_given():
    """An instance of a subclass is the model the filter and the core call: here a single
    integrator whose step halves the velocity it integrates (a drag), recognisable in the state."""

    class Dragged(SingleIntegrator):
        def step(self, positions, velocities, u, dt):
            return positions + dt * 0.5 * u, 0.5 * u

    cfg = FilterConfig(dynamics=Dragged(), u_max=2.0, dt=0.01)
    assert isinstance(cfg.model, Dragged)
    res = SafetyFilter(cfg).filter([[0.0, 0.0], [3.0, 0.0]], [[1.0, 0.0], [0.0, 0.0]], [1, 1])
    assert res.feasible.all()
    env = BatchedEnv("crowd", num_agents=3, safety_filter=False)
    env.reset(seed=0)
    env.scenario.dynamics = Dragged()  # the scenario names its model; an instance is one too
    before = env.sim.state.positions.copy()
    env.step(np.ones((1, 3, 2), dtype=np.float32) * 0.1)
    u = 0.1 * env.scenario.u_max  # each component of the control the action asks for
    np.testing.assert_allclose(env.sim.state.velocities, 0.5 * u)  # the model's drag
    np.testing.assert_allclose(env.sim.state.positions - before, env.sim.dt * 0.5 * u)


def test_no_model_name_is_compared_outside_the_models():
    pattern = re.compile(r"""(==|!=|\bin)\s*\(?\s*["'](single|double)_integrator["']""")
    pattern2 = re.compile(r"""["'](single|double)_integrator["']\s*(==|!=)""")
    hits = []
    for path in (ROOT / "rsvo_env").rglob("*.py"):
        if "dynamics" in path.parts[-2:-1]:
            continue
        for k, line in enumerate(path.read_text().splitlines(), 1):
            if pattern.search(line) or pattern2.search(line) or "DYNAMICS[" in line:
                hits.append(f"{path.relative_to(ROOT)}:{k}: {line.strip()}")
    assert not hits, hits
