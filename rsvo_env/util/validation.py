"""Input checks shared by the filter, the world and the wrappers.

Every check raises ``ValueError`` whose message names the field, the agent index (or name) and
the offending value, and never repairs the input.
"""

from __future__ import annotations

import difflib
import math
import reprlib
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

# how long a value may stand in a message: an error names the value it refuses, and a message
# stays a line long whatever the value (a list of a million numbers, a nested alias bomb)
SHOWN_CHARS = 120
_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxstring, _SHORT.maxother = 3, SHOWN_CHARS, SHOWN_CHARS
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxdict = _SHORT.maxset = _SHORT.maxarray = 8


def shown(value: Any) -> str:
    """``repr(value)`` for a message, at most ``SHOWN_CHARS`` characters: containers cut after
    a few items and levels (``reprlib``, which never renders what it leaves out), the rest cut
    in the middle."""
    try:
        text = _SHORT.repr(value)
    except Exception:  # a value whose own repr fails is still named by its type
        text = f"<{type(value).__name__}>"
    if len(text) > SHOWN_CHARS:
        half = (SHOWN_CHARS - 3) // 2
        text = f"{text[:half]}...{text[-half:]}"
    return text


def unknown_keywords(owner: str, unknown: Sequence[str], known: Iterable[str]) -> str:
    """The message for keywords ``owner`` does not take: the list of them, the known one each
    most resembles, and the known ones listed while the message stays under 500 characters."""
    known = sorted(known)
    guesses = [
        f"{shown(k)} -> {shown(close[0])}"
        for k in list(unknown)[:4]
        for close in [difflib.get_close_matches(str(k), known, 1)]
        if close
    ]
    head = f"{owner} got unknown keyword argument(s) {shown(list(unknown))}"
    if guesses:
        head += f" (did you mean {', '.join(guesses)}?)"
    if len(head) > 220:
        head = f"{head[:200]}..."
    listing = ", ".join(known)
    if len(listing) > 250:
        listing = f"{listing[:220].rsplit(', ', 1)[0]}, ... ({len(known)} in all)"
    return f"{head}; known: {listing}"


@njit(cache=True)
def all_finite(a: NDArray) -> bool:
    """Whether every entry of a real array is finite (``np.isfinite(a).all()`` in one pass)."""
    for v in a.flat:
        if not np.isfinite(v):
            return False
    return True


def _label(index: int, names: Sequence[str] | None) -> str:
    if names is None:
        return f"agent {index}"
    return f"agent {shown(names[index])} (index {index})"


def real_array(values: ArrayLike, name: str) -> NDArray[np.float64]:
    """``values`` as float64, refusing what is not a real number: strings, bools, complex
    numbers and objects raise ``ValueError`` naming ``name`` (numpy would convert some of them
    silently: ``"1.5"`` to 1.5, ``True`` to 1.0, ``1+2j`` to 1.0)."""
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be real numbers, got {shown(values)}") from exc
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be real numbers, got {arr.dtype} values: {shown(values)}")
    return arr.astype(np.float64, copy=False)


def check_theta(
    theta: ArrayLike, name: str = "theta", allow_scalar: bool = False
) -> NDArray[np.float64]:
    """Personality scores: finite and >= 0 (paper, Sec. III-A: theta_i in R>=0)."""
    arr = real_array(theta, name)
    if arr.ndim == 0 and not allow_scalar:
        arr = arr.reshape(1)
    if not allow_scalar and arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of scores, got shape {arr.shape}")
    bad = ~np.isfinite(arr) | (arr < 0)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f"[{idx[0]}]" if len(idx) == 1 else (f"[{idx}]" if idx else "")
        value = arr[idx] if idx else arr
        raise ValueError(
            f"{name}{where} = {shown(float(value))}: a personality score must be finite and >= 0"
            + (f" (agent {idx[0]})" if len(idx) == 1 else "")
        )
    return arr


def check_theta_interval(value: ArrayLike, name: str, theta_max: float) -> tuple[float, float]:
    """A range of personality scores (low, high): finite, 0 < low <= high <= ``theta_max``."""
    arr = real_array(value, name)
    if arr.shape != (2,) or not np.isfinite(arr).all() or not 0 < arr[0] <= arr[1]:
        raise ValueError(f"{name} = {shown(value)} must be (low, high) with 0 < low <= high")
    if arr[1] > theta_max:
        raise ValueError(f"{name} = {shown(value)} exceeds the scenario's theta_max = {theta_max}")
    return float(arr[0]), float(arr[1])


def check_vectors(
    values: ArrayLike,
    name: str,
    n: int | None = None,
    names: Sequence[str] | None = None,
    lead: tuple[int, ...] | None = (),
    width: int = 2,
) -> NDArray[np.float64]:
    """An array of finite planar vectors (positions, velocities, actions), shape
    ``lead + (N, width)``: (N, 2) by default, (E, N, 2) with ``lead=(E,)``, either with
    ``lead=None``. The error names the env (when batched), the agent and the value."""
    arr = real_array(values, name)
    ok_lead = arr.ndim in (2, 3) if lead is None else arr.shape[:-2] == lead
    if (
        arr.ndim < 2
        or not ok_lead
        or arr.shape[-1] != width
        or (n is not None and arr.shape[-2] != n)
    ):
        rows = "N" if n is None else str(n)
        want = f"({', '.join([*map(str, lead or ()), rows])}, {width})"
        raise ValueError(f"{name} has shape {arr.shape}, expected {want}")
    if all_finite(arr):  # one compiled pass; the slow search below only names the culprit
        return arr
    bad = ~np.isfinite(arr).all(axis=-1)
    if bad.any():
        idx = tuple(int(i) for i in np.argwhere(bad)[0])
        i = idx[-1]
        env = f"env {idx[0]}, " if len(idx) == 2 else ""
        where = "".join(f"[{k}]" for k in idx)
        raise ValueError(
            f"{name}{where} = {arr[idx].tolist()} is not finite ({env}{_label(i, names)})"
        )
    return arr


def check_action(value: ArrayLike, agent: str, shape: tuple[int, ...] = (2,)) -> NDArray:
    """One agent's action: real numbers, the right shape, finite."""
    arr = real_array(value, f"action of agent {shown(agent)}")
    if arr.shape != shape:
        raise ValueError(f"action of agent {shown(agent)} has shape {arr.shape}, expected {shape}")
    if not np.isfinite(arr).all():
        raise ValueError(f"action of agent {shown(agent)} = {arr.tolist()} is not finite")
    return arr


def check_action_dict(
    actions: dict, agents: Sequence[str], shape: tuple[int, ...] = (2,)
) -> NDArray[np.float64]:
    """A PettingZoo action dict: exactly the live agents, each a finite action of ``shape``.

    Returns the actions stacked in ``agents`` order. The common case is checked in bulk; the
    per-agent checks run only to name the offender.
    """
    if not isinstance(actions, dict):
        raise ValueError(f"actions must be a dict keyed by agent name, got {shown(type(actions))}")
    # as many keys as live agents, each of them present: exactly the live agents
    values = [actions[a] for a in agents if a in actions]
    if len(actions) != len(agents) or len(values) != len(agents):
        live = set(agents)
        unknown = [a for a in actions if a not in live]
        if unknown:
            raise ValueError(
                f"unknown agent name {shown(unknown[0])} with action {shown(actions[unknown[0]])}; "
                f"live agents are {list(agents)}"
            )
        missing = [a for a in agents if a not in actions]
        raise ValueError(f"no action given for agent {shown(missing[0])}")
    out: NDArray | None
    try:
        out = np.array(values)
    except (TypeError, ValueError):
        out = None
    # numpy would turn a list of bools, or a bool array stacked with float ones, into numbers
    plain = all(type(v) is np.ndarray and v.dtype.kind in "uif" for v in values)
    if (
        not plain
        or out is None
        or out.dtype.kind not in "uif"
        or out.shape != (len(agents),) + shape
        or not all_finite(out)
    ):
        for agent in agents:
            check_action(actions[agent], agent, shape)
    assert out is not None  # else check_action refused an agent's action
    return out.astype(np.float64, copy=False)


def check_count(value: int, name: str, least: int) -> int:
    """An integer >= ``least`` (not a bool, a float or a string)."""
    integer = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if not integer or value < least:
        raise ValueError(f"{name} = {shown(value)} must be an integer >= {least}")
    return int(value)


def check_seed(seed: object, name: str = "seed") -> int | None:
    """None or an integer >= 0 (not a bool, a float such as 1.5 or 2.0, or a string), as
    Gymnasium's seeding takes it."""
    if seed is None:
        return None
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, (bool, np.bool_)) or seed < 0:
        raise ValueError(f"{name} = {shown(seed)} must be None or an integer >= 0")
    return int(seed)


def check_flag(value: bool, name: str) -> bool:
    """True or False (a bool or numpy bool; not a string such as ``"False"``, which is truthy,
    nor 0 and 1)."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name} = {shown(value)} must be True or False")
    return bool(value)


def check_positive(value: float, name: str) -> float:
    """A finite real number > 0 (not a bool or a string)."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise ValueError(f"{name} = {shown(value)} must be a finite number > 0")
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} = {shown(value)} must be a finite number > 0") from exc
    if not math.isfinite(v) or v <= 0:
        raise ValueError(f"{name} = {shown(value)} must be a finite number > 0")
    return v


def check_real(value: float, name: str) -> float:
    """A finite real number (not a bool, a string or a complex number)."""
    if isinstance(value, (bool, np.bool_, str, bytes, complex, np.complexfloating)):
        raise ValueError(f"{name} = {shown(value)} must be a finite real number")
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} = {shown(value)} must be a finite real number") from exc
    if not math.isfinite(v):
        raise ValueError(f"{name} = {shown(value)} must be a finite real number")
    return v


def check_values(name: str, params: dict[str, Any], defaults: dict[str, Any]) -> None:
    """Each parameter of the type its default has: a flag True or False, a real number finite
    (converted to float in ``params``), a tuple of the default's shape and finite; a NaN
    would only surface later, as an error naming no field. ``name`` is the scenario's."""
    for key, default in defaults.items():
        if isinstance(default, bool):
            if not isinstance(params[key], (bool, np.bool_)):
                raise ValueError(f"{name}.{key} = {shown(params[key])} must be True or False")
        elif isinstance(default, float):
            params[key] = check_real(params[key], f"{name}.{key}")
        elif isinstance(default, tuple):
            arr = real_array(params[key], f"{name}.{key}")
            if arr.shape != np.shape(default):
                raise ValueError(
                    f"{name}.{key} = {shown(params[key])} has shape {arr.shape}, expected "
                    f"{np.shape(default)}"
                )
            if not np.isfinite(arr).all():
                raise ValueError(f"{name}.{key} = {shown(params[key])} must be finite")
