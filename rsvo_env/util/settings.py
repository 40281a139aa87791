"""What the layers below the filter read of its configuration.

[`FilterConfig`][rsvo_env.FilterConfig] is the one implementation. The bodies and the
dynamics models take it as a ``FilterSettings``, so that they never import the filter
layer above them (``docs/architecture.md``).
"""

from __future__ import annotations

from typing import Any, Protocol

from numpy.typing import NDArray


class FilterSettings(Protocol):
    """The filter's settings as a body or a dynamics model reads them (names as in
    ``FilterConfig``: ``gamma`` of Eq. (6), the box ``lo``/``hi``, the model's own)."""

    @property
    def gamma(self) -> float: ...
    @property
    def safety_radius(self) -> float: ...
    @property
    def dt(self) -> float | None: ...
    @property
    def barrier(self) -> str: ...
    @property
    def split(self) -> str: ...
    @property
    def gamma2(self) -> float | None: ...
    @property
    def lookahead(self) -> float | None: ...
    @property
    def w_max(self) -> float | None: ...
    @property
    def lo(self) -> NDArray: ...
    @property
    def hi(self) -> NDArray: ...
    @property
    def model(self) -> Any: ...  # the dynamics model (rsvo_env.dynamics.model.Dynamics)
