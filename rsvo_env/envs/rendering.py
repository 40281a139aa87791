"""Pictures: pygame frames (``rgb_array`` headless, ``human`` in a window), GIFs, and matplotlib
figures of trajectories like the paper's."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

# Steps of trajectory drawn behind each agent (and all an env keeps by default).
TRAIL = 400
EGOIST = np.array([220, 60, 40])
ALTRUIST = np.array([40, 90, 220])
BACKGROUND = (250, 250, 248)


def theta_scale(theta: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each agent's place in [0, 1] between the group's most egoistic (smallest theta, 0) and
    most altruistic (1) member; equal scores are all 0.5."""
    lo, hi = float(np.min(theta)), float(np.max(theta))
    return np.full(len(theta), 0.5) if hi <= lo else (np.asarray(theta) - lo) / (hi - lo)


def theta_colors(theta: NDArray[np.float64]) -> NDArray[np.uint8]:
    """One RGB colour per agent, from egoist (red, smallest theta) to altruist (blue)."""
    share = theta_scale(theta)
    return np.round(EGOIST + (ALTRUIST - EGOIST) * share[:, None]).astype(np.uint8)


def role(theta: NDArray[np.float64], i: int) -> str:
    """' (egoist)' for the group's smallest theta, ' (altruist)' for its largest, else ''."""
    lo, hi = float(np.min(theta)), float(np.max(theta))
    if hi <= lo:
        return ""
    return " (egoist)" if theta[i] == lo else " (altruist)" if theta[i] == hi else ""


class Renderer:
    """Draws a world onto a pygame surface; a window only in ``human`` mode."""

    def __init__(
        self,
        arena: tuple[NDArray, NDArray],
        mode: str,
        size: int = 600,
        fps: int = 50,
        trail: int = TRAIL,
        lanes: Sequence[NDArray] = (),
        caption: str = "",
    ) -> None:
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame

        self.pygame = pygame
        self.mode = mode
        lo, hi = (np.asarray(a, dtype=np.float64) for a in arena)
        # a narrow arena (the ramp merge) is widened so that the captions fit beside it
        span = hi - lo
        grow = np.maximum(0.6 * span[::-1] - span, 0.0) / 2
        lo, hi = lo - grow, hi + grow
        span = hi - lo
        self.scale = size / float(span.max())
        self.width = int(np.ceil(span[0] * self.scale))
        self.height = int(np.ceil(span[1] * self.scale))
        self.lo, self.fps, self.trail = lo, fps, trail
        self.lanes = [self.to_screen(np.asarray(line, dtype=np.float64)) for line in lanes]
        self.caption = caption
        pygame.font.init()
        self.font = pygame.font.Font(None, max(16, max(self.width, self.height) // 24))
        self.surface = pygame.Surface((self.width, self.height))
        self.window = None
        self.clock = None
        if mode == "human":
            pygame.display.init()
            self.window = pygame.display.set_mode((self.width, self.height))
            pygame.display.set_caption("rsvo-env")
            self.clock = pygame.time.Clock()

    @property
    def shape(self) -> tuple[int, int, int]:
        """The (height, width, 3) shape of an ``rgb_array`` frame."""
        return self.height, self.width, 3

    def to_screen(self, xy: NDArray) -> NDArray:
        s = (np.asarray(xy) - self.lo) * self.scale
        return np.stack([s[..., 0], self.height - s[..., 1]], axis=-1)

    def draw(
        self,
        positions: NDArray,
        goals: NDArray,
        theta: NDArray,
        radii: NDArray,
        history: Sequence[NDArray] = (),
        time: float | None = None,
        obstacles: NDArray | None = None,
        headings: NDArray | None = None,
    ) -> None:
        """Lanes, obstacles (grey, true size), trails, goals (crosses) and agents (each body its
        true radius, theta colour) at ``time``. ``radii`` (N,) body radii; ``obstacles`` (O, 5)
        capsules; ``headings`` (N,): a unicycle's heading, drawn as a tick from its centre."""
        pg = self.pygame
        surf = self.surface
        surf.fill(BACKGROUND)
        for line in self.lanes:
            pg.draw.lines(surf, (180, 180, 180), False, line, 3)
        for cap in () if obstacles is None else obstacles:
            self._capsule(cap)
        colors = theta_colors(theta)
        body_px = np.maximum(2, np.round(np.broadcast_to(radii, theta.shape) * self.scale))
        if len(history) > 1:
            trail = self.to_screen(np.stack(list(history)[-self.trail :]))
            for i in range(positions.shape[0]):
                pg.draw.lines(surf, tuple(int(c) for c in colors[i]), False, trail[:, i], 1)
        for i, g in enumerate(self.to_screen(goals)):
            c = tuple(int(v) for v in colors[i])
            x, y = int(g[0]), int(g[1])
            pg.draw.line(surf, c, (x - 5, y - 5), (x + 5, y + 5), 2)
            pg.draw.line(surf, c, (x - 5, y + 5), (x + 5, y - 5), 2)
        for i, p in enumerate(self.to_screen(positions)):
            c = tuple(int(v) for v in colors[i])
            r_px = int(body_px[i])
            halo = pg.Surface((2 * r_px + 2, 2 * r_px + 2), pg.SRCALPHA)
            pg.draw.circle(halo, (*c, 70), (r_px + 1, r_px + 1), r_px)
            surf.blit(halo, (int(p[0]) - r_px - 1, int(p[1]) - r_px - 1))
            pg.draw.circle(surf, c, (int(p[0]), int(p[1])), r_px, 2)  # the body, its radius
            pg.draw.circle(surf, c, (int(p[0]), int(p[1])), max(2, r_px // 4))
            if headings is not None:
                tip = p + r_px * np.array([np.cos(headings[i]), -np.sin(headings[i])])
                pg.draw.line(surf, c, (int(p[0]), int(p[1])), (int(tip[0]), int(tip[1])), 2)
        # short lines, so that narrow arenas (the ramp merge) show them whole
        top = ([] if time is None else [f"t = {time:.2f} s"]) + self.caption.split(", ")
        for k, text in enumerate(t for t in top if t):
            label = self.font.render(text, True, (40, 40, 40))
            surf.blit(label, (6, 4 + k * self.font.get_linesize()))
        key = ["x: goal", "blue: altruist", "red: egoist (small theta)"]
        for k, text in enumerate(key):
            label = self.font.render(text, True, (90, 90, 90))
            surf.blit(label, (6, self.height - (k + 1) * self.font.get_linesize() - 4))

    def _capsule(self, cap: NDArray) -> None:
        """One obstacle: a disc (a circle) or a thick segment with round ends (a wall)."""
        pg, grey = self.pygame, (120, 120, 120)
        a, b = self.to_screen(cap[0:2]), self.to_screen(cap[2:4])
        r = max(1, int(round(cap[4] * self.scale)))
        for end in (a, b):
            pg.draw.circle(self.surface, grey, (int(end[0]), int(end[1])), r)
        if not np.array_equal(a, b):
            pg.draw.line(self.surface, grey, a, b, 2 * r)

    def frame(self) -> NDArray[np.uint8]:
        arr = self.pygame.surfarray.array3d(self.surface)  # (W, H, 3)
        return np.ascontiguousarray(np.transpose(arr, (1, 0, 2)))

    def show(self) -> None:
        if self.window is None:
            return
        self.pygame.event.pump()
        self.window.blit(self.surface, (0, 0))
        self.pygame.display.flip()
        if self.clock is not None:
            self.clock.tick(self.fps)

    def close(self) -> None:
        if self.window is not None:
            self.pygame.display.quit()
            self.window = None


def save_gif(frames: Sequence[NDArray[np.uint8]], path: str | Path, fps: int = 25) -> Path:
    """Write frames (H, W, 3) to an animated GIF that plays at ``fps`` frames per second."""
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    # imageio's GIF writer takes the frame duration in milliseconds (GIF stores centiseconds)
    imageio.mimsave(path, list(frames), duration=1000.0 / fps, loop=0)
    return path


MARK_STYLES: tuple[Literal[":", "-.", "--"], ...] = (":", "-.", "--")
OBSTACLE_GREY = (0.55, 0.55, 0.55)


def _capsule_patch(ax: Any, cap: NDArray) -> None:
    """One obstacle (x0, y0, x1, y1, radius) at its true size: a disc, or a segment of that
    half-thickness with round ends."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    a, b, r = np.asarray(cap[:2]), np.asarray(cap[2:4]), float(cap[4])
    for end in (a, b):
        ax.add_patch(plt.Circle((float(end[0]), float(end[1])), r, color=OBSTACLE_GREY, lw=0))
    d = b - a
    if np.hypot(*d) > 0:
        n = np.array([-d[1], d[0]]) / np.hypot(*d) * r
        ax.add_patch(Polygon([a + n, b + n, b - n, a - n], color=OBSTACLE_GREY, lw=0))


def marker_handles(mark_labels: Sequence[str] = ()) -> list[Any]:
    """Legend entries that explain ``plot_trajectories``' markers."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    grey = "0.35"
    handles = [
        Line2D([], [], ls="none", marker="o", mfc="white", mec=grey, label="start"),
        Patch(color=grey, alpha=0.35, label="final position (disc: R/2; number: agent)"),
        Line2D([], [], ls="none", marker="x", color=grey, label="goal"),
        Line2D([], [], ls="--", color=grey, lw=1, label="path"),
    ]
    for k, text in enumerate(mark_labels):
        handles.append(
            Patch(
                facecolor=grey, alpha=0.2, edgecolor="k", linestyle=MARK_STYLES[k % 3], label=text
            )
        )
    return handles


def plot_trajectories(
    trajectory: NDArray,
    goals: NDArray,
    theta: NDArray,
    safety_radius: float,
    ax: Any = None,
    title: str | None = None,
    marks: Sequence[int] = (),
    mark_labels: Sequence[str] = (),
    legend: bool | str = True,
    colorbar: bool = True,
    obstacles: NDArray | None = None,
) -> Any:
    """A figure like the paper's, readable without the code: each agent's path (dashed, coloured
    by theta from egoist red to altruist blue, with a colour bar), its start (hollow circle), its
    final position (a disc of radius R/2 with the agent's number in it) and its goal (cross).
    ``marks`` are steps at which the agents are also drawn (faded discs), named by
    ``mark_labels`` in the legend (e.g. deadlock onset, resolution). ``legend="agents"`` keeps
    only the agents' entries (for panels that share ``marker_handles`` in one figure legend);
    ``legend="markers"`` only the markers', in a type that stays legible when the picture is
    shown small (the colour bar names each agent's theta).
    ``obstacles`` (O, 5): capsules, drawn grey at their true size. Equal scores have no colour
    scale to show: the bar is left out and the legend names the one theta.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LinearSegmentedColormap, Normalize
    from matplotlib.patches import Patch

    if ax is None:
        _, ax = plt.subplots(figsize=(6.5, 5.5), layout="constrained")
    for cap in () if obstacles is None else obstacles:
        _capsule_patch(ax, cap)
    theta = np.asarray(theta, dtype=float)
    colors = theta_colors(theta) / 255.0
    styles = MARK_STYLES
    handles = []
    for i in range(trajectory.shape[1]):
        (line,) = ax.plot(trajectory[:, i, 0], trajectory[:, i, 1], "--", color=colors[i], lw=1)
        line.set_label(f"agent {i + 1}: theta = {theta[i]:.3g}{role(theta, i)}")
        handles.append(line)
        for k, t in enumerate(marks):
            if 0 <= t < len(trajectory):
                ax.add_patch(
                    plt.Circle(
                        trajectory[t, i],
                        safety_radius / 2,
                        facecolor=colors[i],
                        alpha=0.12,
                        edgecolor="k",
                        linestyle=styles[k % 3],
                        lw=0.6,
                    )
                )
        ax.plot(*trajectory[0, i], "o", mfc="white", mec=colors[i], ms=6)
        ax.add_patch(plt.Circle(trajectory[-1, i], safety_radius / 2, color=colors[i], alpha=0.35))
        ax.annotate(str(i + 1), trajectory[-1, i], fontsize=8, ha="center", va="center")
        ax.plot(*goals[i], "x", color=colors[i])
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if legend == "agents":
        ax.legend(handles=handles, fontsize=6, loc="upper left")
    elif legend == "markers":
        handles = marker_handles(mark_labels)
        if obstacles is not None and len(obstacles):
            handles.append(Patch(color=OBSTACLE_GREY, label="obstacle"))
        ax.figure.legend(handles=handles, fontsize=11, loc="outside lower center", ncol=2)
    elif legend:
        handles += marker_handles(mark_labels)
        if obstacles is not None and len(obstacles):
            handles.append(Patch(color=OBSTACLE_GREY, label="obstacle"))
        ncol = 2 if len(handles) <= 12 else 3
        if ax.figure.get_layout_engine() is not None:
            # below the axes and their labels, placed by the layout: it hides no path, no label
            ax.figure.legend(handles=handles, fontsize=6, loc="outside lower center", ncol=ncol)
        else:
            ax.legend(
                handles=handles,
                fontsize=6,
                loc="upper center",
                bbox_to_anchor=(0.5, -0.13),
                ncol=ncol,
            )
    if colorbar and theta.max() > theta.min():
        cmap = LinearSegmentedColormap.from_list("theta", [EGOIST / 255.0, ALTRUIST / 255.0])
        norm = Normalize(float(theta.min()), float(theta.max()))
        bar = ax.figure.colorbar(plt.cm.ScalarMappable(norm, cmap), ax=ax, shrink=0.8)
        big = legend == "markers"
        bar.set_label("theta: red egoist (small), blue altruist (large)", fontsize=11 if big else 7)
    if title:
        ax.set_title(title, fontsize=12 if legend == "markers" else 9)
    return ax.figure
