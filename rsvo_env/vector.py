"""``rsvo_env.vector``, the path README and docs show: the module itself is
:mod:`rsvo_env.envs.vector`, and this name is that very module."""

import sys

from rsvo_env.envs import vector

sys.modules[__name__] = vector
