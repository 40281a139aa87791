"""Bad input is refused by name, and the state is left as it was: seeds, reset options, flags,
residual parameters whatever the action mode, the filter's box bounds."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env import wrappers
from rsvo_env.control.residual import Residual
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.filter.safety import FilterConfig

BAD_SEEDS = [1.5, "3", np.float64(2.0), 2.0, -1, True, np.bool_(False), 1j]


@pytest.mark.parametrize("seed", BAD_SEEDS)
def test_batched_and_single_envs_refuse_the_same_seeds(seed):
    venv = BatchedEnv("crowd", num_envs=2, num_agents=3)
    venv.reset(seed=0)
    before = venv.sim.state.positions.copy()
    with pytest.raises(ValueError, match="seed"):
        venv.reset(seed=seed)
    np.testing.assert_array_equal(venv.sim.state.positions, before)
    env = rsvo_env.parallel_env("crowd", num_agents=3)
    with pytest.raises(ValueError, match="seed"):
        env.reset(seed=seed)


def test_numpy_integer_seeds_are_seeds():
    a, b = BatchedEnv("crowd", num_envs=2, num_agents=3), BatchedEnv("crowd", num_envs=2)
    np.testing.assert_array_equal(a.reset(seed=np.int64(5))[0], a.reset(seed=5)[0])
    assert b.reset(seed=np.uint8(3))[0].shape[0] == 2


@pytest.mark.parametrize(
    "theta",
    [
        [[1.0], [2.0], [3.0]],  # (E, 1): once read as one row [1, 2, 3] for every env
        [[1, 2, 3, 4, 5, 6]] * 3,  # (E, 2N)
        [[1.0, 2.0, 3.0]],  # (1, N) for 3 envs
        [[[1.0, 2.0, 3.0]]] * 3,  # 3-D
        [1.0, 2.0],  # too few
    ],
)
def test_theta_options_of_the_wrong_shape_are_refused_by_name(theta):
    venv = BatchedEnv("crowd", num_envs=3, num_agents=3)
    venv.reset(seed=0)
    before = venv.sim.state.theta.copy()
    with pytest.raises(ValueError, match="theta"):
        venv.reset(seed=1, options={"theta": theta})
    np.testing.assert_array_equal(venv.sim.state.theta, before)


def test_a_bad_theta_row_names_its_env_and_agent():
    venv = BatchedEnv("crowd", num_envs=3, num_agents=3)
    with pytest.raises(ValueError, match=r"theta\[2\] = -3.0.*agent 2.*env 1"):
        venv.reset(seed=0, options={"theta": [[1, 2, 3], [1, 2, -3], [1, 1, 1]]})
    with pytest.raises(ValueError, match="theta"):
        venv.reset(seed=0, options={"theta": [["1", "2", "3"]] * 3})
    obs, _ = venv.reset(seed=0, options={"theta": [[1, 2, 3], [4, 5, 6], [7, 8, 9]]})
    np.testing.assert_array_equal(venv.sim.state.theta, [[1, 2, 3], [4, 5, 6], [7, 8, 9]])


BAD_FLAGS = ["False", "no", 0, 1, None, 1.0, "True"]


@pytest.mark.parametrize("value", BAD_FLAGS)
def test_flags_are_true_or_false(value):
    with pytest.raises(ValueError, match="right_hand"):
        Residual(0.5, right_hand=value)
    with pytest.raises(ValueError, match="safety_filter"):
        BatchedEnv("crowd", num_agents=3, safety_filter=value)
    with pytest.raises(ValueError, match="right_hand"):
        BatchedEnv("crowd", num_agents=3, action="residual", residual_right_hand=value)
    with pytest.raises(ValueError, match="safety_filter"):
        rsvo_env.parallel_env("crowd", safety_filter=value)
    with pytest.raises(ValueError, match="record_series"):
        rsvo_env.parallel_env("crowd", record_series=value)


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"gate_radius": "abc"}, "gate_radius"),
        ({"residual_scale": -5}, "scale"),
        ({"interaction_radius": float("nan")}, "interaction_radius"),
        ({"yield_radius": 0.0}, "yield_radius"),
        ({"residual_right_hand": "nope"}, "right_hand"),
    ],
)
def test_residual_parameters_are_checked_without_residual_actions(kwargs, name):
    with pytest.raises(ValueError, match=name):
        BatchedEnv("crowd", num_agents=3, action="direct", **kwargs)


@pytest.mark.parametrize(
    "kwargs,name",
    [
        ({"u_max": "3"}, "u_max"),
        ({"u_max": True}, "u_max"),
        ({"u_max": ("1", "2")}, "u_max"),
        ({"u_min": "-1"}, "u_min"),
        ({"u_max": 3 + 0j}, "u_max"),
        ({"u_max": [1.0, 2.0, 3.0]}, "u_max"),
        ({"u_max": float("nan")}, "u_max"),
        ({"u_min": (1.0, 1.0), "u_max": 2.0}, "u_min"),
    ],
)
def test_filter_box_bounds_are_real_numbers(kwargs, name):
    with pytest.raises(ValueError, match=name):
        FilterConfig(**kwargs)


def test_filter_box_bounds_per_component_are_kept():
    cfg = FilterConfig(u_max=(1.0, 2.0), u_min=np.array([-3.0, -0.5]))
    assert cfg.hi.tolist() == [1.0, 2.0] and cfg.lo.tolist() == [-3.0, -0.5]


@pytest.mark.parametrize(
    "name,kwargs,field",
    [
        ("ramp_merge", {"barrier": 0}, "barrier"),
        ("ramp_merge", {"split": ""}, "split"),
        ("ramp_merge", {"merge_point": -1}, "merge_point"),
        ("ramp_merge", {"merge_point": (0.0, 1.0, 2.0)}, "merge_point"),
        ("ramp_merge", {"v_des": -1.0}, "v_des"),
        ("ramp_merge", {"k_v": -1.0}, "k_v"),
        ("ramp_merge", {"v0": -1.0}, "v0"),
        ("ramp_merge", {"finish_y": -1.0}, "finish_y"),
        ("crowd", {"rh_trigger_factor": -1.0}, "rh_trigger_factor"),
        ("crowd", {"rorca_goal_reach": -0.5}, "rorca_goal_reach"),
        ("crowd", {"rorca_goal_reach": float("inf")}, "rorca_goal_reach"),
        ("circular_swap", {"rh_trigger": -1.0}, "rh_trigger"),
        ("circular_swap", {"circle_radius": 0.0}, "circle_radius"),
        ("crowd", {"side_factor": -2.0}, "side_factor"),
        ("position_swap", {"start": ((0.0, 0.0),)}, "start"),
    ],
)
def test_scenario_parameters_out_of_range_are_refused_by_name(name, kwargs, field):
    with pytest.raises(ValueError, match=field):
        BatchedEnv(name, **kwargs)


@pytest.mark.parametrize("size", ["600", True, 2.5, 0])
def test_render_size_is_an_integer(size):
    with pytest.raises(ValueError, match="render_size"):
        rsvo_env.parallel_env("crowd", render_size=size)


def test_gamma_and_the_filter_keywords_are_reported_as_used_through_every_adapter():
    """One owner: gamma=5 (and barrier, split, neighbor_radius) given to any adapter is the
    value the filter uses and the value the world reports."""
    import gymnasium
    import pettingzoo

    from rsvo_env.training import config as configs

    def used(sim):
        (flt,) = sim.filters
        return flt.config

    sims = {
        "parallel_env + RCBFSafetyFilter": rsvo_env.parallel_env("crowd", gamma=5.0).unwrapped.sim,
        "filtered_parallel_env": rsvo_env.parallel_env("crowd", gamma=5.0).unwrapped.sim,
        "BatchedEnv": BatchedEnv("crowd", gamma=5.0).sim,
        "gymnasium.make": gymnasium.make(
            "rsvo/Crowd-v0", gamma=5.0
        ).unwrapped.parallel.unwrapped.sim,
        "pettingzoo.make": pettingzoo.make("parallel", "rsvo/Crowd-v0", gamma=5.0).unwrapped.sim,
        "SB3VecEnv": wrappers.SB3VecEnv(BatchedEnv("crowd", gamma=5.0)).venv.sim,
        "ResidualAction": wrappers.ResidualAction(
            rsvo_env.parallel_env("crowd", gamma=5.0)
        ).unwrapped.sim,
        "training config": configs.make_env(
            configs.resolve({**configs.load("crowd"), "env": {"num_agents": 4, "gamma": 5.0}}), 1
        ).sim,
    }
    for name, sim in sims.items():
        assert used(sim).gamma == 5.0 == sim.world_params["gamma"], name
    # the filter's other keywords take the same way, gymnasium.make included
    env = gymnasium.make("rsvo/RampMerge-v0", barrier="hocbf", split="sign_aware")
    sim = env.unwrapped.parallel.unwrapped.sim
    assert (used(sim).barrier, used(sim).split) == ("hocbf", "sign_aware")
    assert (sim.world_params["barrier"], sim.world_params["split"]) == ("hocbf", "sign_aware")
    batched = BatchedEnv("ramp_merge", barrier="hocbf").sim
    assert used(batched).barrier == batched.world_params["barrier"] == "hocbf"
    env = gymnasium.make("rsvo/Crowd-v0", neighbor_radius=50.0)  # once an unknown keyword
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert used(env.unwrapped.parallel.unwrapped.sim).neighbor_radius == 50.0
    with pytest.raises(TypeError, match="need safety_filter=True"):
        rsvo_env.parallel_env("crowd", safety_filter=False, neighbor_radius=5.0)


@pytest.mark.parametrize("dt", [1e-18, 1e-300, 5e-324])
def test_a_dt_too_small_for_any_step_count_is_refused_by_name(dt):
    """``dt`` that passes positivity but would make the deadlock window more steps than an
    int64 count holds: a ValueError naming dt at construction (it was an OverflowError, or a
    numba typing error, later)."""
    with pytest.raises(ValueError, match=r"circular_swap\.dt = .* too small"):
        rsvo_env.parallel_env("circular_swap", dt=dt)
    env = rsvo_env.parallel_env("circular_swap", dt=2e-15)  # the smallest kept: it steps
    env.reset(seed=0)
    env.step(env.unwrapped.nominal_actions())


@pytest.mark.parametrize("scenario", ["crowd", "doorway", "obstacle_field", "custom"])
@pytest.mark.parametrize("model", ["double_integrator", "unicycle"])
def test_scenes_take_a_model_instance_as_its_name(scenario, model):
    """``dynamics=DoubleIntegrator()`` where a scene takes models by name: the same episode as
    the name (it raised ValueError); an instance of a model the scene does not take, or not a
    model at all, is refused naming the field."""
    from rsvo_env import dynamics

    scene = {"starts": [[0.0, 0.0], [4.0, 0.0]], "goals": [[4.0, 0.0], [0.0, 0.0]]}
    kwargs = scene if scenario == "custom" else {}
    runs = []
    for given in (model, type(dynamics.MODELS[model])()):
        env = BatchedEnv(scenario, num_envs=2, dynamics=given, **kwargs)
        env.reset(seed=0)
        for _ in range(5):
            env.step(env.nominal_actions())
        runs.append(env.sim.state.positions.copy())
    np.testing.assert_array_equal(runs[0], runs[1])
    with pytest.raises(ValueError, match=r"crowd\.dynamics"):
        rsvo_env.parallel_env("crowd", dynamics=object())
