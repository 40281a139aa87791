"""``rsvo simulate``: run a scenario with the scripted controller, print its metrics, and
optionally write a GIF and a trajectory figure.

    rsvo simulate circular_swap --theta 2 1 2 1 2 1 --gif out/circular.gif --png out/circular.png
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

import rsvo_env
from rsvo_env.rendering import plot_trajectories, save_gif


def run(
    scenario: str = "circular_swap",
    safety_filter: bool = True,
    weighting: str = "asymmetric",
    theta: list[float] | None = None,
    seed: int = 0,
    gif: str | Path | None = None,
    gif_every: int = 5,
    render_size: int = 400,
    **kwargs: Any,
) -> dict[str, Any]:
    """One episode under the scripted nominal controller; returns the episode metrics plus the
    trajectory (T+1, N, 2), theta and goals."""
    from wrappers import RCBFSafetyFilter  # the cli is the top floor: it may use wrappers

    env = rsvo_env.parallel_env(
        scenario,
        render_mode="rgb_array" if gif else None,
        weighting=weighting,
        render_size=render_size,
        **kwargs,
    )
    if safety_filter:
        env = RCBFSafetyFilter(env)
    options = {"theta": theta} if theta is not None else None
    env.reset(seed=seed, options=options)
    base = env.unwrapped
    frames = [env.render()] if gif else []
    while env.agents:
        env.step(base.nominal_actions())
        if gif and (base.metrics.steps % gif_every == 0 or not env.agents):
            frames.append(env.render())
    out = dict(base.episode_metrics)
    out["trajectory"] = np.stack(base.history)
    out["theta"] = base.world.theta.copy()
    out["goals"] = base.world.goals.copy()
    out["safety_radius"] = base.world.safety_radius
    if gif:
        fps = max(1, int(round(1.0 / (base.dt * gif_every))))
        out["gif"] = save_gif(frames, gif, fps=min(fps, 50))
    env.close()
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        prog="rsvo simulate",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ap.add_argument(
        "scenario", nargs="?", default="circular_swap", choices=sorted(rsvo_env.SCENARIOS)
    )
    ap.add_argument("--no-filter", action="store_true", help="run without the safety filter")
    ap.add_argument("--weighting", default="asymmetric", choices=["asymmetric", "symmetric"])
    ap.add_argument("--theta", type=float, nargs="+", help="personality scores, one per agent")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--gif", type=Path, help="write an animated GIF here")
    ap.add_argument("--png", type=Path, help="write a trajectory figure here")
    args = ap.parse_args(argv)
    out = run(
        args.scenario,
        safety_filter=not args.no_filter,
        weighting=args.weighting,
        theta=args.theta,
        seed=args.seed,
        gif=args.gif,
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

        fig = plot_trajectories(
            out["trajectory"], out["goals"], out["theta"], out["safety_radius"], title=args.scenario
        )
        args.png.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(args.png, dpi=120, bbox_inches="tight")
        plt.close(fig)
        print(f"{'png':>18}: {args.png}")
    return 0 if out["n_collision_steps"] == 0 or args.no_filter else 1
