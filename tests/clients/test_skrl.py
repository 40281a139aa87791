"""skrl's IPPO and MAPPO on ``rsvo/Crowd-v0`` (PettingZoo's registry), with skrl's own
``wrap_env(env, "pettingzoo")`` and ``SequentialTrainer``, unchanged. MAPPO's centralised value
function reads ``env.state()`` (skrl asks the wrapper for ``state_spaces`` and ``state()``).

One skrl config bug is worked around (skrl 2.1): ``MultiAgentCfg.expand`` refuses the empty
dicts that are the defaults of the ``*_kwargs`` fields (``learning_rate_scheduler_kwargs``,
``observation_preprocessor_kwargs``, ...: "Specified keys (set()) do not match possible
agents"), so :func:`per_agent_defaults` gives each such field one empty dict per agent, which
means the same. Otherwise the configs are skrl's dataclasses with small rollouts, so a few
hundred steps go through several updates."""

import dataclasses

import pettingzoo
import pytest
import torch
from skrl.envs.wrappers.torch import wrap_env
from skrl.memories.torch import RandomMemory
from skrl.models.torch import DeterministicMixin, GaussianMixin, Model
from skrl.multi_agents.torch.ippo import IPPO, IPPO_CFG
from skrl.multi_agents.torch.mappo import MAPPO, MAPPO_CFG
from skrl.trainers.torch import SequentialTrainer

import rsvo_env  # noqa: F401  (registers the ids)

STEPS = 300


class Policy(GaussianMixin, Model):
    def __init__(self, observation_space, action_space, device):
        Model.__init__(
            self, observation_space=observation_space, action_space=action_space, device=device
        )
        GaussianMixin.__init__(self, clip_actions=True)
        n = self.num_observations
        self.net = torch.nn.Sequential(
            torch.nn.Linear(n, 32), torch.nn.Tanh(), torch.nn.Linear(32, self.num_actions)
        )
        self.log_std = torch.nn.Parameter(torch.full((self.num_actions,), -0.5))

    def compute(self, inputs, role=""):
        return self.net(inputs["observations"]), {"log_std": self.log_std}


class Value(DeterministicMixin, Model):
    """The value function; ``key`` "states" (MAPPO: the global state) or "observations"."""

    def __init__(self, space, key, device):
        kwargs = {"state_space" if key == "states" else "observation_space": space}
        Model.__init__(self, device=device, **kwargs)
        DeterministicMixin.__init__(self)
        self.key = key
        n = self.num_states if key == "states" else self.num_observations
        self.net = torch.nn.Sequential(
            torch.nn.Linear(n, 32), torch.nn.Tanh(), torch.nn.Linear(32, 1)
        )

    def compute(self, inputs, role=""):
        return self.net(inputs[self.key]), {}


def per_agent_defaults(cfg, agents):
    """The workaround above: every field left at ``{}`` becomes ``{uid: {} for uid}``."""
    for field in dataclasses.fields(cfg):
        if getattr(cfg, field.name) == {}:
            setattr(cfg, field.name, {uid: {} for uid in agents})
    return cfg


def make(algorithm):
    torch.manual_seed(0)
    base = pettingzoo.make("parallel", "rsvo/Crowd-v0", num_agents=4, max_steps=60)
    env = wrap_env(base, "pettingzoo")
    device = env.device
    models, memories = {}, {}
    for uid in env.possible_agents:
        value = (
            Value(env.state_spaces[uid], "states", device)
            if algorithm is MAPPO
            else Value(env.observation_spaces[uid], "observations", device)
        )
        models[uid] = {
            "policy": Policy(env.observation_spaces[uid], env.action_spaces[uid], device),
            "value": value,
        }
        memories[uid] = RandomMemory(memory_size=32, num_envs=env.num_envs, device=device)
    cfg = (MAPPO_CFG if algorithm is MAPPO else IPPO_CFG)(
        rollouts=32, learning_epochs=2, mini_batches=2
    )
    cfg = per_agent_defaults(cfg, env.possible_agents)
    agent = algorithm(
        possible_agents=env.possible_agents,
        models=models,
        memories=memories,
        observation_spaces=env.observation_spaces,
        state_spaces=env.state_spaces,
        action_spaces=env.action_spaces,
        device=device,
        cfg=cfg,
    )
    return env, base, agent


@pytest.mark.parametrize("algorithm", [IPPO, MAPPO])
def test_skrl_trains_on_the_crowd(algorithm):
    torch.set_num_threads(1)
    env, base, agent = make(algorithm)
    state_dim = env.state_spaces[env.possible_agents[0]].shape[0]
    assert state_dim == base.state_space.shape[0] == 4 * 8
    before = [p.detach().clone() for p in agent.models["agent_0"]["value"].parameters()]
    trainer = SequentialTrainer(
        env=env,
        agents=agent,
        cfg={
            "timesteps": STEPS,
            "disable_progressbar": True,
            "close_environment_at_exit": False,
            "headless": True,
        },
    )
    trainer.train()
    after = list(agent.models["agent_0"]["value"].parameters())
    assert any(not torch.equal(a, b) for a, b in zip(after, before, strict=True))
    # the value network of MAPPO was fed the global state: its input width is the state's
    first = agent.models["agent_0"]["value"].net[0]
    assert first.in_features == (
        state_dim if algorithm is MAPPO else env.observation_spaces["agent_0"].shape[0]
    )
    # behind the filter, through the client: no collision in the episodes it played (60 steps)
    metrics = base.unwrapped.episode_metrics
    assert metrics is not None and metrics["n_collision_steps"] == 0
    assert metrics["min_distance"] >= 1.0 - 1e-9
