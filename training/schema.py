"""The schema of a training config: every key and value checked before anything runs.

A check takes ``(value, where)`` and returns the value or raises ``ValueError`` naming the key
(``validation.episodes``) and the value. Sections are mappings whose unknown keys are refused
(a typo such as ``validation.episdoes`` is an error, not a silent default). The SB3 sections
are checked against the algorithm's own signature (``ppo.n_epoch`` is refused, ``ppo.n_epochs``
must be an integer), the env section by building the env, which refuses unknown keywords.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from rsvo_env.util.validation import shown, unknown_keywords

Check = Callable[[Any, str], Any]


def _fail(where: str, value: Any, what: str) -> ValueError:
    return ValueError(f"config {where} = {shown(value)} must be {what}")


def integer(least: int) -> Check:
    def check(value: Any, where: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < least:
            raise _fail(where, value, f"an integer >= {least}")
        return value

    return check


def real(low: float | None = None, high: float | None = None, positive: bool = False) -> Check:
    what = "a finite number" + (" > 0" if positive else "")
    if low is not None:
        what += f" in [{low}, {high}]"

    def check(value: Any, where: str) -> float:
        ok = isinstance(value, (int, float)) and not isinstance(value, bool)
        ok = ok and bool(np.isfinite(value)) and (not positive or value > 0)
        if ok and low is not None:
            ok = low <= value <= high
        if not ok:
            raise _fail(where, value, what)
        return value

    return check


def flag(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise _fail(where, value, "true or false")
    return value


def text(value: Any, where: str) -> str:
    if not isinstance(value, str):
        raise _fail(where, value, "a string")
    return value


def choice(options: tuple[str, ...]) -> Check:
    def check(value: Any, where: str) -> str:
        if value not in options:
            raise ValueError(f"config {where} = {shown(value)}; use one of {options}")
        return value

    return check


def optional(inner: Check) -> Check:
    return lambda value, where: None if value is None else inner(value, where)


def integers(least: int) -> Check:
    """A non-empty list of integers >= ``least`` (layer widths)."""

    def check(value: Any, where: str) -> list[int]:
        if not isinstance(value, list) or not value:
            raise _fail(where, value, f"a list of integers >= {least}")
        for k, v in enumerate(value):
            integer(least)(v, f"{where}[{k}]")
        return value

    return check


def section(fields: Mapping[str, Check]) -> Check:
    """A mapping with only these keys, each checked."""

    def check(value: Any, where: str) -> dict[str, Any]:
        mapping(value, where)
        unknown = sorted(set(value) - set(fields))
        if unknown:
            raise ValueError(unknown_keywords(f"config {where}:", unknown, fields))
        for key, sub in fields.items():
            if key in value:
                sub(value[key], f"{where}.{key}" if where else key)
        return value

    return check


def mapping(value: Any, where: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ValueError(f"config {where} = {shown(value)} must be a mapping (a section of keys)")
    return value


VALIDATION = section(
    {
        "every": integer(0),
        "episodes": integer(1),
        "seed": integer(0),
        "max_steps": optional(integer(1)),
    }
)

# PPO-Lagrangian's constraint (training/lagrangian.py): the allowed mean episode cost of an
# agent, the multiplier's start and its dual-ascent step
LAGRANGIAN = section(
    {
        "cost_limit": real(0.0, float("inf")),
        "multiplier_init": real(0.0, float("inf")),
        "multiplier_lr": real(positive=True),
    }
)

RLLIB = section(
    {
        "lr": real(positive=True),
        "gamma": real(0.0, 1.0),
        "lambda": real(0.0, 1.0),
        "clip_param": real(positive=True),
        "train_batch_size": integer(1),
        "minibatch_size": integer(1),
        "num_epochs": integer(1),
        "hiddens": integers(1),
    }
)

# what the trainer sets itself, never the config
_SET_BY_TRAINER = {"self", "policy", "env", "seed", "verbose", "device", "_init_setup_model"}


def _by_default(default: Any) -> Check | None:
    """The check a parameter's default value implies (None: any value is the SB3's to judge)."""
    if isinstance(default, bool):
        return flag
    if isinstance(default, int):
        return integer(0)
    if isinstance(default, float):
        return real()
    if isinstance(default, str):
        return text
    return None


def _signature_fields(cls: type, skip: set[str]) -> dict[str, Check]:
    fields: dict[str, Check] = {}
    init = getattr(cls, "__init__")  # noqa: B009  (the class's own, not an instance's)
    for name, param in inspect.signature(init).parameters.items():
        if name in skip or param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
            continue
        fields[name] = _by_default(param.default) or (lambda value, where: value)
    return fields


def sb3_section(algo: str) -> Check:
    """The section of SB3 algorithm ``algo`` (``ppo``, ``sac``): its constructor's keywords,
    typed by their defaults, and ``policy_kwargs`` checked against its MlpPolicy's."""
    from rsvo_env.training.algorithms import algorithm_class

    cls = algorithm_class(algo)
    fields = _signature_fields(cls, _SET_BY_TRAINER)
    policy = cls.policy_aliases["MlpPolicy"]
    policy_fields = _signature_fields(
        policy, {"self", "observation_space", "action_space", "lr_schedule"}
    )
    fields["policy_kwargs"] = optional(section(policy_fields))
    if "train_freq" in fields:  # an int or [n, "step" | "episode"]
        fields["train_freq"] = lambda value, where: value
    if "gradient_steps" in fields:  # -1: as many as env steps
        fields["gradient_steps"] = integer(-1)
    # numbers SB3 would take as a schedule or a float alike
    for name in ("learning_rate", "clip_range", "clip_range_vf", "ent_coef", "target_kl"):
        if name in fields:
            fields[name] = optional(_number_or_text(name, auto=algo == "sac"))
    fields.update({k: v for k, v in SB3_RANGES.items() if k in fields})
    if algo != "sac":  # PPO normalises advantages over a minibatch: at least two samples
        fields["batch_size"] = integer(2)
    return section(fields)


# the ranges SB3 asserts (or fails on) deep inside its constructor or its first rollout, checked
# here first: a value it would take to a traceback is the user's mistake, named before any work
SB3_RANGES: dict[str, Check] = {
    "n_steps": integer(1),
    "batch_size": integer(1),
    "n_epochs": integer(1),
    "buffer_size": integer(1),
    "gamma": real(0.0, 1.0),
    "gae_lambda": real(0.0, 1.0),
    "tau": real(0.0, 1.0),
    "vf_coef": real(0.0, float("inf")),
    "max_grad_norm": real(positive=True),
    "stats_window_size": integer(1),
}


def _number_or_text(name: str, auto: bool) -> Check:
    """A rate or a range: a number > 0 (the entropy coefficient >= 0, or with ``auto`` SAC's
    ``"auto"`` / ``"auto_0.1"``); SB3 fails deep inside on the rest (a negative learning rate in
    torch's optimiser) or, worse, trains on nonsense."""
    if name != "ent_coef":
        return real(positive=True)
    number = real(0.0, float("inf"))

    def check(value: Any, where: str) -> Any:
        if isinstance(value, str):
            if auto and (value == "auto" or value.startswith("auto_")):
                return value
            what = 'a number >= 0, "auto" or "auto_<initial value>"' if auto else "a number >= 0"
            raise _fail(where, value, what)
        return number(value, where)

    return check
