"""rsvo_env.training.train and rsvo_env.training.evaluate through their real entry points, and
their configs."""

import csv
import json

import imageio.v2 as imageio
import numpy as np
import pytest
import yaml

from rsvo_env.cli.main import main as rsvo
from rsvo_env.sim import observation
from rsvo_env.training import config as configs
from rsvo_env.training import evaluate, train
from rsvo_env.training.seeded_episodes import record_gif, run_episodes, scripted_policy
from rsvo_env.wrappers.sb3 import SB3VecEnv

SMALL = [
    "--scenario",
    "circular_swap",
    "--set",
    "env.num_agents=4",
    "--num-envs",
    "2",
    "--set",
    "env.num_obs_neighbors=3",
    "--set",
    "ppo.n_steps=32",
    "--set",
    "ppo.batch_size=128",
    "--set",
    "validation.every=1024",
    "--set",
    "validation.episodes=3",
    "--set",
    "checkpoint_every=2048",
    "--no-progress",
]


def test_train_writes_logs_and_a_model_that_loads_and_evaluates(tmp_path, capsys):
    """Through the command line's ``rsvo train`` and ``rsvo evaluate``."""
    run = tmp_path / "run"
    assert rsvo(["train", *SMALL, "--timesteps", "3000", "--seed", "1", "--out", str(run)]) == 0
    for name in ("config.yaml", "model.zip", "best_model.zip", "progress.csv", "summary.json"):
        assert (run / name).is_file(), name
    assert list((run / "checkpoints").glob("model_*_steps.zip"))
    assert list(run.glob("events.out.tfevents.*"))  # TensorBoard
    with open(run / "progress.csv") as f:
        rows = list(csv.DictReader(f))
    logged = {k for row in rows for k, v in row.items() if v != ""}
    for key in (
        "rollout/success_rate",
        "rollout/completion_time",
        "rollout/intervention_rate",
        "rollout/cost",
        "rollout/infeasible_steps",
        "rollout/ep_rew_mean",
        "rollout/episode_cost",
        "rollout/contact_agent_steps",
        "eval/success_rate",
        "eval/episode_cost",
    ):
        assert key in logged, key
    # no collision anywhere in training: the logged cost is zero in every row
    assert all(float(r["rollout/collision_steps_total"] or 0) == 0 for r in rows)
    assert all(float(r["rollout/contact_agent_steps"] or 0) == 0 for r in rows)
    with open(run / "validation.csv") as f:
        validations = list(csv.DictReader(f))
    assert len(validations) >= 3 and all(int(v["collisions"]) == 0 for v in validations)
    assert all(
        float(v["episode_cost"]) == 0 and float(v["episode_length"]) > 0 for v in validations
    )
    saved = yaml.safe_load((run / "config.yaml").read_text())
    assert saved["env"]["num_agents"] == 4 and saved["seed"] == 1 and saved["algo"] == "ppo"
    # one thread budget for the policy and the env's kernels (the config's default, 1)
    import numba
    import torch

    from rsvo_env.util import threads as kernels

    assert saved["threads"] == 1 == torch.get_num_threads() == numba.get_num_threads()
    assert kernels.get_num_threads() == 1

    gif = tmp_path / "episode.gif"
    args = [str(run / "model.zip"), "--episodes", "6", "--seed", "5", "--compare-scripted"]
    assert rsvo(["evaluate", *args, "--gif", str(gif)]) == 0
    report = json.loads((run / "evaluation.json").read_text())
    assert report["policy"]["episodes"] == 6 and report["policy"]["collisions"] == 0
    # an episode succeeds when every agent arrives: the share arrived is at least the success
    for who in ("policy", "scripted"):
        assert report[who]["success_rate"] <= report[who]["arrived"] <= 1.0
    assert report["scripted"]["collisions"] == 0
    assert report["policy"]["min_distance"] >= 1.0 * (1 - 1e-9)
    assert report["paired_completion_time"]["paired_seeds"] >= 1
    assert gif.stat().st_size > 0
    assert "paired: policy - scripted" in capsys.readouterr().out
    # the same policy in a larger crowd than it was trained in (its observation is local)
    bigger = tmp_path / "bigger.json"
    args = [str(run / "model.zip"), "--episodes", "2", "--set", "env.num_agents=9"]
    assert rsvo(["evaluate", *args, "--out", str(bigger)]) == 0
    report = json.loads(bigger.read_text())
    assert report["num_agents"] == 9 and report["policy"]["collisions"] == 0
    with pytest.raises(SystemExit) as exit_:
        rsvo(["evaluate", str(run / "model.zip"), "--set", "env.num_agents=abc"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.startswith("rsvo evaluate: error:") and "abc" in err


def test_time_limit_stops_training_and_saves(tmp_path, capsys):
    run = tmp_path / "run"
    quiet = [a for a in SMALL if a != "--no-progress"]
    args = [*quiet, "--timesteps", "10000000", "--time-limit", "2", "--out", str(run)]
    assert train.main(args) == 0
    summary = json.loads((run / "summary.json").read_text())
    assert summary["stopped_by_time_limit"] is True
    assert summary["agent_steps"] < 10_000_000 and (run / "model.zip").is_file()
    # the bar follows the time limit: it passes the halfway mark and ends full, although the
    # steps taken are a sliver of the step budget
    frames = capsys.readouterr().err.replace("\r", "\n").splitlines()
    shown = [float(f.split("%")[0].split()[-1]) for f in frames if "agent-steps" in f]
    assert shown and shown[-1] == 100.0 and any(40.0 <= s <= 60.0 for s in shown)
    assert summary["agent_steps"] / 10_000_000 < 0.05


def test_progress_share_is_the_nearer_end_of_the_budget():
    from rsvo_env.training.callbacks import Progress

    bar = Progress(1000, seconds=10.0)
    assert bar.fraction(100, 1.0) == 0.1
    assert bar.fraction(100, 5.0) == 0.5  # the time limit is nearer
    assert bar.fraction(800, 5.0) == 0.8  # the steps are
    assert bar.fraction(2000, 1.0) == 1.0 and bar.fraction(0, 30.0) == 1.0
    assert Progress(1000, None).fraction(250, 1e6) == 0.25


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--set", "env.dt=0.2"], ["gamma * dt", "2"]),
        (["--set", "env.gamma=-1"], ["gamma", "-1"]),
        (["--set", "bogus=1"], ["bogus"]),
        (["--set", "nokey"], ["key=value"]),
        (["--set", "env.theta_range=[0, 3]"], ["theta_range"]),
        (["--scenario", "nowhere"], ["nowhere", "circular_swap"]),
        (["--time-limit", "0"], ["time-limit"]),
        (["--timesteps", "0"], ["timesteps", "0"]),
        (["--set", "ppo.policy_kwargs.activation_fn=gelu"], ["activation_fn", "gelu", "relu"]),
        (["--set", "validation.max_steps=0"], ["validation.max_steps", "0"]),
        (["--set", "validation.max_steps=2.5"], ["validation.max_steps", "2.5"]),
        (["--set", "validation.max_steps=true"], ["validation.max_steps", "True"]),
    ],
)
def test_bad_configs_fail_before_training_naming_the_field(tmp_path, capsys, extra, words):
    with pytest.raises(SystemExit) as exit_:
        train.main([*SMALL, *extra, "--out", str(tmp_path / "r")])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert all(w in err for w in words), err
    assert not (tmp_path / "r" / "model.zip").exists()


def test_every_scenario_has_a_valid_config_with_gamma_dt_at_most_one():
    for path in sorted(configs.CONFIG_DIR.glob("*.yaml")):
        cfg = configs.resolve(configs.load(path=path))
        env = configs.make_env(cfg, num_envs=1)
        assert env.sim.filters[0].config.gamma * env.scenario.params["dt"] <= 1.0
    names = {p.stem for p in configs.CONFIG_DIR.glob("*.yaml")}
    assert names == {
        "circular_swap",
        "crowd",
        "doorway",
        "obstacle_field",
        "position_swap",
        "ramp_merge",
    }


def test_validation_and_evaluation_episodes_have_their_own_time_cap(tmp_path):
    """``validation.max_steps`` caps the episodes of validation and evaluation, not training's;
    a policy that stands still runs into whichever cap applies."""
    cfg = configs.resolve(configs.load("circular_swap"))

    def still(obs, env):
        return np.zeros((*obs.shape[:-1], 2))

    cfg["action"] = "direct"
    assert set(run_episodes(cfg, still, 2, seed=0)["steps"]) == {cfg["env"]["max_steps"]}
    cfg["validation"]["max_steps"] = 37
    assert set(run_episodes(cfg, still, 2, seed=0)["steps"]) == {37}
    assert configs.make_env(cfg, num_envs=1).sim.max_steps == cfg["env"]["max_steps"] != 37
    # the GIF of an evaluation too: a frame at the reset and one a step
    cfg["validation"]["max_steps"] = 4
    gif = record_gif(cfg, still, 0, str(tmp_path / "still.gif"))
    assert len(imageio.mimread(gif)) == 5


def test_zero_residual_is_the_scripted_controller_on_the_same_seeds():
    """The comparison protocol pairs seeds exactly: a zero residual reproduces the scripted
    controller's episodes value for value."""
    cfg = configs.resolve(configs.load("circular_swap"))

    def zero(obs, env):
        return np.zeros((*obs.shape[:-1], 2))

    a = run_episodes(cfg, zero, 4, seed=11)
    b = run_episodes(cfg, scripted_policy, 4, seed=11, action="direct")
    for key in ("success", "completion_time", "steps"):
        assert np.array_equal(a[key], b[key]), key
    # the scripted command reaches the direct env as a float32 action: equal to float32 precision
    for key in ("min_distance", "return"):
        assert np.allclose(a[key], b[key], rtol=1e-5), key
    c = run_episodes(cfg, scripted_policy, 4, seed=12, action="direct")
    assert not np.array_equal(b["min_distance"], c["min_distance"])  # other seeds, other episodes


@pytest.mark.parametrize("stall_gate", [None, 0.5])
def test_the_residual_share_counts_the_agent_steps_in_which_the_residual_acted(stall_gate):
    """A policy that holds every agent still (a residual against the scripted command): with no
    stall gate its residual acts in every agent-step en route (the circular config's gates open
    far from the goal); with a stall gate of 0.5 s it is gated off once an agent stalls, so the
    share falls. A direct-action run has no residual and no share."""
    cfg = configs.resolve(configs.load("circular_swap"))
    cfg = {**cfg, "stall_gate": stall_gate, "env": {**cfg["env"], "max_steps": 40}}
    cfg["validation"] = {**cfg.get("validation", {}), "max_steps": 40}

    def against(obs, env):
        s = env.sim.state
        toward = s.goals - s.positions
        toward /= np.linalg.norm(toward, axis=-1, keepdims=True)
        return env.sim.to_actions(-toward * env.scenario.u_max)

    share = run_episodes(cfg, against, 2, seed=3)["residual_share"]
    if stall_gate is None:
        assert np.array_equal(share, [1.0, 1.0])
    else:
        assert (share > 0.0).all() and (share < 0.9).all()
    assert "residual_share" not in run_episodes(cfg, scripted_policy, 1, seed=3, action="direct")


def test_readme_states_the_circular_config_as_it_is():
    """docs/training.md's quick start describes the shipped config; hold it to the YAML."""
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "docs" / "training.md").read_text()
    text = " ".join(readme.split("## Quick start: a policy behind the filter", 1)[1].split())
    cfg = configs.resolve(configs.load("circular_swap"))
    env = cfg["env"]
    assert "(dt 0.1 s, γ 10, a 30 s time cap)" in text
    assert (env["dt"], env["gamma"], env["max_steps"] * env["dt"]) == (0.1, 10.0, 30.0)
    assert "agent of 32 batched envs" in text and cfg["num_envs"] == 32
    policy = cfg["ppo"]["policy_kwargs"]
    assert "two ReLU layers of 64" in text
    assert policy["net_arch"] == [64, 64] and policy["activation_fn"] == "relu"
    assert "U(1, 10)" in text and env["theta_range"] == [1.0, 10.0] and env["random_rotation"]
    assert "6 M agent-steps" in text and cfg["timesteps"] == 6_000_000
    assert env["frame"] == "goal" and cfg["action"] == "residual" and cfg["algo"] == "ppo"


def test_readme_states_the_crowd_config_as_it_is():
    from pathlib import Path

    readme = (Path(__file__).resolve().parents[2] / "docs" / "training.md").read_text()
    text = " ".join(readme.split("## Quick start: a policy behind the filter", 1)[1].split())
    cfg = configs.resolve(configs.load("crowd"))
    assert "The 12-agent crowd" in text and cfg["env"]["num_agents"] == 12
    assert "`yield_radius: 1.25`" in text and "within 1.25 m" in text
    env = configs.make_env(cfg, num_envs=1)
    assert env.sim.residual.yield_radius == 1.25 == cfg["yield_radius"]
    assert env.scenario.params["safety_radius"] == 1.0  # so 1.25 m is 1.25 R
    assert "15 M agent-steps" in text and cfg["timesteps"] == 15_000_000
    assert "observes its neighbours' goals" in text
    assert "rel_goal" in [f.name for f in observation.NEIGHBOR_FEATURES]
    assert "`interaction_radius: 2.0`" in text and "nobody within 2 m" in text
    assert env.sim.residual.interaction_radius == 2.0 == cfg["interaction_radius"]
    assert "`stall_clock: 50`" in text and env.sim.stall.unit == 50
    assert "episodes end after 40 s" in text and env.sim.max_steps * env.sim.dt == 40.0
    assert "evaluated with a 100 s cap" in text and cfg["validation"]["max_steps"] == 1000
    assert env.single_observation_space.shape == (observation.size(5, stall=True),)


def test_sac_trains_and_evaluates_through_the_same_entry_points(tmp_path):
    run = tmp_path / "sac"
    args = [*SMALL, "--algo", "sac", "--timesteps", "1200", "--set", "sac.learning_starts=400"]
    assert train.main([*args, "--set", "sac.gradient_steps=1", "--out", str(run)]) == 0
    assert yaml.safe_load((run / "config.yaml").read_text())["algo"] == "sac"
    assert evaluate.main([str(run / "model.zip"), "--episodes", "2", "--seed", "3"]) == 0
    report = json.loads((run / "evaluation.json").read_text())
    assert report["policy"]["collisions"] == 0 and report["policy"]["episodes"] == 2


def test_a_named_activation_reaches_the_policy():
    import torch
    from stable_baselines3 import PPO

    # 8 envs of 6 agents, 32 steps: the rollout fills the config's minibatch of 1,536
    cfg = configs.resolve(configs.load("circular_swap"), num_envs=8)
    hyper = configs.hyperparameters(cfg)
    assert hyper["policy_kwargs"]["activation_fn"] is torch.nn.ReLU
    assert cfg["ppo"]["policy_kwargs"]["activation_fn"] == "relu"  # the config keeps its name
    venv = SB3VecEnv(configs.make_env(cfg, num_envs=cfg["num_envs"]))
    model = PPO("MlpPolicy", venv, **hyper)
    layers = list(model.policy.mlp_extractor.policy_net)
    assert [type(m) for m in layers] == [torch.nn.Linear, torch.nn.ReLU] * 2


def test_theta_actions_train_and_evaluate(tmp_path):
    """``env.theta_action: true``: the policy also chooses every agent's theta each step, through
    the same entry points; the report has no collision."""
    run = tmp_path / "run"
    args = [*SMALL, "--set", "env.theta_action=true", "--timesteps", "1500", "--out", str(run)]
    assert train.main(args) == 0
    saved = yaml.safe_load((run / "config.yaml").read_text())
    assert saved["env"]["theta_action"] is True
    args = [str(run / "model.zip"), "--episodes", "3", "--compare-scripted"]
    assert evaluate.main(args) == 0
    report = json.loads((run / "evaluation.json").read_text())
    assert report["policy"]["collisions"] == 0 and report["policy"]["infeasible"] == 0
    cfg = configs.resolve(saved)
    env = configs.make_env(cfg, num_envs=2)
    assert env.single_action_space.shape == (3,)
