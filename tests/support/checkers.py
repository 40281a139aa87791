"""PettingZoo's conformance tests as the suite calls them. Both API tests reset with an option
of their own (``{"options": 1}``, to check that ``reset`` takes the keyword); the env says once
that it reads no such option (a typo of ``theta`` must not pass silently), and here that
warning is asserted, not left in the run's output."""

from __future__ import annotations

from typing import Any

import pytest

THEIR_OPTION = r"reset options \['options'\] are not used by rsvo_env"


def checked(check: Any, env: Any, **kwargs: Any) -> None:
    """``check(env, **kwargs)`` (``parallel_api_test`` or ``api_test``), expecting the env's
    one warning about PettingZoo's own reset option."""
    with pytest.warns(UserWarning, match=THEIR_OPTION):
        check(env, **kwargs)
