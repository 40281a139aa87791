"""``rsvo_env.safety``, the path README and docs show: the module itself is
:mod:`rsvo_env.filter.safety`, and this name is that very module."""

import sys

from rsvo_env.filter import safety

sys.modules[__name__] = safety
