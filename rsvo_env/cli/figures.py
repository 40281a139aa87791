"""The reproduction's figures, drawn from the studies' data (matplotlib, headless)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from rsvo_env.cli.studies import defaults
from rsvo_env.cli.studies.position_swap import RADII, WEIGHTS
from rsvo_env.cli.studies.ramp_merge import CASES
from rsvo_env.rendering import plot_trajectories


def position_swap(runs: dict, path: Path) -> None:
    """Fig. 3: trajectories of each radius (rows) and weight split (columns)."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(12, 8))
    for (R, w1), out in runs.items():
        ax = axes[RADII.index(R), WEIGHTS.index(w1)]
        marks = [out["deadlock_onset"]] if out["deadlock_onset"] else []
        plot_trajectories(
            out["trajectory"],
            out["goals"],
            out["theta"],
            R,
            ax=ax,
            marks=marks,
            title=f"R_safe = {R:g}, omega = {w1:.1f} / {1 - w1:.1f}",
        )
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def ramp_merge(runs: dict, path: Path) -> None:
    """Fig. 4: each vehicle's progress along y over time, per split and theta case."""
    import matplotlib.pyplot as plt

    p = defaults("ramp_merge")
    merge_y = p["merge_point"][1]
    fig, axes = plt.subplots(2, 3, figsize=(12, 7), sharey=True)
    for (split, case), out in runs.items():
        ax = axes[0 if split == "capability" else 1, list(CASES).index(case)]
        traj = out["trajectory"]
        for i, style in ((0, "-"), (1, "--")):
            ax.plot(
                np.arange(len(traj)) * p["dt"],
                traj[:, i, 1],
                style,
                label=f"V{i + 1} (theta {out['theta'][i]:g})",
            )
        ax.axhline(merge_y, color="grey", lw=0.8)
        ax.set_title(f"{split} split, {case}", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=7)
    for ax in axes[:, 0]:
        ax.set_ylabel(f"y [m] (merge at {merge_y:g})")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def circular(data: dict, out_dir: Path) -> None:
    """Figs. 5-7: both trajectories, and the average minimum distance over time."""
    import matplotlib.pyplot as plt

    for name in ("sym", "asym"):
        out = data[name]
        marks = [m for m in (out["deadlock_onset"], out["deadlock_resolved"]) if m]
        title = {"sym": "symmetric", "asym": "asymmetric"}[name]
        fig = plot_trajectories(
            out["trajectory"],
            out["goals"],
            out["theta"],
            out["safety_radius"],
            marks=marks,
            title=f"{title}, theta = (2,1,2,1,2,1)",
        )
        fig.savefig(out_dir / f"circular_{title}.png", dpi=100, bbox_inches="tight")
        plt.close(fig)
    fig, ax = plt.subplots(figsize=(7, 4))
    t = np.arange(1, len(data["sym"]["avg_min_distance_series"]) + 1)
    ax.plot(t, data["sym"]["avg_min_distance_series"], label="symmetric")
    series = [o["avg_min_distance_series"] for o in data["random"]]
    longest = max(len(s) for s in series)
    padded = np.array([np.pad(s, (0, longest - len(s)), mode="edge") for s in series])
    ax.plot(
        np.arange(1, longest + 1),
        padded.mean(axis=0),
        label=f"asymmetric, mean of {len(series)} random theta sets",
    )
    ax.plot(
        np.arange(1, len(data["asym"]["avg_min_distance_series"]) + 1),
        data["asym"]["avg_min_distance_series"],
        "--",
        label="asymmetric, (2,1,2,1,2,1)",
    )
    ax.axhline(data["sym"]["safety_radius"], color="grey", lw=0.8, label="R_safe")
    ax.set_xlabel("step")
    ax.set_ylabel("average minimum distance D [m]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "avg_min_distance.png", dpi=100)
    plt.close(fig)
