"""A digest of full episodes of every scenario: each model, batched and single, filter on and
off, the residual and theta actions, barriers and weightings. Two commits that print the same
lines behave the same, bit for bit (every observation, reward, flag, info array and metric
hashed).

    python -m benchmarks.tools.episode_digest > before.txt   # at one commit
    python -m benchmarks.tools.episode_digest | diff before.txt -   # at another

Only public paths are used (``rsvo_env.parallel_env``, ``rsvo_env.envs.vector.BatchedEnv``,
the filter wrapper where a library before 1.0 needs it: ``single_env_speed.single_env``), so the
script runs unchanged across a move of the library's modules.
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from benchmarks.speed.single_env_speed import single_env
from rsvo_env.envs.vector import BatchedEnv  # noqa: E402

STEPS = 300
SCENE = dict(
    starts=[[-6, -1.5], [-6, 1.5], [6, -1.5], [6, 1.5]],
    goals=[[6, 1.5], [6, -1.5], [-6, 1.5], [-6, -1.5]],
    radii=[0.4, 0.4, 0.5, 0.5],
    walls=[[[0, 2], [0, 8]], [[0, -2], [0, -8]]],
    circles=[[3, 5, 1.0]],
)
SPREAD = {"theta_range": (1.0, 10.0)}
# (name, scenario, keywords); the filter's own keywords (split) only where it is on
CASES: list[tuple[str, str, dict[str, Any]]] = [
    ("position_swap", "position_swap", {}),
    ("circular_swap", "circular_swap", SPREAD),
    ("circular_swap move_to_goal", "circular_swap", {"nominal": "move_to_goal", **SPREAD}),
    ("circular_swap symmetric", "circular_swap", {"weighting": "symmetric", **SPREAD}),
    ("ramp_merge", "ramp_merge", SPREAD),
    ("ramp_merge paper split", "ramp_merge", {"split": "paper", **SPREAD}),
    ("crowd", "crowd", {"theta_range": (1.0, 10.0)}),
    ("crowd 80", "crowd", {"num_agents": 80, "theta_range": (1.0, 10.0)}),
    ("doorway", "doorway", {}),
    ("obstacle_field", "obstacle_field", {}),
    ("unicycle_crowd", "unicycle_crowd", {}),
    ("custom single", "custom", dict(SCENE)),
    ("custom double", "custom", dict(SCENE, dynamics="double_integrator", a_max=2.0, dt=0.05)),
]


class Digest:
    def __init__(self) -> None:
        self.h = hashlib.sha256()

    def add(self, value: Any) -> None:
        if isinstance(value, dict):
            for key in sorted(value, key=str):
                self.h.update(str(key).encode())
                self.add(value[key])
        elif isinstance(value, (list, tuple)):
            for v in value:
                self.add(v)
        elif isinstance(value, np.ndarray):
            self.h.update(str(value.dtype).encode() + str(value.shape).encode())
            self.h.update(np.ascontiguousarray(value).tobytes())
        else:
            self.h.update(repr(value).encode())

    def hex(self) -> str:
        return self.h.hexdigest()[:16]


FILTER_ONLY = ("split",)


def single(scenario: str, filtered: bool, kwargs: dict[str, Any]) -> str:
    env = single_env(scenario, filtered, filter_part(kwargs), **scene_part(kwargs))
    d = Digest()
    d.add(env.reset(seed=3))
    for _ in range(STEPS):
        if not env.agents:
            break
        d.add(env.step(env.unwrapped.nominal_actions()))
    d.add(env.unwrapped.episode_metrics)  # None while the episode runs
    d.add(env.unwrapped.state())
    return d.hex()


def scene_part(kwargs: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in kwargs.items() if k not in FILTER_ONLY}


def filter_part(kwargs: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in kwargs.items() if k in FILTER_ONLY}


def batched(scenario: str, filtered: bool, kwargs: dict[str, Any], **extra: Any) -> str:
    kw = kwargs if filtered else scene_part(kwargs)
    venv = BatchedEnv(scenario, num_envs=3, safety_filter=filtered, **kw, **extra)
    d = Digest()
    d.add(venv.reset(seed=5))
    rng = np.random.default_rng(0)
    for _ in range(STEPS):
        a = venv.nominal_actions()
        if extra.get("action") == "residual":
            a = 0.3 * rng.uniform(-1, 1, a.shape)
        if extra.get("theta_action"):
            a[..., 2] = rng.choice([-1.0, 1.0], a.shape[:-1])
        d.add(venv.step(a))
    d.add(venv.state())
    return d.hex()


def main() -> None:
    for name, scenario, kwargs in CASES:
        for filtered in (True, False):
            label = f"{name:32s} filter={filtered!s:5s}"
            print(f"{label} single  {single(scenario, filtered, kwargs)}")
            print(f"{label} batched {batched(scenario, filtered, kwargs)}")
    for name, scenario, kwargs in CASES[6:8]:
        residual = batched(scenario, True, kwargs, action="residual", gate_radius=0.5)
        print(f"{name:32s} residual               {residual}")
        theta = batched(scenario, True, kwargs, theta_action=True)
        print(f"{name:32s} theta_action           {theta}")


if __name__ == "__main__":
    main()
