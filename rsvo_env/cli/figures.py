"""The reproduction's figures, drawn from the studies' data (matplotlib, headless)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from rsvo_env.cli.studies import defaults
from rsvo_env.cli.studies.position_swap import RADII, WEIGHTS
from rsvo_env.cli.studies.ramp_merge import CASES
from rsvo_env.envs.rendering import marker_handles, plot_trajectories, role


def position_swap(runs: dict, path: Path) -> None:
    """Fig. 3: trajectories of each radius (rows) and weight split (columns)."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import LinearSegmentedColormap, Normalize

    from rsvo_env.envs.rendering import ALTRUIST, EGOIST

    fig, axes = plt.subplots(2, 3, figsize=(13, 9), layout="constrained")
    for (R, w1), out in runs.items():
        ax = axes[RADII.index(R), WEIGHTS.index(w1)]
        onset = out["deadlock_onset"]
        plot_trajectories(
            out["trajectory"],
            out["goals"],
            out["theta"],
            R,
            ax=ax,
            marks=[onset] if onset else [],
            legend="agents",
            colorbar=False,
            title=f"R_safe {R:g}, omega_1 / omega_2 = {w1:.1f} / {1 - w1:.1f}"
            + (f"\nthey meet at step {onset}" if onset else ""),
        )
    cmap = LinearSegmentedColormap.from_list("theta", [EGOIST / 255.0, ALTRUIST / 255.0])
    bar = fig.colorbar(plt.cm.ScalarMappable(Normalize(0, 1), cmap), ax=axes, shrink=0.6)
    bar.set_ticks(
        [0, 1], labels=["egoist\n(smaller theta,\nlarger omega)", "altruist\n(larger theta)"]
    )
    fig.suptitle("position_swap, asymmetric weighting, filter on (paper Fig. 3)")
    fig.legend(
        handles=marker_handles(["positions when the agents meet (the right-hand rule fires)"]),
        loc="outside lower center",
        ncol=5,
        fontsize=8,
    )
    fig.savefig(path, dpi=100, bbox_inches="tight")
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
                label=f"V{i + 1} ({'left' if i == 0 else 'right'} lane), "
                f"theta {out['theta'][i]:g}{role(out['theta'], i)}",
            )
        ax.axhline(merge_y, color="grey", lw=0.8, label="merge point")
        ax.set_title(f"{split} split, {case}", fontsize=9)
        ax.set_xlabel("t [s]")
        ax.legend(fontsize=7)
    for ax in axes[:, 0]:
        ax.set_ylabel(f"y [m] (merge at {merge_y:g})")
    fig.suptitle("ramp_merge: position along the road over time, braking barrier (paper Fig. 4)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def event_marks(out: dict) -> tuple[list[int], list[str]]:
    """The steps of deadlock onset and resolution that happened, and their legend labels."""
    marks, labels = [], []
    for key, text in (("deadlock_onset", "deadlock onset"), ("deadlock_resolved", "resolved")):
        if out[key]:
            marks.append(out[key])
            labels.append(f"positions at {text} (step {out[key]})")
    return marks, labels


def episode(
    out: dict, scenario: str, weighting: str, filtered: bool = True, legend: bool | str = True
) -> Any:
    """One episode's trajectories, its events marked, titled with scenario, theta, weighting
    and filter (``rsvo simulate --png`` and the circular figures); ``legend`` as
    ``rendering.plot_trajectories``' (``"markers"``: a picture shown small, its title short)."""
    marks, labels = event_marks(out)
    if legend == "markers":
        return plot_trajectories(out["trajectory"], out["goals"], out["theta"],
                                 out["safety_radius"], marks=marks, mark_labels=labels,
                                 title=f"{scenario}, {weighting} weighting, "
                                 + ("filter on" if filtered else "no filter"),
                                 obstacles=out.get("obstacles"), legend="markers")  # fmt: skip
    theta = ", ".join(f"{t:g}" for t in out["theta"])
    return plot_trajectories(
        out["trajectory"],
        out["goals"],
        out["theta"],
        out["safety_radius"],
        marks=marks,
        mark_labels=labels,
        title=f"{scenario}, theta = ({theta}), {weighting} weighting, "
        + ("filter on" if filtered else "no filter"),
        obstacles=out.get("obstacles"),
    )


def circular(data: dict, out_dir: Path) -> list[Path]:
    """Figs. 5-7: both trajectories, and the average minimum distance over time."""
    import matplotlib.pyplot as plt

    written = []
    for name in ("sym", "asym"):
        weighting = {"sym": "symmetric", "asym": "asymmetric"}[name]
        fig = episode(data[name], "circular_swap", weighting)
        written.append(out_dir / f"circular_{weighting}.png")
        fig.savefig(written[-1], dpi=100, bbox_inches="tight")
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
    ax.set_title(
        "circular_swap: average distance to the nearest neighbour (paper Fig. 7)", fontsize=9
    )
    fig.tight_layout()
    written.append(out_dir / "avg_min_distance.png")
    fig.savefig(written[-1], dpi=100)
    plt.close(fig)
    return written
