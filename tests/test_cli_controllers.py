"""Which scripted controller each command runs, as README and ``--help`` say: ``rsvo simulate``
the scenario's own (``--nominal`` chooses), ``rsvo reproduce`` the paper's."""

import pytest

from rsvo_env.cli import main as rsvo


def metrics(capsys, args):
    assert rsvo.main(["simulate", "circular_swap", "--theta", *"212121", *args]) == 0
    out = capsys.readouterr().out
    wanted = ("deadlock_onset", "deadlock_resolved", "completed")
    rows = [line.split(":") for line in out.splitlines()]
    return [int(value) for key, value, *_ in rows if key.strip() in wanted]


def test_simulate_runs_the_scenarios_controller_and_nominal_chooses(capsys):
    """README's numbers: the paper's controller 138 / 278 / 489 (what reproduce reports),
    R-ORCA, the circular swap's own, 216 / 297 / 505."""
    assert metrics(capsys, ["--nominal", "move_to_goal"]) == [138, 278, 489]
    assert metrics(capsys, []) == [216, 297, 505]
    assert metrics(capsys, ["--nominal", "rorca"]) == [216, 297, 505]


def test_simulate_refuses_a_controller_the_model_cannot_take(capsys):
    assert rsvo.main(["simulate", "ramp_merge", "--nominal", "rorca"]) == 2
    assert "not controlled by its velocity" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["simulate", "reproduce"])
def test_help_says_its_description_once(capsys, command):
    with pytest.raises(SystemExit):
        rsvo.main([command, "--help"])
    out = capsys.readouterr().out
    first = out.split("\n\n")[1].split(":", 1)[1].split()[:6]  # past the command's name
    assert out.count(" ".join(first)) == 1
