"""A controller is one module plus its registration: a toy controller defined here, registered
with one call, is what a scenario's ``nominal`` names, with settings of its own."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from rsvo_env import control
from rsvo_env.control import Controller
from rsvo_env.envs.vector import BatchedEnv


class Halving(Controller):
    """A toy: half the preferred velocity, scaled by its own setting ``halving_gain``."""

    name = "halving"
    settings = {"halving_gain": 0.5}
    positive = ("halving_gain",)
    reads = ()

    def check(self, params: dict[str, Any], scenario: str) -> float:
        super().check(params, scenario)
        return float(params["halving_gain"])

    def steer(self, state, preferred, scenario):
        return scenario.controller_settings * preferred


@pytest.fixture
def halving():
    controller = control.register(Halving())
    try:
        yield controller
    finally:
        control.CONTROLLERS.pop("halving")


def test_a_registered_controller_is_what_nominal_names(halving):
    kw = {"num_envs": 1, "num_agents": 4, "safety_filter": False}
    half = BatchedEnv("circular_swap", nominal="halving", halving_gain=0.25, **kw)
    full = BatchedEnv("circular_swap", nominal="move_to_goal", **kw)
    half.reset(seed=3)
    full.reset(seed=3)
    np.testing.assert_allclose(half.nominal_actions(), 0.25 * full.nominal_actions())
    assert half.scenario.controller is halving


def test_its_settings_are_checked_and_unknown_names_refused(halving):
    with pytest.raises(ValueError, match=r"circular_swap.halving_gain = -1"):
        BatchedEnv("circular_swap", num_envs=1, nominal="halving", halving_gain=-1.0)
    with pytest.raises(ValueError, match=r"circular_swap.nominal = 'nope'.*'halving'"):
        BatchedEnv("circular_swap", num_envs=1, nominal="nope")
    with pytest.raises(ValueError, match=r"ramp_merge.nominal = 'halving'"):
        BatchedEnv("ramp_merge", num_envs=1, nominal="halving")


def test_a_taken_name_or_setting_is_refused(halving):
    with pytest.raises(ValueError, match="'halving' is registered already"):
        control.register(Halving())

    class Stealing(Controller):
        name = "stealing"
        settings = {"rorca_tau": 1.0}

    with pytest.raises(ValueError, match=r"\['rorca_tau'\] are the rorca controller's"):
        control.register(Stealing())
    assert "stealing" not in control.names()
