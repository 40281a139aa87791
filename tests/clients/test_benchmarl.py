"""A centralised critic through BenchMARL: MAPPO on the filtered crowd as a custom task, the
documented way (a ``TaskClass`` whose env is TorchRL's ``PettingZooWrapper`` with
``return_state=True``), so MAPPO's critic reads ``env.state()``. IPPO beside it, whose critic
reads the agents' own observations."""

import pytest
import torch
from benchmarl.algorithms import IppoConfig, MappoConfig
from benchmarl.environments.pettingzoo.common import PettingZooClass
from benchmarl.experiment import Experiment, ExperimentConfig
from benchmarl.models.mlp import MlpConfig
from torchrl.envs.libs.pettingzoo import PettingZooWrapper

import rsvo_env

AGENTS, STEPS = 4, 50


class CrowdTask(PettingZooClass):
    """The filtered crowd: continuous actions, a global state, ``STEPS``-step episodes."""

    def get_env_fun(self, num_envs, continuous_actions, seed, device):
        return lambda: PettingZooWrapper(
            rsvo_env.parallel_env("crowd", num_agents=AGENTS, max_steps=STEPS),
            categorical_actions=False,
            return_state=True,
            seed=seed,
            device=device,
        )

    def supports_continuous_actions(self):
        return True

    def supports_discrete_actions(self):
        return False

    def has_state(self):
        return True

    def has_render(self, env):
        return False

    def max_steps(self, env):
        return STEPS

    @staticmethod
    def env_name():
        return "rsvo"


def experiment(algorithm_config, tmp_path):
    config = ExperimentConfig.get_from_yaml()
    config.max_n_iters = 2
    config.on_policy_collected_frames_per_batch = 2 * STEPS
    config.on_policy_n_envs_per_worker = 1
    config.on_policy_n_minibatch_iters = 2
    config.on_policy_minibatch_size = STEPS
    config.evaluation = False
    config.render = False
    config.loggers = []
    config.create_json = False
    config.checkpoint_interval = 0
    config.save_folder = str(tmp_path)
    return Experiment(
        task=CrowdTask(name="CROWD", config={}),
        algorithm_config=algorithm_config.get_from_yaml(),
        model_config=MlpConfig.get_from_yaml(),
        critic_model_config=MlpConfig.get_from_yaml(),
        seed=0,
        config=config,
    )


@pytest.mark.parametrize("algorithm", [MappoConfig, IppoConfig])
def test_benchmarl_trains_with_the_global_state(algorithm, tmp_path):
    torch.set_num_threads(1)
    exp = experiment(algorithm, tmp_path)
    state_dim = 8 * AGENTS
    assert exp.state_spec is not None and exp.state_spec["state"].shape[-1] == state_dim
    params = exp.losses["agent"].critic_network_params.flatten_keys()
    widths = {int(w.shape[-1]) for k, w in params.items() if k.endswith("weight")}
    # MAPPO's critic is fed the global state; IPPO's each agent's observation
    obs_dim = exp.observation_spec["agent", "observation"].shape[-1]
    assert (state_dim if algorithm is MappoConfig else obs_dim) in widths
    assert (obs_dim if algorithm is MappoConfig else state_dim) not in widths
    before = {k: v.detach().clone() for k, v in params.items()}
    exp.run()
    assert exp.n_iters_performed == 2 and exp.total_frames == 4 * STEPS
    after = exp.losses["agent"].critic_network_params.flatten_keys()
    assert any(not torch.equal(after[k], v) for k, v in before.items())
