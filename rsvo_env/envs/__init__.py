"""The environments over the core: the PettingZoo ParallelEnv, ``BatchedEnv``, the factory,
rendering, registration."""
