"""The simulation core: ``Simulator`` (E envs x N agents as arrays) and the stages of its step."""
