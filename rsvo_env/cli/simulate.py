"""rsvo simulate: run one scenario with its scripted controller behind the R-CBF filter, print
its episode metrics, and optionally write an animated GIF and a trajectory figure.

The controller is the scenario's own (--nominal default): R-ORCA for the circular swap, the
crowd, the doorway and the obstacle field; move-to-goal with the right-hand rule, the paper's,
for the rest. `rsvo reproduce` runs the paper's controller everywhere: give --nominal
move_to_goal here to see its numbers.

example: rsvo simulate circular_swap --theta 2 1 2 1 2 1 --gif circular.gif --png circular.png
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import rsvo_env
from rsvo_env import control, dynamics
from rsvo_env.cli.episode import run
from rsvo_env.util.arguments import (
    HelpFormatter,
    Parser,
    UserError,
    check_output,
    count,
    user_input,
)
from rsvo_env.util.scene_file import read_scene
from rsvo_env.util.validation import check_flag, check_seed

# the run's own settings a scene file may hold too, and the flag that sets each
RUN_FLAGS = {
    "theta": "--theta",
    "weighting": "--weighting",
    "seed": "--seed",
    "safety_filter": "--no-filter",
}


def run_settings(args: argparse.Namespace, scene: dict[str, Any]) -> dict[str, Any]:
    """The run's settings (``RUN_FLAGS``) from the command line or the scene file, each taken
    out of ``scene``; one given in both is refused, and a scene file's values are checked as
    the flags' are (``UserError`` naming the field)."""
    flags = {
        "theta": args.theta,
        "weighting": getattr(args, "weighting", None),
        "seed": getattr(args, "seed", None),
        "safety_filter": False if args.no_filter else None,
    }
    for key, flag in RUN_FLAGS.items():
        if key in scene:
            if flags[key] is not None:
                raise UserError(f"{key} is given twice: {flag} and the scene file's {key}")
            flags[key] = scene.pop(key)
    with user_input():
        seed = check_seed(0 if flags["seed"] is None else flags["seed"], "seed")
        safety_filter = check_flag(
            True if flags["safety_filter"] is None else flags["safety_filter"], "safety_filter"
        )
    weighting = "asymmetric" if flags["weighting"] is None else flags["weighting"]
    return {
        "theta": flags["theta"],
        "weighting": weighting,
        "seed": seed,
        "safety_filter": safety_filter,
    }


def main(argv: list[str] | None = None) -> int:
    ap = Parser(
        prog="rsvo simulate",
        description=__doc__,
        formatter_class=HelpFormatter,
    )
    ap.add_argument(
        "scenario",
        nargs="?",
        default="circular_swap",
        choices=sorted(rsvo_env.SCENARIOS),
        help="which scenario (custom: give --scene)",
    )
    ap.add_argument("--no-filter", action="store_true", help="run without the safety filter")
    ap.add_argument(
        "--weighting",
        default=argparse.SUPPRESS,
        choices=["asymmetric", "symmetric"],
        help="asymmetric: the paper's R-SVO weights; symmetric: 0.5 for every pair "
        "(default: asymmetric)",
    )
    ap.add_argument(
        "--nominal",
        choices=control.names(),
        help="the scripted controller (default: the scenario's own, see above)",
    )
    ap.add_argument("--theta", type=float, nargs="+", help="personality scores >= 0, one per agent")
    ap.add_argument(
        "--scene",
        type=Path,
        help="custom: your scene, a YAML or JSON mapping of its keywords (starts, goals, radii, "
        "circles, walls, thickness, dynamics, u_max, a_max, ...; docs/scenarios.md)",
    )
    ap.add_argument(
        "--seed", type=count(0), default=argparse.SUPPRESS, help="seed of the episode (default: 0)"
    )
    ap.add_argument(
        "--dynamics",
        choices=dynamics.NAMES,
        help="the agents' model, in the scenes that take one (default: the scene's)",
    )
    ap.add_argument(
        "--num-agents",
        type=count(2),
        metavar="N",
        help="how many agents, in the scenes laid out for any number (default: the scene's)",
    )
    ap.add_argument(
        "--max-steps",
        type=count(1),
        metavar="STEPS",
        help="the episode's step cap (default: the scene's)",
    )
    ap.add_argument("--gif", type=Path, help="write an animated GIF here (.gif)")
    ap.add_argument("--png", type=Path, help="write a trajectory figure here (.png)")
    args = ap.parse_args(argv)
    # formats and folders are checked before any work
    check_output(args.gif, ".gif")
    check_output(args.png, ".png")
    scene: dict[str, Any] = {}
    if (args.scene is None) != (args.scenario != "custom"):
        raise UserError("--scene FILE goes with the custom scenario (and custom needs one)")
    if args.scene is not None:
        with user_input():
            scene = read_scene(args.scene)
    # the scene's own keywords given by flag, each at most once
    for key, flag in (
        ("nominal", "--nominal"),
        ("dynamics", "--dynamics"),
        ("num_agents", "--num-agents"),
        ("max_steps", "--max-steps"),
    ):
        value = getattr(args, key)
        if value is not None:
            if key in scene:
                raise UserError(f"{key} is given twice: {flag} and the scene file's {key}")
            scene[key] = value
    out = run(args.scenario, gif=args.gif, **run_settings(args, scene), **scene)
    for key in (
        "steps",
        "success",
        "deadlock_onset",
        "deadlock_resolved",
        "completed",
        "min_distance",
        "n_collision_steps",
        "n_infeasible",
    ):
        print(f"{key:>18}: {out[key]}")
    if args.gif:
        print(f"{'gif':>18}: {out['gif']}")
    if args.png:
        import matplotlib.pyplot as plt

        from rsvo_env.cli.figures import episode

        fig = episode(out, args.scenario, out["weighting"], filtered=out["filtered"])
        fig.savefig(args.png, dpi=120, bbox_inches="tight")
        plt.close(fig)
        print(f"{'png':>18}: {args.png}")
    return 0 if out["n_collision_steps"] == 0 or not out["filtered"] else 1
