"""The command lines' contract: a user's mistake is one ``error:`` line and exit status 2, found
before any work; a bug in our code keeps its traceback. Training configs are checked against
their schema before anything runs, every bad value named."""

import copy

import pytest

from rsvo_env.cli import main as rsvo
from rsvo_env.cli import simulate
from rsvo_env.envs.parallel import RSVOParallelEnv
from rsvo_env.training import config as configs
from rsvo_env.training import evaluate, train
from rsvo_env.util import scene_file


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
        (["simulate", "crowd", "--num-agents", "-3"], ["--num-agents", "-3", ">= 2"]),
        (["simulate", "crowd", "--num-agents", "2.5"], ["--num-agents", "2.5"]),
        (["simulate", "crowd", "--max-steps", "0"], ["--max-steps", "0"]),
        (["simulate", "crowd", "--dynamics", "bogus"], ["--dynamics", "bogus"]),
        (["simulate", "ramp_merge", "--dynamics", "unicycle"], ["ramp_merge", "dynamics"]),
        (["simulate", "position_swap", "--num-agents", "5"], ["exactly 2 agents", "5"]),
        # the real reason, not "/proc: No such file or directory"
        (["reproduce", "--out", "/proc/forbidden", "--quick"], ["/proc", "takes no new files"]),
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
        # the filter's settings are checked with the filter off too (they are saved with the run)
        (["--set", "env.safety_filter=false", "--set", "env.gamma=-1"], ["gamma", "-1"]),
        (["--set", "env.safety_filter=false", "--set", "env.barrier=bogus"], ["barrier", "bogus"]),
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
    from rsvo_env.training import sweep

    extra = [a.format(afile=a_file) for a in extra]
    out = [] if "--out" in extra else ["--out", str(tmp_path / "sweep")]
    with pytest.raises(SystemExit) as exit_:
        sweep.main([*extra, *out])
    assert exit_.value.code == 2
    line = one_error_line(capsys)
    assert all(w in line for w in words), line
    assert not (tmp_path / "sweep").exists()


SCENE = "starts: [[0, 0], [4, 0]]\ngoals: [[4, 0], [0, 0]]\n"


@pytest.mark.parametrize("line,flag", [
    ("theta: [1, 3]", ["--theta", "1", "3"]),
    ("weighting: symmetric", ["--weighting", "symmetric"]),
    ("seed: 3", ["--seed", "3"]),
    ("safety_filter: false", ["--no-filter"]),
])  # fmt: skip
def test_a_scene_file_may_hold_the_runs_own_settings(tmp_path, capsys, monkeypatch, line, flag):
    """``theta``, ``weighting``, ``seed`` and ``safety_filter`` in a scene file run as the flag
    would (they crashed: "run() got multiple values for keyword argument"); given in both
    places, one error line before any work."""
    seen = []
    real = simulate.run
    monkeypatch.setattr(simulate, "run", lambda *a, **k: seen.append(k) or real(*a, **k))
    scene = tmp_path / "scene.yaml"
    scene.write_text(SCENE + line + "\n")
    assert exit_code(lambda: rsvo.main(["simulate", "custom", "--scene", str(scene)])) in (0, 1)
    key, value = line.split(": ")
    expect = {"theta": [1, 3], "weighting": "symmetric", "seed": 3, "safety_filter": False}[key]
    assert seen[-1][key] == expect
    capsys.readouterr()
    code = exit_code(lambda: rsvo.main(["simulate", "custom", "--scene", str(scene), *flag]))
    assert code == 2 and "given twice" in one_error_line(capsys)
    assert len(seen) == 1


@pytest.mark.parametrize("text,words", [
    (SCENE + "safety_filter: 'no'\n", ["safety_filter", "'no'"]),
    (SCENE + "seed: 1.5\n", ["seed", "1.5"]),
    (SCENE + "starts: [[0, 1], [4, 1]]\n", ["starts", "twice"]),
    ("a: &x [1, *x]\n" + SCENE, ["refers to itself"]),
    (SCENE + "dt: 1e-300\n", ["dt", "1e-300", "too small"]),
    (SCENE + "dt: 1.0e-18\n", ["dt", "too small"]),
])  # fmt: skip
def test_bad_scene_files_are_one_error_line(tmp_path, capsys, text, words):
    """A scene file's run settings checked as flags are, a key given twice (YAML 1.2 requires
    unique keys; JSON below), a recursive alias, a dt too small for any step count."""
    scene = tmp_path / "scene.yaml"
    scene.write_text(text)
    assert exit_code(lambda: rsvo.main(["simulate", "custom", "--scene", str(scene)])) == 2
    line = one_error_line(capsys)
    assert all(w in line for w in words), line


def test_a_json_scene_with_a_key_twice_is_refused(tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text('{"starts": [[0, 0], [4, 0]], "goals": [[4, 0], [0, 0]], "goals": [[1, 1]]}')
    assert exit_code(lambda: rsvo.main(["simulate", "custom", "--scene", str(scene)])) == 2
    assert "'goals' is given twice" in one_error_line(capsys)


def test_aliases_expand_to_at_most_a_million_values(tmp_path, capsys):
    """Six levels of ten aliases each (about 300 bytes, a million numbers: once a 3.1 MB error
    line) are refused by size before any use; five levels (100,000 numbers) are read."""
    lines = ["a0: &a0 [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 10)}]" for i in range(1, 6)]
    # 11 + 111 + ... + 111,111 values (each list counts) and the mapping
    assert scene_file.check_size(scene_file.load_yaml("\n".join(lines[:5]))) == 123_456
    scene = tmp_path / "scene.yaml"
    scene.write_text("\n".join(lines) + "\nstarts: *a5\n")
    assert exit_code(lambda: rsvo.main(["simulate", "custom", "--scene", str(scene)])) == 2
    line = one_error_line(capsys)
    assert "1,000,000 values" in line and len(line) < 200


@pytest.mark.parametrize("dynamics", ["single_integrator", "double_integrator", "unicycle"])
def test_simulate_reaches_every_model_from_the_command_line(capsys, dynamics):
    """``rsvo simulate crowd --dynamics D --num-agents 12 --max-steps 300`` runs each model:
    300 steps of 12 agents, no contact."""
    args = ["simulate", "crowd", "--dynamics", dynamics, "--num-agents", "12", "--max-steps", "300"]
    assert rsvo.main(args) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    out = {k.strip(): v.strip() for k, v in (line.split(":", 1) for line in lines)}
    assert int(out["steps"]) == 300 and int(out["n_collision_steps"]) == 0
