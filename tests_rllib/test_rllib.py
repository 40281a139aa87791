"""RLlib (the distributed extra, its own venv): the env adapter, training through the real entry
point locally, with an env runner, on a two-node Ray cluster, and the Tune sweep."""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from ray.rllib.utils.pre_checks.env import check_multiagent_environments

from rsvo_env.training import config as configs
from rsvo_env.training import evaluate, sweep, train
from rsvo_env.training.rllib_env import RSVOMultiAgentEnv

ROOT = Path(__file__).resolve().parents[1]
TINY = [
    "--engine",
    "rllib",
    "--set",
    "env.num_agents=4",
    "--set",
    "env.num_obs_neighbors=3",
    "--set",
    "rllib.train_batch_size=256",
    "--set",
    "rllib.minibatch_size=256",
    "--set",
    "rllib.num_epochs=1",
    "--set",
    "validation.every=1024",
    "--set",
    "validation.episodes=3",
    "--timesteps",
    "2048",
]


def small_cfg():
    cfg = configs.load("circular_swap")
    cfg["env"].update(num_agents=4, num_obs_neighbors=3)
    return configs.resolve(cfg, engine="rllib")


def test_adapter_passes_rllibs_checker_and_equals_the_parallel_env():
    cfg = small_cfg()
    env = RSVOMultiAgentEnv({"cfg": cfg})
    check_multiagent_environments(env)
    ref = configs.make_parallel(cfg)
    obs, infos = env.reset(seed=3)
    ref_obs, _ = ref.reset(seed=3)
    assert all(np.array_equal(obs[a], ref_obs[a]) for a in ref.possible_agents)
    assert set(infos[ref.possible_agents[0]]) >= {"intervention", "cost", "episode_success"}
    rng = np.random.default_rng(0)
    for _ in range(400):
        acts = {a: rng.uniform(-1, 1, 2).astype(np.float32) for a in ref.possible_agents}
        obs, rew, term, trunc, _ = env.step(acts)
        ref_obs, ref_rew, *_ = ref.step(acts)
        assert all(np.array_equal(obs[a], ref_obs[a]) and rew[a] == ref_rew[a] for a in obs)
        # the global state for a centralised critic: the parallel env's, inside its space
        assert np.array_equal(env.state(), ref.state()) and env.state_space.contains(env.state())
        if term["__all__"] or trunc["__all__"]:
            assert env.agents == [] and len(term) == len(obs) + 1
            break
    else:
        pytest.fail("the episode never ended")


def run_train(tmp_path, capsys, *extra):
    out = tmp_path / "run"
    assert train.main([*TINY, *extra, "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["engine"] == "rllib" and summary["agent_steps"] >= 2048
    assert summary["validation"]["collisions"] == 0
    for name in ("config.yaml", "progress.csv", "validation.csv", "checkpoint", "best_checkpoint"):
        assert (out / name).exists(), name
    # validation.csv as the SB3 path writes it: a row per validation, no collision in any
    with open(out / "validation.csv") as f:
        validations = list(csv.DictReader(f))
    assert validations and {"timesteps", "success_rate", "collisions"} <= set(validations[0])
    assert all(int(v["collisions"]) == 0 for v in validations)
    assert evaluate.main([str(out / "checkpoint"), "--episodes", "4", "--compare-scripted"]) == 0
    report = json.loads((out / "evaluation.json").read_text())
    assert report["policy"]["collisions"] == 0 and report["policy"]["episodes"] == 4
    assert report["policy"]["min_distance"] >= 1.0 * (1 - 1e-9)
    assert "paired: policy - scripted" in capsys.readouterr().out
    return summary


def test_local_training_writes_a_checkpoint_that_evaluates(tmp_path, capsys):
    summary = run_train(tmp_path, capsys)
    assert summary["env_runner_nodes"] == []  # local mode: the driver sampled
    rows = (tmp_path / "run" / "progress.csv").read_text().splitlines()
    assert rows[0].startswith("agent_steps,") and len(rows) >= 3


def test_training_with_one_env_runner(tmp_path, capsys):
    summary = run_train(
        tmp_path, capsys, "--num-env-runners", "1", "--num-envs-per-env-runner", "2"
    )
    assert len(summary["env_runner_nodes"]) == 1


def ray_cli(*args):
    ray = str(Path(sys.executable).parent / "ray")
    return subprocess.run([ray, *args], capture_output=True, text=True, timeout=180)


def test_a_two_node_cluster_runs_the_env_runners_on_the_worker(tmp_path, capsys):
    """A head with no CPUs and a worker node with two, on the loopback address: the env runner
    (one CPU) can only be placed on the worker."""
    import ray

    port = "6391"
    ray_cli("stop", "--force")
    head = ray_cli(
        "start",
        "--head",
        "--node-ip-address=127.0.0.1",
        f"--port={port}",
        "--num-cpus=0",
        "--include-dashboard=false",
    )
    assert head.returncode == 0, head.stderr
    try:
        worker = ray_cli(
            "start", f"--address=127.0.0.1:{port}", "--node-ip-address=127.0.0.1", "--num-cpus=2"
        )
        assert worker.returncode == 0, worker.stderr
        ray.init(address=f"127.0.0.1:{port}")
        nodes = [n for n in ray.nodes() if n["Alive"]]
        ray.shutdown()
        assert len(nodes) == 2
        worker_id = next(n["NodeID"] for n in nodes if n["Resources"].get("CPU", 0) == 2)
        summary = run_train(
            tmp_path, capsys, "--num-env-runners", "1", "--address", f"127.0.0.1:{port}"
        )
        assert summary["env_runner_nodes"] == [worker_id]
        assert summary["driver_node"] != worker_id
    finally:
        ray_cli("stop", "--force")


def test_sweep_writes_its_table(tmp_path):
    out = tmp_path / "sweep"
    args = [
        "--set",
        "env.num_agents=4",
        "--set",
        "env.num_obs_neighbors=3",
        "--set",
        "rllib.train_batch_size=256",
        "--set",
        "rllib.minibatch_size=256",
        "--set",
        "rllib.num_epochs=1",
        "--timesteps",
        "1000",
        "--episodes",
        "3",
        "--seeds",
        "0",
        "--thetas",
        "paper",
        "--out",
        str(out),
    ]
    assert sweep.main(args) == 0
    rows = (out / "sweep.csv").read_text().splitlines()
    assert len(rows) == 1 + 2  # two weightings x one theta assignment x one seed
    table = (out / "sweep.md").read_text()
    for words in ("| asymmetric | paper |", "| symmetric | paper |"):
        assert words in table
    assert all(row.split(",")[6] == "0" for row in rows[1:])  # no collision in any trial


def test_bad_engine_options_are_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        train.main([*TINY, "--num-env-runners", "-1", "--out", str(tmp_path / "r")])
    assert exit_.value.code == 2 and "num-env-runners" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        train.main([*TINY, "--algo", "sac", "--out", str(tmp_path / "r")])
    assert "rllib engine trains ppo" in capsys.readouterr().err
    assert os.environ.get("RAY_ADDRESS") is None  # nothing left pointing at a cluster


def test_one_module_is_shared_by_every_agent():
    from rsvo_env.training.rllib_engine import SHARED, build

    config = build(small_cfg(), 0, 1)
    assert set(config.policies) == {SHARED}
    assert {config.policy_mapping_fn(a, None) for a in ("agent_0", "agent_3")} == {SHARED}


def test_theta_search_runs_tune_with_optuna_and_never_loses_to_its_starts(tmp_path):
    """Ray Tune + Optuna's TPE over the paper's six-agent game: the starts (the paper's
    alternating assignment, equal scores) are trials, so the best is at least as good as both,
    and the report's measures are those of the batched evaluation."""
    from rsvo_env.training import theta_search

    out = tmp_path / "search"
    assert theta_search.main(["--trials", "6", "--out", str(out)]) == 0
    report = json.loads((out / "search.json").read_text())
    assert report["trials"] == 6 and len(report["rows"]) == 6
    assert report["alternating"]["completion"] == 489 and report["equal"]["completion"] == 610
    assert report["best"]["completion"] <= report["alternating"]["completion"]
    low, high = report["range"]
    for row in report["rows"]:
        assert all(low <= t <= high for t in row["theta"]) and row["collision_steps"] == 0
    # a row's objective is the batched evaluation of its theta
    from rsvo_env.envs.vector import BatchedEnv
    from rsvo_env.training.personalities import PAPER_GAME, evaluate

    row = report["rows"][-1]
    stats = evaluate([row["theta"]], [0], **PAPER_GAME)
    done, cap = stats["completed"][0, 0], BatchedEnv("circular_swap").sim.max_steps
    assert row["completion"] == (done if done >= 0 else 2 * cap)


def test_theta_search_refuses_bad_arguments(tmp_path, capsys):
    from rsvo_env.training import theta_search

    for args, words in (
        (["--low", "5", "--high", "1"], "--low 5.0 exceeds --high 1.0"),
        (["--low", "0"], "--low"),
        (["--set", "num_agents=abc"], "num_agents"),
        (["--set", "nonsense"], "key=value"),
    ):
        with pytest.raises(SystemExit) as exit_:
            theta_search.main([*args, "--out", str(tmp_path / "s")])
        assert exit_.value.code == 2 and words in capsys.readouterr().err


def test_theta_actions_through_the_rllib_adapter_and_module(tmp_path, capsys):
    """``env.theta_action: true`` on the RLlib path: the adapter passes RLlib's checker with
    three action components, and a trained module's policy answers with three."""
    cfg = small_cfg()
    cfg["env"]["theta_action"] = True
    env = RSVOMultiAgentEnv({"cfg": cfg})
    check_multiagent_environments(env)
    assert env.action_spaces["agent_0"].shape == (3,)
    out = tmp_path / "run"
    args = [*TINY, "--set", "env.theta_action=true", "--out", str(out)]
    assert train.main(args) == 0
    assert evaluate.main([str(out / "checkpoint"), "--episodes", "2"]) == 0
    report = json.loads((out / "evaluation.json").read_text())
    assert report["policy"]["collisions"] == 0 and report["policy"]["infeasible"] == 0
