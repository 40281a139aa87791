"""The registries' entry points (``rsvo_env.envs.registration``): an id names its scenario, so a
``scenario=`` keyword that names another is refused rather than silently swapping the scene."""

from __future__ import annotations

from typing import Any

from rsvo_env.util.validation import shown
from wrappers.joint import JointControlEnv
from wrappers.safety_filter import filtered_aec_env, filtered_parallel_env


def _scenario(id_scenario: str, kwargs: dict[str, Any]) -> str:
    """The id's scenario; a ``scenario`` keyword may repeat it, never change it."""
    given = kwargs.pop("scenario", id_scenario)
    if given != id_scenario:
        raise TypeError(
            f"scenario = {shown(given)}: this id names the scenario {shown(id_scenario)}; for "
            f"another, "
            f"make that scenario's id, or wrappers.JointControlEnv({shown(given)}, ...) / "
            f"rsvo_env.parallel_env({shown(given)}, ...)"
        )
    return id_scenario


def joint_env(id_scenario: str, **kwargs: Any) -> JointControlEnv:
    """gymnasium's entry point: :class:`wrappers.joint.JointControlEnv` of the id's scenario."""
    return JointControlEnv(_scenario(id_scenario, kwargs), **kwargs)


def parallel_env(id_scenario: str, **kwargs: Any):
    """PettingZoo's parallel entry point: the id's scenario behind the filter."""
    return filtered_parallel_env(_scenario(id_scenario, kwargs), **kwargs)


def aec_env(id_scenario: str, **kwargs: Any):
    """PettingZoo's AEC entry point."""
    return filtered_aec_env(scenario=_scenario(id_scenario, kwargs), **kwargs)
