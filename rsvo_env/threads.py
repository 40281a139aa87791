"""``rsvo_env.threads``, the path README and docs show: the module itself is
:mod:`rsvo_env.util.threads`, and this name is that very module."""

import sys

from rsvo_env.util import threads

sys.modules[__name__] = threads
