"""Every refusal is a bounded message: no error message is longer than 500 characters for any
input (a million numbers, a megabyte string, nested lists that share their parts, an object
whose repr is huge), through every scenario keyword, the filter's config and call, the envs'
reset and step, and the command line's scene files and flags."""

import numpy as np
import pytest

import rsvo_env
from rsvo_env import FilterConfig, SafetyFilter
from rsvo_env.cli import main as rsvo
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.scenarios.registry import SCENARIOS
from rsvo_env.util.validation import shown

LIMIT = 500


class HugeRepr:
    def __repr__(self) -> str:
        return "x" * 10**6


def shared_bomb(levels: int = 6, width: int = 10) -> list:
    """``width ** levels`` numbers, held in ``levels`` lists that each repeat the one below
    (what YAML's aliases build)."""
    part: list = list(range(width))
    for _ in range(levels - 1):
        part = [part] * width
    return part


BAD_VALUES = {
    "million numbers": list(range(10**6)),
    "megabyte string": "s" * 10**6,
    "nested shared lists": shared_bomb(),
    "huge repr": HugeRepr(),
    "huge array": np.full((1000, 1000), np.nan),
    "complex array": np.ones(10**5) * 1j,
}


def refusal(call) -> str:
    with pytest.raises((ValueError, TypeError)) as err:
        call()
    return str(err.value)


def test_shown_is_bounded_and_exact_for_short_values():
    for value in BAD_VALUES.values():
        assert len(shown(value)) <= 120
    for value in (1.5, "crowd", [1, 2, 3], (0.5, 2.0), None, True, np.float64(2.5)):
        assert shown(value) == repr(value)


@pytest.mark.parametrize("scenario", sorted(SCENARIOS))
@pytest.mark.parametrize("kind", sorted(BAD_VALUES))
def test_every_scenario_keyword_refuses_in_a_bounded_message(scenario, kind):
    custom = ("starts", "goals", "radii", "circles", "walls", "u_max", "dt", "theta")
    keys = sorted(SCENARIOS[scenario]().all_defaults() if scenario != "custom" else custom)
    base = {"starts": [[0.0, 0.0], [4.0, 0.0]], "goals": [[4.0, 0.0], [0.0, 0.0]]}
    for key in keys:
        kwargs = {**(base if scenario == "custom" else {}), key: BAD_VALUES[kind]}
        message = refusal(lambda kw=kwargs: rsvo_env.parallel_env(scenario, **kw).reset(seed=0))
        assert len(message) <= LIMIT, (key, len(message), message[:200])


@pytest.mark.parametrize("kind", sorted(BAD_VALUES))
def test_the_filter_and_the_envs_refuse_in_bounded_messages(kind):
    bad = BAD_VALUES[kind]
    messages = []
    for field in (
        "gamma",
        "safety_radius",
        "u_max",
        "dt",
        "dynamics",
        "weighting",
        "solver",
        "barrier",
        "neighbor_radius",
    ):
        messages.append(refusal(lambda f=field: FilterConfig(**{f: bad})))
    flt = SafetyFilter(FilterConfig())
    x, u, theta = np.zeros((3, 2)) + [[0, 0], [5, 0], [0, 5]], np.zeros((3, 2)), np.ones(3)
    messages.append(refusal(lambda: flt.filter(bad, u, theta)))
    messages.append(refusal(lambda: flt.filter(x, bad, theta)))
    messages.append(refusal(lambda: flt.filter(x, u, bad)))
    env = rsvo_env.parallel_env("circular_swap")
    messages.append(refusal(lambda: env.reset(seed=0, options={"theta": bad})))
    env.reset(seed=0)
    messages.append(refusal(lambda: env.step({a: bad for a in env.agents})))
    messages.append(refusal(lambda: env.step({"x" * 10**5: np.zeros(2)})))
    venv = BatchedEnv("crowd", num_envs=2, num_agents=4)
    venv.reset(seed=0)
    messages.append(refusal(lambda: venv.step(bad)))
    messages.append(refusal(lambda: BatchedEnv("crowd", num_envs=bad)))
    for message in messages:
        assert len(message) <= LIMIT, (len(message), message[:200])


@pytest.mark.parametrize("text", [
    "starts: " + "[" * 5000 + "]" * 5000 + "\ngoals: [[1, 1]]\n",
    "starts: [[0, 0], [4, 0]]\ngoals: [[4, 0], [0, 0]]\nu_max: '" + "s" * 10**5 + "'\n",
    "starts: [" + ", ".join(["[0, 0]"] * 20000) + "]\ngoals: [[1, 1]]\n",
    "starts: [[0, 0], [4, 0]]\ngoals: [[4, 0], [0, 0]]\n" + "x" * 10**5 + ": 1\n",
    "starts: [[0, 0], [4, 0]]\ngoals: [[4, 0], [0, 0]]\ndt: [" + ", ".join(["1.5"] * 10**5) + "]\n",
])  # fmt: skip
def test_scene_files_are_refused_in_one_bounded_line(tmp_path, capsys, text):
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    try:
        code = rsvo.main(["simulate", "custom", "--scene", str(path)])
    except SystemExit as exit_:
        code = exit_.code
    assert code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and len(lines[0]) <= LIMIT + 40, lines[0][:300]
