"""GIFs of the scenes with walls and obstacles, under the scripted controller behind the filter:
``benchmarks/results/doorway.gif`` and ``benchmarks/results/obstacle_field.gif``.

Egoists (red, theta 0.5) and altruists (blue, theta 4) alternate, so the picture shows who
yields at the bottleneck. Run from a checkout: ``python -m benchmarks.tools.scene_gifs``.
"""

from __future__ import annotations

from benchmarks.harness import RESULTS
from rsvo_env.cli.episode import run

SCENES = {
    "doorway": [0.5, 4.0, 0.5, 4.0, 4.0, 0.5, 4.0, 0.5],
    "obstacle_field": [0.5, 4.0] * 5,
}


def main() -> None:
    for scenario, theta in SCENES.items():
        path = RESULTS / f"{scenario}.gif"
        out = run(scenario, theta=theta, gif=path, gif_every=10, render_size=400)
        print(
            f"{scenario}: completed at step {out['completed']}, "
            f"{out['n_collision_steps']} collision steps -> {path}"
        )


if __name__ == "__main__":
    main()
