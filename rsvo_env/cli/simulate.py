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
from rsvo_env.cli.arguments import Parser, UserError, check_output, count, user_input
from rsvo_env.cli.episode import run
from rsvo_env.cli.scene_file import read_scene
from rsvo_env.scenarios.base import NOMINALS


class HelpFormatter(argparse.RawDescriptionHelpFormatter, argparse.ArgumentDefaultsHelpFormatter):
    """Keeps the description's lines and shows every default."""


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
        default="asymmetric",
        choices=["asymmetric", "symmetric"],
        help="asymmetric: the paper's R-SVO weights; symmetric: 0.5 for every pair",
    )
    ap.add_argument(
        "--nominal",
        choices=NOMINALS,
        help="the scripted controller (default: the scenario's own, see above)",
    )
    ap.add_argument("--theta", type=float, nargs="+", help="personality scores >= 0, one per agent")
    ap.add_argument(
        "--scene",
        type=Path,
        help="custom: your scene, a YAML or JSON mapping of its keywords (starts, goals, radii, "
        "circles, walls, thickness, dynamics, u_max, a_max, ...; docs/scenarios.md)",
    )
    ap.add_argument("--seed", type=count(0), default=0, help="seed of the episode")
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
        if "nominal" in scene and args.nominal is not None:
            raise UserError("the controller is given twice: --nominal and the scene's nominal")
    out = run(
        args.scenario,
        safety_filter=not args.no_filter,
        weighting=args.weighting,
        theta=args.theta,
        seed=args.seed,
        gif=args.gif,
        **({} if args.nominal is None else {"nominal": args.nominal}),
        **scene,
    )
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

        fig = episode(out, args.scenario, args.weighting, filtered=not args.no_filter)
        fig.savefig(args.png, dpi=120, bbox_inches="tight")
        plt.close(fig)
        print(f"{'png':>18}: {args.png}")
    return 0 if out["n_collision_steps"] == 0 or args.no_filter else 1
