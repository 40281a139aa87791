"""Pictures: pygame frames (``rgb_array`` headless, ``human`` in a window), GIFs, and matplotlib
figures of trajectories like the paper's."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

EGOIST = np.array([220, 60, 40])
ALTRUIST = np.array([40, 90, 220])
BACKGROUND = (250, 250, 248)


def theta_colors(theta: NDArray[np.float64]) -> NDArray[np.uint8]:
    """One RGB colour per agent, from egoist (red, small theta) to altruist (blue).

    The position on the scale is the agent's R-SVO share against the group's mean score,
    ``theta_i / (theta_i + mean theta)``, so equal scores are all the middle colour.
    """
    mean = float(np.mean(theta)) if len(theta) else 0.0
    total = theta + mean
    share = np.where(total > 0, theta / np.where(total > 0, total, 1.0), 0.5)
    return np.round(EGOIST + (ALTRUIST - EGOIST) * share[:, None]).astype(np.uint8)


class Renderer:
    """Draws a world onto a pygame surface; a window only in ``human`` mode."""

    def __init__(
        self,
        arena: tuple[NDArray, NDArray],
        mode: str,
        size: int = 600,
        fps: int = 50,
        trail: int = 400,
    ) -> None:
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame

        self.pygame = pygame
        self.mode = mode
        lo, hi = (np.asarray(a, dtype=np.float64) for a in arena)
        span = hi - lo
        self.scale = size / float(span.max())
        self.width = int(np.ceil(span[0] * self.scale))
        self.height = int(np.ceil(span[1] * self.scale))
        self.lo, self.fps, self.trail = lo, fps, trail
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
        safety_radius: float,
        history: Sequence[NDArray] = (),
    ) -> None:
        pg = self.pygame
        surf = self.surface
        surf.fill(BACKGROUND)
        colors = theta_colors(theta)
        r_px = max(2, int(round(0.5 * safety_radius * self.scale)))
        if len(history) > 1:
            trail = self.to_screen(np.stack(history[-self.trail :]))
            for i in range(positions.shape[0]):
                pg.draw.lines(surf, tuple(int(c) for c in colors[i]), False, trail[:, i], 1)
        for i, g in enumerate(self.to_screen(goals)):
            c = tuple(int(v) for v in colors[i])
            x, y = int(g[0]), int(g[1])
            pg.draw.line(surf, c, (x - 5, y - 5), (x + 5, y + 5), 2)
            pg.draw.line(surf, c, (x - 5, y + 5), (x + 5, y - 5), 2)
        halo = pg.Surface((2 * r_px + 2, 2 * r_px + 2), pg.SRCALPHA)
        for i, p in enumerate(self.to_screen(positions)):
            c = tuple(int(v) for v in colors[i])
            halo.fill((0, 0, 0, 0))
            pg.draw.circle(halo, (*c, 70), (r_px + 1, r_px + 1), r_px)
            surf.blit(halo, (int(p[0]) - r_px - 1, int(p[1]) - r_px - 1))
            pg.draw.circle(surf, c, (int(p[0]), int(p[1])), r_px, 2)  # safety circle, R/2
            pg.draw.circle(surf, c, (int(p[0]), int(p[1])), max(2, r_px // 4))

    def frame(self) -> NDArray[np.uint8]:
        arr = self.pygame.surfarray.array3d(self.surface)  # (W, H, 3)
        return np.ascontiguousarray(np.transpose(arr, (1, 0, 2)))

    def show(self) -> None:
        if self.window is None:
            return
        self.pygame.event.pump()
        self.window.blit(self.surface, (0, 0))
        self.pygame.display.flip()
        self.clock.tick(self.fps)

    def close(self) -> None:
        if self.window is not None:
            self.pygame.display.quit()
            self.window = None


def save_gif(frames: Sequence[NDArray[np.uint8]], path: str | Path, fps: int = 25) -> Path:
    """Write frames (H, W, 3) to an animated GIF."""
    import imageio.v2 as imageio

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    imageio.mimsave(path, list(frames), duration=1.0 / fps, loop=0)
    return path


def plot_trajectories(
    trajectory: NDArray,
    goals: NDArray,
    theta: NDArray,
    safety_radius: float,
    ax: Any = None,
    title: str | None = None,
    marks: Sequence[int] = (),
) -> Any:
    """A figure like the paper's: paths (dashed), final positions with safety circles, goals.

    ``trajectory`` is (T, N, 2). ``marks`` are step indices at which the agents are also drawn
    (faded), e.g. deadlock onset and resolution.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(5, 5))
    colors = theta_colors(theta) / 255.0
    n = trajectory.shape[1]
    for i in range(n):
        ax.plot(trajectory[:, i, 0], trajectory[:, i, 1], "--", color=colors[i], lw=1)
        for t in marks:
            if 0 <= t < len(trajectory):
                ax.add_patch(
                    plt.Circle(trajectory[t, i], safety_radius / 2, color=colors[i], alpha=0.15)
                )
        ax.add_patch(plt.Circle(trajectory[-1, i], safety_radius / 2, color=colors[i], alpha=0.35))
        ax.plot(*goals[i], "x", color=colors[i])
        ax.annotate(str(i + 1), trajectory[0, i], fontsize=8, ha="center", va="center")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    if title:
        ax.set_title(title, fontsize=9)
    return ax.figure
