"""``rsvo_env.nominal``, the path README and docs show: the module itself is
:mod:`rsvo_env.control.nominal`, and this name is that very module."""

import sys

from rsvo_env.control import nominal

sys.modules[__name__] = nominal
