"""ResponsibilityWeighting: choose how pairs share responsibility.

The weighting lives in the world: this wrapper sets the base env's mode (and the current
world's, if an episode is running), and the filter reads ``world.omega``, so the two wrappers
stack in either order. The wrapped env itself is reweighted (wrappers configure in place,
``docs/api.md``). A single episode can still pick another mode through
``reset(options={"weighting": ...})``.
"""

from __future__ import annotations

from typing import Any

from pettingzoo.utils import BaseParallelWrapper

from rsvo_env.responsibility.svo import Weighting


class ResponsibilityWeighting(BaseParallelWrapper):
    """The responsibility weighting of an env's episodes, passed to each reset as an option (the
    outermost weighting wrapper wins over inner ones; a caller's own option over every wrapper).

    Args:
        env: The PettingZoo env (an ``RSVOParallelEnv`` or a wrapper of one).
        mode: ``"asymmetric"`` (the paper's R-SVO weights), ``"symmetric"`` (0.5 for every
            pair) or a callable ``theta -> omega`` matrix (validated: entries in [0, 1],
            ``W + W.T = 1``).

    Raises:
        ValueError: An unknown mode.
    """

    def __init__(self, env: Any, mode: Weighting = "asymmetric") -> None:
        super().__init__(env)
        env.unwrapped.set_weighting(mode)  # validated: fails now on a bad mode
        self.mode = mode

    def reset(
        self, seed: int | None = None, options: dict | None = None
    ) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
        """Reset the env with this weighting.

        Args:
            seed: As the env's ``reset``.
            options: As the env's; a ``weighting`` given here wins over the wrapper's.

        Returns:
            The env's observations and infos.
        """
        # Passed down as an option: the outermost weighting wrapper wins over inner ones, and an
        # explicit per-episode option from the caller wins over every wrapper.
        return self.env.reset(seed=seed, options={"weighting": self.mode, **(options or {})})
