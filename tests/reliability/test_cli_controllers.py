"""Which scripted controller each command runs, as docs/cli.md and ``--help`` say: ``rsvo simulate``
the scenario's own (``--nominal`` chooses), ``rsvo reproduce`` the paper's."""

from pathlib import Path

import pytest

from rsvo_env.cli import main as rsvo


def metrics(capsys, args):
    assert rsvo.main(["simulate", "circular_swap", "--theta", *"212121", *args]) == 0
    out = capsys.readouterr().out
    wanted = ("deadlock_onset", "deadlock_resolved", "completed")
    rows = [line.split(":") for line in out.splitlines()]
    return [int(value) for key, value, *_ in rows if key.strip() in wanted]


def test_simulate_runs_the_scenarios_controller_and_nominal_chooses(capsys):
    """docs/cli.md's numbers: the paper's controller 138 / 278 / 489 (what reproduce reports),
    R-ORCA, the circular swap's own, 154 / 286 / 486."""
    assert metrics(capsys, ["--nominal", "move_to_goal"]) == [138, 278, 489]
    assert metrics(capsys, []) == [154, 286, 486]
    assert metrics(capsys, ["--nominal", "rorca"]) == [154, 286, 486]
    doc = " ".join((Path(__file__).parents[2] / "docs" / "cli.md").read_text().split())
    assert "138 / 278 / 489" in doc and "154 / 286 / 486" in doc


def test_simulate_refuses_a_controller_the_model_cannot_take(capsys):
    assert rsvo.main(["simulate", "ramp_merge", "--nominal", "rorca"]) == 2
    assert "ramp_merge.nominal = 'rorca'" in capsys.readouterr().err


@pytest.mark.parametrize("command", ["simulate", "reproduce"])
def test_help_says_its_description_once(capsys, command):
    with pytest.raises(SystemExit):
        rsvo.main([command, "--help"])
    out = capsys.readouterr().out
    first = out.split("\n\n")[1].split(":", 1)[1].split()[:6]  # past the command's name
    assert out.count(" ".join(first)) == 1


SCENE = """# two groups cross a wall's gap, double integrators
starts: [[-6, -1.5], [-6, 1.5], [6, -1.5], [6, 1.5]]
goals: [[6, 1.5], [6, -1.5], [-6, 1.5], [-6, -1.5]]
radii: [0.4, 0.4, 0.5, 0.5]
walls: [[[0, 2], [0, 8]], [[0, -2], [0, -8]]]
circles: [[3, 5, 1.0]]
dynamics: double_integrator
a_max: 2.0
dt: 0.05
gamma: 1e1
"""


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_simulate_custom_takes_a_scene_file(tmp_path, capsys, suffix):
    import json

    import yaml

    path = tmp_path / f"scene{suffix}"
    scene = yaml.safe_load(SCENE) | {"gamma": 10.0}
    path.write_text(SCENE if suffix == ".yaml" else json.dumps(scene))
    png = tmp_path / "custom.png"
    assert rsvo.main(["simulate", "custom", "--scene", str(path), "--png", str(png)]) == 0
    out = capsys.readouterr().out
    assert "success: True" in out and "n_collision_steps: 0" in out and png.exists()


@pytest.mark.parametrize(
    "args, text, words",
    [
        (["simulate", "custom"], None, ["--scene FILE goes with the custom scenario"]),
        (["simulate", "crowd", "--scene", "{f}"], SCENE, ["--scene FILE goes with the custom"]),
        (["simulate", "custom", "--scene", "{f}"], "[1, 2]", ["expected a mapping"]),
        (["simulate", "custom", "--scene", "{f}"], "starts: [[0, 0], [0.5, 0]]\ngoals: "
         "[[5, 0], [0, 5]]\n", ["overlap"]),
        (["simulate", "custom", "--scene", "{f}"], SCENE + "dynamics: warp\n", ["dynamics"]),
        (["simulate", "custom", "--scene", "{f}"], "starts: [[0, 0]\n", ["not valid YAML"]),
        (["simulate", "custom", "--scene", "{f}", "--nominal", "rorca"], SCENE + "nominal: rorca\n",
         ["given twice"]),
    ],
)  # fmt: skip
def test_a_bad_scene_file_is_one_error_line(tmp_path, capsys, args, text, words):
    path = tmp_path / "scene.yaml"
    if text is not None:
        path.write_text(text)
    assert rsvo.main([a.format(f=path) for a in args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(w in err[0] for w in words), err
