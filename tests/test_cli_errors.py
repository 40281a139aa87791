"""The command lines' contract: a user's mistake is one ``error:`` line and exit status 2, found
before any work; a bug in our code keeps its traceback. Training configs are checked against
their schema before anything runs, every bad value named."""

import copy

import pytest

from rsvo_env.cli import main as rsvo
from rsvo_env.envs.parallel import RSVOParallelEnv
from training import config as configs
from training import evaluate, train


def one_error_line(capsys):
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "error:" in lines[0], lines
    assert "Traceback" not in lines[0]
    return lines[0]


@pytest.fixture
def a_file(tmp_path):
    f = tmp_path / "afile"
    f.write_text("not a folder")
    return f


@pytest.mark.parametrize(
    "args,words",
    [
        (["simulate", "--seed", "-1"], ["-1", ">= 0"]),
        (["simulate", "--gif", "{afile}/x.gif"], ["afile", "not a directory"]),
        (["simulate", "--png", "{afile}/x.png"], ["afile", "not a directory"]),
        (["simulate", "--gif", "{tmp}"], ["must end in .gif"]),
        (["reproduce", "--out", "{afile}/sub"], ["afile", "not a directory"]),
        (["reproduce", "--out", "{afile}"], ["not a directory"]),
        (["reproduce", "--seed", "-3", "--quick"], ["-3"]),
        (["reproduce", "--readme", "{tmp}/none.md", "--quick"], ["none.md"]),
        (["simulate", "circular_swap", "--theta", "1", "1"], ["theta has 2 entries"]),
    ],
)
def test_rsvo_user_errors_are_one_line_before_any_work(
    tmp_path, a_file, capsys, monkeypatch, args, words
):
    ran = []
    monkeypatch.setattr(RSVOParallelEnv, "step", lambda *a: ran.append(1))
    args = [a.format(afile=a_file, tmp=tmp_path) for a in args]
    assert exit_code(lambda: rsvo.main(args)) == 2
    line = one_error_line(capsys)
    assert all(w in line for w in words), line
    assert not ran  # no episode ran


def exit_code(call):
    """What the command exits with: its return value, or argparse's ``sys.exit``."""
    try:
        return call()
    except SystemExit as exit_:
        return exit_.code


def test_a_bug_keeps_its_traceback(monkeypatch):
    """A ValueError raised inside the episode is not the user's: it propagates."""

    def broken(self, actions):
        raise ValueError("a bug in the step")

    monkeypatch.setattr(RSVOParallelEnv, "step", broken)
    with pytest.raises(ValueError, match="a bug in the step"):
        rsvo.main(["simulate", "position_swap"])


SMALL = ["--scenario", "position_swap", "--timesteps", "64", "--num-envs", "2"]


@pytest.mark.parametrize(
    "extra,words",
    [
        (["--set", "validation=5"], ["validation", "5", "mapping"]),
        (["--config", "{tmp}/missing.yaml"], ["missing.yaml", "does not exist"]),
        (["--seed", "-1"], ["-1"]),
        (["--set", "ppo.n_epochs=abc"], ["ppo.n_epochs", "'abc'"]),
        (["--set", "ppo.n_epoch=10"], ["n_epoch", "unknown"]),
        (["--set", "validation.episodes=0"], ["validation.episodes", "0"]),
        (["--set", "validation.episodes=2.5"], ["validation.episodes", "2.5"]),
        (["--set", "validation.every=abc"], ["validation.every", "abc"]),
        (["--set", "validation.seed=-5"], ["validation.seed", "-5"]),
        (["--set", "validation.episdoes=3"], ["episdoes"]),
        (["--set", "checkpoint_every=-5"], ["checkpoint_every", "-5"]),
        (["--set", "env=5"], ["env", "mapping"]),
        (["--set", "ppo.policy_kwargs=5"], ["ppo.policy_kwargs", "mapping"]),
        (["--set", "ppo.policy_kwargs.net_arc=[8]"], ["net_arc"]),
        (["--set", "rllib.bogus=1"], ["rllib", "bogus"]),
        (["--set", "residual_right_hand=nope"], ["residual_right_hand", "nope"]),
        (["--set", "gate_radius=abc"], ["gate_radius", "abc"]),
        (["--out", "{afile}/run"], ["afile", "not a directory"]),
    ],
)
def test_train_refuses_bad_configs_before_anything_runs(tmp_path, a_file, capsys, extra, words):
    extra = [a.format(tmp=tmp_path, afile=a_file) for a in extra]
    out = [] if "--out" in extra else ["--out", str(tmp_path / "run")]
    with pytest.raises(SystemExit) as exit_:
        train.main([*SMALL, *extra, *out])
    assert exit_.value.code == 2
    line = one_error_line(capsys)
    assert all(w in line for w in words), line
    assert not (tmp_path / "run").exists()  # no half-written run folder


@pytest.mark.parametrize(
    "extra,words",
    [
        (["--seed", "-1"], ["-1"]),
        (["--episodes", "0"], ["0"]),
        (["--gif", "{afile}/e.gif"], ["afile", "not a directory"]),
        (["--out", "{afile}/e.json"], ["afile", "not a directory"]),
    ],
)
def test_evaluate_refuses_bad_arguments_before_any_episode(tmp_path, a_file, capsys, extra, words):
    extra = [a.format(afile=a_file) for a in extra]
    with pytest.raises(SystemExit) as exit_:
        evaluate.main([str(tmp_path / "model.zip"), *extra])
    assert exit_.value.code == 2
    line = one_error_line(capsys)
    assert all(w in line for w in words), line


def test_every_shipped_config_passes_its_schema():
    for path in sorted(configs.CONFIG_DIR.glob("*.yaml")):
        cfg = configs.load(path=path)
        resolved = configs.resolve(copy.deepcopy(cfg))
        assert resolved["validation"]["episodes"] >= 1


@pytest.mark.parametrize(
    "extra,words",
    [
        (["--seeds", "-1"], ["-1"]),
        (["--timesteps", "0"], ["0"]),
        (["--set", "validation=3"], ["validation", "mapping"]),
        (["--scenario", "nowhere"], ["nowhere"]),
        (["--out", "{afile}/sweep"], ["afile", "not a directory"]),
    ],
)
def test_sweep_refuses_bad_arguments_before_any_trial(tmp_path, a_file, capsys, extra, words):
    from training import sweep

    extra = [a.format(afile=a_file) for a in extra]
    out = [] if "--out" in extra else ["--out", str(tmp_path / "sweep")]
    with pytest.raises(SystemExit) as exit_:
        sweep.main([*extra, *out])
    assert exit_.value.code == 2
    line = one_error_line(capsys)
    assert all(w in line for w in words), line
    assert not (tmp_path / "sweep").exists()
