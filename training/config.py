"""Training configs: a YAML file per scenario, CLI overrides, validation, and the envs they make.

A config is a plain dict (``configs/<scenario>.yaml``); ``resolve`` merges the overrides and
checks every field before anything is built, so a bad value fails with its name, not deep inside
SB3. The resolved config is saved beside the model and is all
``rsvo_env.training.evaluate`` needs.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import yaml

from rsvo_env.control.residual import Residual
from rsvo_env.envs.factory import FILTER_KEYWORDS
from rsvo_env.envs.vector import BatchedEnv
from rsvo_env.training import schema
from rsvo_env.util.scene_file import load_yaml
from rsvo_env.util.validation import shown, unknown_keywords

CONFIG_DIR = Path(__file__).parent / "configs"

ALGOS = ("ppo", "sac", "ppo_lagrangian")
# the section of hyperparameters each algorithm reads (PPO-Lagrangian is PPO plus `lagrangian`)
SECTION = {"ppo": "ppo", "sac": "sac", "ppo_lagrangian": "ppo"}
ACTIONS = ("direct", "residual")
WEIGHTINGS = ("asymmetric", "symmetric")
ENGINES = ("sb3", "rllib")
# the activations a config may name for an SB3 policy (``policy_kwargs.activation_fn``)
ACTIVATIONS = ("tanh", "relu")
# every top-level key and its check; the sections' own keys are checked in theirs
TOP: dict[str, schema.Check] = {
    "scenario": schema.text,
    "algo": schema.choice(ALGOS),
    "action": schema.choice(ACTIONS),
    "gate_radius": schema.real(),
    "residual_right_hand": schema.flag,
    "residual_scale": schema.real(positive=True),
    "yield_radius": schema.optional(schema.real(positive=True)),
    "interaction_radius": schema.optional(schema.real(positive=True)),
    "stall_gate": schema.optional(schema.real(positive=True)),
    "weighting": schema.choice(WEIGHTINGS),
    "num_envs": schema.integer(1),
    "timesteps": schema.integer(1),
    "env": schema.mapping,
    "ppo": schema.mapping,
    "sac": schema.mapping,
    "lagrangian": schema.LAGRANGIAN,
    "validation": schema.VALIDATION,
    "checkpoint_every": schema.integer(0),
    "seed": schema.integer(0),
    "threads": schema.integer(1),
    "engine": schema.choice(ENGINES),
    "rllib": schema.RLLIB,
}


def load(scenario: str | None = None, path: str | Path | None = None) -> dict[str, Any]:
    """The config of a scenario (``configs/<scenario>.yaml``) or of a file."""
    if path is None:
        if scenario is None:
            raise ValueError("give a scenario or a config path")
        path = CONFIG_DIR / f"{scenario}.yaml"
        if not path.exists():
            known = sorted(p.stem for p in CONFIG_DIR.glob("*.yaml"))
            raise ValueError(f"no config for scenario {shown(scenario)}; configs exist for {known}")
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"config file {shown(str(path))} does not exist")
    with open(path) as f:
        try:
            cfg = load_yaml(f)
        except yaml.YAMLError as exc:
            raise ValueError(f"{path}: not a YAML file ({exc})") from None
    if not isinstance(cfg, dict):
        raise ValueError(f"{path}: a config is a mapping, got {type(cfg).__name__}")
    return cfg


def set_value(cfg: dict[str, Any], assignment: str) -> None:
    """Apply ``key.sub=value`` (the value parsed as YAML) to a config in place."""
    if "=" not in assignment:
        raise ValueError(f"--set {shown(assignment)}: use key=value, e.g. env.num_agents=8")
    key, raw = assignment.split("=", 1)
    node = cfg
    *parents, leaf = key.split(".")
    for part in parents:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise ValueError(f"--set {shown(assignment)}: {shown(part)} is not a section")
    node[leaf] = load_yaml(raw)


def resolve(cfg: dict[str, Any], **overrides: Any) -> dict[str, Any]:
    """A checked copy of ``cfg`` with the non-None ``overrides`` (top-level keys) applied:
    every key and value against ``TOP`` (``rsvo_env.training.schema``), then the env
    built once, before anything runs."""
    out = copy.deepcopy(cfg)
    out.update({k: v for k, v in overrides.items() if v is not None})
    out.setdefault("seed", 0)
    out.setdefault("threads", 1)
    out.setdefault("env", {})
    out.setdefault("engine", "sb3")
    unknown = sorted(set(out) - set(TOP))
    if unknown:
        raise ValueError(unknown_keywords("the config", unknown, TOP))
    for key in ("scenario", "algo", "action", "weighting", "num_envs", "timesteps"):
        if key not in out:
            raise ValueError(f"config has no {shown(key)}")
    schema.section(TOP)(out, "")
    section = "rllib" if out["engine"] == "rllib" else SECTION[out["algo"]]
    if out["engine"] == "rllib" and out["algo"] != "ppo":
        raise ValueError(f"config algo = {shown(out['algo'])}: the rllib engine trains ppo")
    if not isinstance(out.get(section), dict):
        raise ValueError(f"config has no {shown(section)} section of hyperparameters")
    if out["engine"] == "sb3":
        for algo in ("ppo", "sac"):
            if algo in out:
                schema.sb3_section(algo)(out[algo], algo)
        hyperparameters(out)
    # build one env now: every scenario, filter and observation field is checked by the env
    # (gamma dt <= 1 by FilterConfig, its one owner)
    make_env(out, num_envs=1).close()
    env = out["env"]
    if env.get("safety_filter", True) is False and set(FILTER_KEYWORDS) & set(env):
        # the filter's settings of a config that turns it off are still saved with the run:
        # each is checked by the filter as if it were on
        make_env({**out, "env": {**env, "safety_filter": True}}, num_envs=1).close()
    val = out.setdefault("validation", {})
    val.setdefault("every", 0)
    val.setdefault("episodes", 20)
    val.setdefault("seed", 900_000)
    # the time cap of validation and evaluation episodes (None: the training episodes' own)
    val.setdefault("max_steps", None)
    out.setdefault("checkpoint_every", 0)
    return out


def hyperparameters(cfg: dict[str, Any]) -> dict[str, Any]:
    """The keyword arguments of the SB3 algorithm ``cfg["algo"]``, with a named activation
    (``policy_kwargs.activation_fn: relu``) turned into its torch module class; PPO-Lagrangian's
    are PPO's and its ``lagrangian`` section (defaults:
    ``rsvo_env.training.lagrangian.PPOLagrangian``)."""
    import torch

    hyper = copy.deepcopy(cfg[SECTION[cfg["algo"]]])
    if cfg["algo"] == "ppo_lagrangian":
        hyper.update(cfg.get("lagrangian") or {})
    kwargs = hyper.get("policy_kwargs") or {}
    name = kwargs.get("activation_fn")
    if name is not None:
        if name not in ACTIVATIONS:
            raise ValueError(
                f"config {cfg['algo']}.policy_kwargs.activation_fn = {shown(name)}; use one of "
                f"{ACTIVATIONS}"
            )
        kwargs["activation_fn"] = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[name]
    return hyper


def residual_settings(cfg: dict[str, Any]) -> Residual:
    """A config's residual mode (its keywords spelled as ``BatchedEnv``'s), the defaults of
    ``rsvo_env.control.residual.Residual`` where it is silent."""
    return Residual.of_env_keywords(cfg)


def make_env(
    cfg: dict[str, Any],
    num_envs: int,
    action: str | None = None,
    weighting: str | None = None,
    **env_overrides: Any,
) -> BatchedEnv:
    """The filtered batched env a config describes (``action``/``weighting``: another choice,
    e.g. ``action="direct"`` for the scripted controller under the same protocol)."""
    return BatchedEnv(
        cfg["scenario"],
        num_envs=num_envs,
        action=action or cfg["action"],
        **residual_settings(cfg).env_keywords(),
        weighting=weighting or cfg["weighting"],
        **{**env_keywords(cfg), **env_overrides},
    )


def env_keywords(cfg: dict[str, Any]) -> dict[str, Any]:
    """The config's env section as the env takes it: with ``safety_filter: false`` (the
    constrained-RL baselines) the filter's own settings (``gamma``, ...) are left out, since a
    config written for the filtered task names them and there is no filter for them to set."""
    env = dict(cfg["env"])
    if env.get("safety_filter", True) is False:
        for key in FILTER_KEYWORDS:
            env.pop(key, None)
    return env


def limit_threads(threads: int) -> None:
    """One thread budget for the policy (torch) and the env's compiled kernels (numba). Both
    keep a pool of workers that spin between parallel sections; on a machine of few cores, two
    runs side by side with a pool each were 10x slower than with one thread each."""
    import numba
    import torch

    from rsvo_env.util import threads as kernels

    # numba first: starting its threading layer can reset the OpenMP thread count torch reads
    n = min(threads, numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(n)
    kernels.set_num_threads(n)  # the library's kernels: parallel only when given the threads
    torch.set_num_threads(threads)


def save(cfg: dict[str, Any], path: str | Path) -> None:
    with open(path, "w") as f:
        yaml.safe_dump(cfg, f, sort_keys=False)


def make_parallel(
    cfg: dict[str, Any], render_mode: str | None = None, action: str | None = None
) -> Any:
    """The same env as a filtered PettingZoo ParallelEnv (one env: videos, the single-env path)."""
    import rsvo_env
    from rsvo_env.wrappers import ResidualAction

    env = rsvo_env.parallel_env(
        cfg["scenario"], render_mode=render_mode, weighting=cfg["weighting"], **env_keywords(cfg)
    )
    if (action or cfg["action"]) == "residual":
        # the wrapper spells the settings as BatchedEnv does (Residual.env_keywords)
        env = ResidualAction(env, **residual_settings(cfg).env_keywords())
    return env
