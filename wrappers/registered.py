"""The registries' entry points (``rsvo_env.envs.registration``): an id names its scenario, so a
``scenario=`` keyword that names another is refused rather than silently swapping the scene."""

from __future__ import annotations

from typing import Any

import rsvo_env
from rsvo_env.envs.parallel import RSVOParallelEnv
from rsvo_env.util.validation import shown
from rsvo_env.wrappers.joint import JointControlEnv
from rsvo_env.wrappers.joint_vector import JointVectorEnv


def _scenario(id_scenario: str, kwargs: dict[str, Any]) -> str:
    """The id's scenario; a ``scenario`` keyword may repeat it, never change it."""
    given = kwargs.pop("scenario", id_scenario)
    if given != id_scenario:
        raise TypeError(
            f"scenario = {shown(given)}: this id names the scenario {shown(id_scenario)}; for "
            f"another, "
            f"make that scenario's id, or rsvo_env.wrappers.JointControlEnv({shown(given)}, ...) / "
            f"rsvo_env.parallel_env({shown(given)}, ...)"
        )
    return id_scenario


def joint_env(id_scenario: str, **kwargs: Any) -> JointControlEnv:
    """gymnasium's entry point: ``rsvo_env.wrappers.joint.JointControlEnv`` of the id's
    scenario."""
    return JointControlEnv(_scenario(id_scenario, kwargs), **kwargs)


def joint_vector_env(
    id_scenario: str, num_envs: int = 1, max_episode_steps: int | None = None, **kwargs: Any
) -> JointVectorEnv:
    """gymnasium's vector entry point (``make_vec(id, E, vectorization_mode=
    "vector_entry_point")``): ``rsvo_env.wrappers.joint_vector.JointVectorEnv`` of the id's
    scenario, E envs of the batched core; the spec's ``max_episode_steps`` is the step cap
    unless ``max_steps`` is given."""
    if max_episode_steps is not None and "max_cycles" not in kwargs:
        kwargs.setdefault("max_steps", max_episode_steps)
    return JointVectorEnv(_scenario(id_scenario, kwargs), num_envs=num_envs, **kwargs)


def parallel_env(id_scenario: str, **kwargs: Any) -> RSVOParallelEnv:
    """PettingZoo's parallel entry point: [`parallel_env`][rsvo_env.parallel_env] of the id's
    scenario."""
    return rsvo_env.parallel_env(_scenario(id_scenario, kwargs), **kwargs)


def aec_env(id_scenario: str, **kwargs: Any) -> Any:
    """PettingZoo's AEC entry point: [`env`][rsvo_env.env] of the id's scenario."""
    return rsvo_env.env(_scenario(id_scenario, kwargs), **kwargs)
