"""Frames, human mode, GIFs and figures."""

import os

import imageio.v2 as imageio
import numpy as np

import rsvo_env
from rsvo_env.cli import main as cli


def test_rgb_array_frames_have_the_documented_shape_and_move():
    env = rsvo_env.parallel_env("circular_swap", render_mode="rgb_array", render_size=300)
    env.reset(seed=0)
    first = env.render()
    assert first.dtype == np.uint8 and first.shape == env.unwrapped.renderer.shape
    assert first.shape == (300, 300, 3)
    for _ in range(30):
        env.step(env.unwrapped.nominal_actions())
    later = env.render()
    assert later.shape == first.shape
    assert np.mean(np.any(later != first, axis=2)) > 0.001  # pixels changed as agents moved
    env.close()


def test_colours_follow_theta():
    from rsvo_env.envs.rendering import theta_colors

    c = theta_colors(np.array([0.0, 1.0, 100.0]))
    assert c[0, 0] > c[2, 0] and c[0, 2] < c[2, 2]  # egoist red, altruist blue
    same = theta_colors(np.array([3.0, 3.0]))
    np.testing.assert_array_equal(same[0], same[1])


def test_human_mode_with_dummy_video_driver():
    assert os.environ.get("SDL_VIDEODRIVER") == "dummy"
    env = rsvo_env.parallel_env("position_swap", render_mode="human")
    env.reset(seed=0)
    for _ in range(5):
        env.step(env.unwrapped.nominal_actions())
    assert env.render() is None
    env.close()


def test_gif_and_figure_by_one_command(tmp_path):
    gif, png = tmp_path / "circular.gif", tmp_path / "circular.png"
    rc = cli.main(
        [
            "simulate",
            "circular_swap",
            "--theta",
            "2",
            "1",
            "2",
            "1",
            "2",
            "1",
            "--gif",
            str(gif),
            "--png",
            str(png),
        ]
    )
    assert rc == 0
    frames = imageio.mimread(gif)
    assert len(frames) > 50
    assert not np.array_equal(frames[0], frames[-1])
    assert png.stat().st_size > 10_000


def test_demo_command(capsys):
    """The demo says what its run shows: the egoist arrives first and swerves less (it once said
    the egoist travels farther; it travelled 8.13 m to the altruist's 8.25 m)."""
    from rsvo_env.cli.demo import head_on_swap

    assert cli.main(["demo"]) == 0
    out = capsys.readouterr().out
    assert "smallest distance kept" in out and "egoist arrives first" in cli_help("demo")
    run = head_on_swap()
    assert run["arrived_0"] < run["arrived_1"]
    assert run["swerve_0"] < run["swerve_1"]
    assert run["min_distance"] >= run["safety_radius"]


def cli_help(command: str) -> str:
    """The command's help text, joined into one line."""
    import contextlib
    import io

    text = io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.suppress(SystemExit):
        cli.main([command, "--help"])
    return " ".join(text.getvalue().split())


def test_trajectory_figures_draw_their_obstacles_and_keep_the_legend_off_the_labels(tmp_path):
    """The doorway's figure drew paths bending round nothing, its legend covered the x label and
    its colour bar spanned 0-2 when every theta is 1."""
    import matplotlib.pyplot as plt

    from rsvo_env.cli.episode import run
    from rsvo_env.cli.figures import episode
    from rsvo_env.envs.rendering import OBSTACLE_GREY

    for scenario, kwargs in (("doorway", {}), ("obstacle_field", {"max_steps": 60})):
        out = run(scenario, **kwargs)
        fig = episode(out, scenario, "asymmetric")
        fig.savefig(tmp_path / f"{scenario}.png")
        ax = fig.axes[0]
        grey = [p for p in ax.patches if p.get_facecolor()[:3] == OBSTACLE_GREY]
        assert len(grey) >= len(out["obstacles"]) > 0
        renderer = fig.canvas.get_renderer()
        legend = fig.legends[0].get_window_extent(renderer)
        label = ax.xaxis.label.get_window_extent(renderer)
        assert not legend.overlaps(label)
        assert len(fig.axes) == 1  # every theta is 1: no colour bar to span a made-up range
        plt.close(fig)
