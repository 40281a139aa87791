"""What a user meets: clean CLI errors, clear refusals of impossible set-ups, warnings for
unused options, registered step limits, a project that points nowhere outside itself."""

import subprocess
import warnings
from pathlib import Path

import gymnasium
import numpy as np
import pytest

import rsvo_env
from tests.support.checkout import run_python

ROOT = Path(__file__).resolve().parents[2]


def rsvo(*args, cwd=None):
    return run_python("-m", "rsvo_env.cli", *args, cwd=cwd)


@pytest.mark.parametrize(
    "args,message",
    [
        (["simulate", "circular_swap", "--theta", "2", "1"], "theta has 2 entries, expected 6"),
        (
            ["simulate", "circular_swap", "--theta", "-1", "1", "1", "1", "1", "1"],
            "theta[0] = -1.0",
        ),
        (["simulate", "--gif", "out.mp4"], "out.mp4 must end in .gif"),
        (["simulate", "--png", "out.jpg"], "out.jpg must end in .png"),
        (["demo", "extra"], "unrecognized arguments: extra"),
        (["simulate", "crowds"], "invalid choice: 'crowds'"),
        (["reproduce", "--seed", "x"], "invalid int value: 'x'"),
    ],
)
def test_cli_user_errors_are_one_line(tmp_path, args, message):
    out = rsvo(*args, cwd=tmp_path)
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], out.stderr
    assert "Traceback" not in out.stderr
    assert not any(tmp_path.iterdir())  # nothing was written: formats are checked first


def test_cli_help_describes_and_shows_defaults():
    top = rsvo("--help")
    assert top.returncode == 0 and "R-CBF" in top.stdout and "reproduce" in top.stdout
    assert "``" not in top.stdout
    sim = " ".join(rsvo("simulate", "--help").stdout.split())  # argparse wraps lines
    assert "(default: circular_swap)" in sim and "(default: 0)" in sim
    assert "(default: asymmetric)" in sim


@pytest.mark.parametrize("name", ["position_swap", "ramp_merge"])
def test_fixed_size_scenarios_refuse_other_counts(name):
    with pytest.raises(
        ValueError, match=rf"{name} is laid out for exactly 2 agents; num_agents = 4"
    ):
        rsvo_env.parallel_env(name, num_agents=4)
    with pytest.raises(ValueError, match="laid out for exactly 2"):
        gymnasium.make(
            f"rsvo/{'PositionSwap' if name == 'position_swap' else 'RampMerge'}-v0", num_agents=3
        )
    rsvo_env.parallel_env(name, num_agents=2)


@pytest.mark.parametrize("count", [0, 1, 2.7, "4", True])
def test_agent_count_must_be_an_integer_of_at_least_two(count):
    with pytest.raises(ValueError, match=r"crowd.num_agents = .* must be an integer >= 2"):
        rsvo_env.parallel_env("crowd", num_agents=count)


@pytest.mark.parametrize("steps", [0, -5, 2.0, "400", True, np.bool_(True)])
def test_the_step_limit_must_be_an_integer_of_at_least_one(steps):
    """A bool is not a step count (True was once taken as a limit of one step)."""
    with pytest.raises(ValueError, match=r"crowd.max_steps = .* must be an integer >= 1"):
        rsvo_env.parallel_env("crowd", num_agents=4, max_steps=steps)


def test_unknown_reset_options_warn_once_and_name_the_known_ones():
    env = rsvo_env.parallel_env("crowd", num_agents=4)
    with pytest.warns(UserWarning, match=r"\['thetas'\] are not used.*\['theta', 'weighting'\]"):
        env.reset(seed=0, options={"thetas": [1, 2, 3, 4]})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env.reset(seed=0, options={"thetas": [1, 2, 3, 4]})  # once is enough
        env.reset(seed=0, options={"theta": [1, 2, 3, 4], "weighting": "symmetric"})


def test_registered_specs_carry_the_step_limit():
    for env_id, scenario in rsvo_env.envs.registration.IDS.items():
        spec = gymnasium.spec(env_id)
        assert spec.max_episode_steps == rsvo_env.SCENARIOS[scenario].defaults["max_steps"]
    # gymnasium.make applies a TimeLimit at the registered limit; a longer episode asks for both
    env = gymnasium.make("rsvo/PositionSwap-v0", max_steps=2000, max_episode_steps=2000)
    assert env.spec.max_episode_steps == 2000 and env.unwrapped.base.max_steps == 2000


def test_repr_names_scenario_and_filter():
    env = rsvo_env.parallel_env("circular_swap", gamma=10.0)
    want = "RSVOParallelEnv('circular_swap', num_agents=6, filter=[gamma=10 exact])"
    assert repr(env.unwrapped) == want
    assert str(env) == "rsvo_circular_swap_v0"  # print(env) names the scenario
    assert str(rsvo_env.parallel_env("crowd")) == "rsvo_crowd_v0"


def test_the_project_points_nowhere_outside_itself():
    """No file of the project refers to the design document or the folder beside it."""
    pattern = r"DESIGN\.md\|" + "shar" + "ed/"  # in two pieces, so that this file does not match
    hits = subprocess.run(
        ["grep", "-rln", pattern, "--include=*.py", "--include=*.md", "."],
        cwd=ROOT,
        capture_output=True,
        text=True,
    ).stdout.split()
    assert [h for h in hits if not h.startswith("./.venv")] == []


def test_reference_solvers_are_quiet(capfd):
    import warnings

    from rsvo_env.filter.safety import FilterConfig, SafetyFilter

    x = [[0.0, 0.0], [1.5, 0.0], [0.0, 1.5]]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")  # osqp 1.x warned of renamed settings here
        for solver in ("osqp", "clarabel", "daqp"):
            flt = SafetyFilter(FilterConfig(solver=solver))
            flt.filter(x, [[3, 0], [-3, 0], [0, -3]], [1, 2, 3])
    out = capfd.readouterr()
    assert out.out == "" and out.err == ""
    assert [str(w.message) for w in caught] == []


def test_committed_gifs_play_at_their_frame_rate():
    from PIL import Image

    for name in ("circular_symmetric.gif", "circular_asymmetric.gif"):
        gif = Image.open(ROOT / "benchmarks" / "results" / name)
        durations = set()
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.add(gif.info["duration"])
        assert durations == {50}, (name, durations)  # 20 frames per second


def test_subprocesses_run_the_checkout_under_test(tmp_path, monkeypatch):
    """A stale ``rsvo_env`` earlier on the path (another install) must not be what the CLI
    tests run: the checkout goes first."""
    stale = tmp_path / "stale" / "rsvo_env"
    stale.mkdir(parents=True)
    (stale / "__init__.py").write_text("raise ImportError('a stale install was imported')\n")
    monkeypatch.setenv("PYTHONPATH", str(stale.parent))
    out = rsvo("--help", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    out = run_python("-c", "import rsvo_env; print(rsvo_env.__file__)", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()).resolve().is_relative_to(ROOT)
