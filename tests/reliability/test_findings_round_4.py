"""Regression tests of the fourth reliability campaign (issue 43): each failed on 043dc0a.
Findings 1 and 2 (rounding at the backup barrier's edge) are in test_backup_barrier.py."""

import numpy as np
import pytest

from rsvo_env.control.stall import DEADLOCK_SECONDS, deadlock_steps
from rsvo_env.envs.vector import BatchedEnv


@pytest.mark.parametrize("dt", [0.3, 0.01, 0.05, 0.1, 0.7, 1e-3, 3.0, 20.0])
def test_3_no_agent_is_deadlocked_before_ten_seconds(dt):
    """The window is the fewest steps that last 10 s: at dt 0.3, 34 steps (10.2 s), not the 33
    (9.9 s) a rounding of 10 / dt gave; no step more where 10 / dt is whole."""
    steps = deadlock_steps(dt)
    assert steps * dt >= DEADLOCK_SECONDS * (1 - 1e-12)
    assert steps == 1 or (steps - 1) * dt < DEADLOCK_SECONDS * (1 - 1e-12)


def test_3_an_agent_held_at_dt_0_3_is_deadlocked_after_ten_seconds_only():
    env = BatchedEnv("crowd", num_envs=1, num_agents=4, dt=0.3, gamma=3.0, max_steps=60)
    env.reset(seed=0)
    hold = np.zeros((1, 4, 2))
    for step in range(1, 40):
        *_, info = env.step(hold)
        flagged = info["deadlocked"][0] & ~info["at_goal"][0]
        assert flagged.any() == (step * 0.3 >= 10.0 - 1e-9), step


def test_4_nominal_actions_keep_theta_exactly():
    """With theta actions, the scripted controller's theta component keeps each agent's score
    bit for bit (it came back as 2.0000000659593 and 7.2999998978 through float32), so the
    filtered actions are those of the same run with theta fixed, step for step."""
    theta = np.array([2.0, 7.3, 1.0, 0.1, 10.0, 3.3])
    runs = {}
    for chosen in (True, False):
        env = BatchedEnv("crowd", num_envs=2, num_agents=6, safety_filter=True, theta_action=chosen)
        env.reset(seed=4, options={"theta": theta})
        u = []
        for _ in range(40):
            a = env.nominal_actions()
            *_, info = env.step(a if chosen else a[..., :2])
            u.append(info["u_safe"])
            if chosen:
                np.testing.assert_array_equal(info["theta"], np.broadcast_to(theta, (2, 6)))
        runs[chosen] = np.array(u)
    np.testing.assert_array_equal(runs[True], runs[False])


def test_5_sb3_refuses_a_next_step_batched_env_at_construction():
    """It was accepted, then raised KeyError '_final_obs' when the first episode ended."""
    from rsvo_env.wrappers import SB3VecEnv

    env = BatchedEnv("crowd", num_envs=2, num_agents=3, autoreset_mode="next_step")
    with pytest.raises(ValueError, match="autoreset_mode = 'next_step'"):
        SB3VecEnv(env)
    vec = SB3VecEnv(BatchedEnv("crowd", num_envs=2, num_agents=3, max_steps=3))
    vec.reset()
    for _ in range(3):
        vec.step_async(np.zeros((6, 2)))
        *_, dones, infos = vec.step_wait()
    assert dones.all() and all("terminal_observation" in i for i in infos)


def test_12_the_vector_env_declares_the_mode_its_batched_env_has_and_the_docs_say_so():
    """A given BatchedEnv keeps its mode (its default SAME_STEP, which NormalizeObservation
    refuses); the docs read as if NEXT_STEP were the default there."""
    from pathlib import Path

    from gymnasium.vector import AutoresetMode
    from gymnasium.wrappers.vector import NormalizeObservation

    from rsvo_env.wrappers import GymnasiumVectorEnv

    given = GymnasiumVectorEnv(BatchedEnv("crowd", num_envs=2, num_agents=3))
    assert given.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    made = GymnasiumVectorEnv("crowd", num_envs=2, num_agents=3)
    assert made.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    nxt = GymnasiumVectorEnv(
        BatchedEnv("crowd", num_envs=2, num_agents=3, autoreset_mode="next_step")
    )
    for env in (made, nxt):
        env = NormalizeObservation(env)
        env.reset(seed=0)
        env.step(env.action_space.sample())
    api = " ".join((Path(__file__).parents[2] / "docs" / "api.md").read_text().split())
    said = "a `BatchedEnv` you pass keeps its own mode, and `BatchedEnv`'s default is `SAME_STEP`"
    assert said in api


def test_7_readme_names_every_registered_step_limit():
    """README said 1500 for two ids and 2000 otherwise; the doorway registers 4000 and the
    obstacle field 3000. Every id's limit is read from the registry and must stand where the
    ids are documented (docs/environments.md, README's reference part before)."""
    import re
    from pathlib import Path

    import gymnasium

    import rsvo_env  # noqa: F401  (registers the ids)

    readme = " ".join((Path(__file__).parents[2] / "docs" / "environments.md").read_text().split())
    said = dict(re.findall(r"`(\w+)` (\d+)", readme.split("(`max_episode_steps`:")[1][:300]))
    specs = {
        k[5:-3]: v.max_episode_steps for k, v in gymnasium.registry.items() if k.startswith("rsvo/")
    }
    assert {k: int(v) for k, v in said.items()} == specs


@pytest.mark.parametrize(
    "setting, words",
    [
        ("ppo.n_steps=0", ["ppo.n_steps", "0", ">= 1"]),
        ("ppo.batch_size=1", ["ppo.batch_size", "1", ">= 2"]),
        ("ppo.n_epochs=0", ["ppo.n_epochs"]),
        ("ppo.gamma=1.5", ["ppo.gamma", "1.5"]),
        ("ppo.gae_lambda=-0.1", ["ppo.gae_lambda"]),
        ("ppo.max_grad_norm=0", ["ppo.max_grad_norm"]),
        ("ppo.learning_rate=-1", ["ppo.learning_rate", "-1", "> 0"]),
        ("ppo.clip_range=0", ["ppo.clip_range", "> 0"]),
        ("ppo.ent_coef=-0.1", ["ppo.ent_coef", "-0.1"]),
        ("ppo.ent_coef=auto", ["ppo.ent_coef", "auto"]),
    ],
)
def test_8_values_sb3_would_fail_on_are_refused_before_any_work(tmp_path, capsys, setting, words):
    """They exited 1 with SB3's 15-line traceback, after config.yaml was written to --out."""
    from rsvo_env.training import train

    out = tmp_path / "run"
    code = exit_code(lambda: train.main(["--set", setting, "--out", str(out)]))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "error:" in err[0], err
    assert all(w in err[0] for w in words), err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    "flags, words",
    [
        (["--num-env-runners", "-1"], ["-1", ">= 0"]),
        (["--num-envs-per-env-runner", "0"], ["0", ">= 1"]),
        (["--num-env-runners", "2"], ["--num-env-runners", "--engine rllib"]),
        (["--address", "localhost:1"], ["--address", "--engine rllib"]),
    ],
)
def test_9_runner_counts_are_checked_and_refused_with_the_sb3_engine(
    tmp_path, capsys, flags, words
):
    """``--num-env-runners -1 --num-envs-per-env-runner 0`` with the SB3 engine exited 0 and
    wrote a whole run: they were checked for RLlib only, and ignored otherwise."""
    from rsvo_env.training import train

    out = tmp_path / "run"
    code = exit_code(lambda: train.main([*flags, "--out", str(out)]))
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "error:" in err[0], err
    assert all(w in err[0] for w in words), err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    "args, words",
    [
        (["simulate", "--png", "/proc/x.png"], ["/proc/x.png", "cannot be written"]),
        (["simulate", "--gif", "/proc/x.gif"], ["/proc/x.gif", "cannot be written"]),
        (["reproduce", "--quick", "--out", "/proc/out"], ["/proc/out", "cannot be written"]),
        (["simulate", "--gif", "{tmp}/missing/x.gif"], ["missing", "does not exist"]),
    ],
)
def test_10_unwritable_outputs_are_found_before_any_work(
    tmp_path, capsys, monkeypatch, args, words
):
    """Permission bits do not tell root (nor a virtual file system): /proc passed the check, the
    whole job ran, then a FileNotFoundError traceback; a missing folder was made silently."""
    from rsvo_env.cli import main as rsvo
    from rsvo_env.envs.parallel import RSVOParallelEnv

    ran = []
    monkeypatch.setattr(RSVOParallelEnv, "step", lambda *a: ran.append(1))
    args = [a.format(tmp=tmp_path) for a in args]
    assert exit_code(lambda: rsvo.main(args)) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(w in err[0] for w in words), err
    assert not ran and not (tmp_path / "missing").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".rsvo-probe")]


def exit_code(call):
    """What a command exits with: its return value, or argparse's ``sys.exit``."""
    try:
        return call()
    except SystemExit as exit_:
        return exit_.code


def test_11_an_id_names_its_scenario():
    """``gymnasium.make("rsvo/Crowd-v0", scenario="custom", ...)`` swapped the scene silently."""
    import gymnasium
    import pettingzoo

    import rsvo_env  # noqa: F401  (registers the ids)

    kw = {"scenario": "custom", "starts": [[0, 0], [5, 0]], "goals": [[5, 0], [0, 0]]}
    with pytest.raises(TypeError, match="scenario = 'custom': this id names the scenario 'crowd'"):
        gymnasium.make("rsvo/Crowd-v0", **kw)
    if hasattr(pettingzoo, "parallel_registry"):
        for kind in ("parallel", "aec"):
            with pytest.raises(TypeError, match="names the scenario 'doorway'"):
                pettingzoo.make(kind, "rsvo/Doorway-v0", scenario="crowd")
    # repeating it is no change
    env = gymnasium.make("rsvo/Crowd-v0", scenario="crowd", num_agents=3)
    assert env.unwrapped.base.scenario.name == "crowd"


def test_14_yaml_numbers_as_a_user_writes_them(tmp_path):
    """``--set env.gamma=1e9`` was refused as the string '1e9' (YAML 1.1 needs ``1.0e9``); the
    same in config files."""
    from rsvo_env.training import config as configs

    cfg = configs.load("crowd", None)
    configs.set_value(cfg, "env.gamma=1e1")
    configs.set_value(cfg, "ppo.learning_rate=3E-4")
    configs.set_value(cfg, "env.num_agents=8")
    assert cfg["env"]["gamma"] == 10.0 and cfg["ppo"]["learning_rate"] == 3e-4
    assert cfg["env"]["num_agents"] == 8 and isinstance(cfg["env"]["num_agents"], int)
    assert configs.resolve(cfg)["env"]["gamma"] == 10.0
    path = tmp_path / "c.yaml"
    path.write_text("scenario: crowd\nenv:\n  gamma: 1e1\n")
    assert configs.load(None, str(path))["env"]["gamma"] == 10.0


@pytest.mark.parametrize("spread, n", [((1, 10), 1500), ((1, 10), 3000), ((1e-3, 1e3), 750),
                                       ((1e-3, 1e3), 1500), ((0.1, 10), 1500)])  # fmt: skip
def test_6_a_steps_memory_is_the_documented_bound_of_agents_and_pairs(spread, n):
    """docs/api.md said "Memory is O(N) an env beyond 1,024 agents", but with theta log-uniform
    on [1e-3, 1e3] a step's peak grew 3.5x for twice the agents: the rows that can bind grow
    toward N^2. The docs now bound it by agents and pairs examined; the bound is read from them
    and measured (tracemalloc: bytes allocated, not time) on the filter's call and on the whole
    ``BatchedEnv.step`` the docs name (the step once peaked over a bound measured on the call
    alone), and theta 1..10 stays O(N)."""
    import re
    import tracemalloc
    from pathlib import Path

    from rsvo_env.filter.safety import FilterConfig, SafetyFilter
    from rsvo_env.scenarios import Crowd

    api = " ".join((Path(__file__).parents[2] / "docs" / "api.md").read_text().split())
    per_agent, per_pair = (
        int(x.replace(",", ""))
        for x in re.search(
            r"at most ([\d,]+) bytes an agent plus ([\d,]+) bytes a pair examined", api
        ).groups()
    )
    rng = np.random.default_rng(n)
    x = Crowd(num_agents=n)._spread(rng)
    theta = np.exp(rng.uniform(*np.log(spread), n))
    angle = rng.uniform(0.0, 2.0 * np.pi, n)
    nominal = 2.0 * np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    flt = SafetyFilter(FilterConfig(gamma=10.0, safety_radius=1.0, u_max=2.0, dt=0.01))
    flt.filter(x, nominal, theta)  # compiled and warmed
    tracemalloc.start()
    res = flt.filter(x, nominal, theta)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    pairs = res.rows.n_pairs
    assert peak <= per_agent * n + per_pair * pairs, (peak, n, pairs)
    if spread == (1, 10):
        assert pairs <= 2.5 * n
    # the step the docs name: the first after a reset (it builds the step's caches) and later
    # ones, scripted and random actions, each against the pairs its own filter call examined
    from rsvo_env.envs.vector import BatchedEnv

    examined = []
    apply = SafetyFilter.apply

    def counted(self, *args, **kwargs):
        out = apply(self, *args, **kwargs)
        examined.append(out.rows.n_pairs)
        return out

    env = BatchedEnv("crowd", num_envs=1, num_agents=n, theta_max=2e3)
    env.reset(seed=1, options={"theta": theta[None]})
    env.step(env.nominal_actions())  # compiled and warmed
    try:
        SafetyFilter.apply = counted
        for step in range(4):
            if step == 0:
                env.reset(seed=0, options={"theta": theta[None]})
            actions = env.nominal_actions() if step % 2 == 0 else rng.uniform(-1, 1, (1, n, 2))
            tracemalloc.start()
            env.step(actions)
            peak = tracemalloc.get_traced_memory()[1]
            tracemalloc.stop()
            assert peak <= per_agent * n + per_pair * examined[-1], (step, peak, n, examined[-1])
    finally:
        SafetyFilter.apply = apply


def test_13_scores_that_overflow_their_sum_warn_nothing():
    """``1e308 + 1e308`` is handled (both halved first) but warned 'overflow encountered in
    add'; every other stray warning of the project's code now fails its test (conftest)."""
    import warnings

    from rsvo_env.responsibility.svo import r_svo, weight_matrix

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert r_svo(1e308, 1e308) == pytest.approx(np.pi / 4)
        W = weight_matrix(np.array([1e308, 1.7976931348623157e308, 1.0]))
    np.testing.assert_allclose((W + W.T)[~np.eye(3, dtype=bool)], 1.0)
