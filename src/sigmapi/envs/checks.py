"""The one validator of what a caller hands a Gymnasium environment of sigmapi: its actions and
its reset options.

Every environment registered under ``sigmapi/`` checks each action with :func:`check_action`
(finite, of the action space's shape, inside the space: a NaN never moves a robot, a value
outside the space is refused, never clipped unasked) and its reset options with
:func:`check_options` and :func:`check_vector` (known names; finite numbers of the right shape,
inside the workspace). A mistake is one :class:`~sigmapi.errors.ConfigError` line (a
``ValueError``) naming the environment's parameter, the constraint, the value and the fix.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate
from sigmapi.errors import ConfigError

__all__ = ["check_action", "check_options", "check_vector"]


def _shown(value: object) -> object:
    """``value`` as an error shows it: an array as a (short) list."""
    if isinstance(value, np.ndarray):
        flat = value.ravel().tolist()
        return [*flat[:8], "..."] if len(flat) > 8 else flat
    return value


def check_vector(
    name: str,
    value: object,
    shape: tuple[int, ...],
    low: ArrayLike,
    high: ArrayLike,
    *,
    fix: str = "",
    unit: str = "",
) -> NDArray[np.float64]:
    """``value`` as a float array of ``shape``, finite and inside ``[low, high]`` (each
    element's bounds broadcast to ``shape``); else one :class:`ConfigError` line."""
    lo = np.broadcast_to(np.asarray(low, dtype=np.float64), shape)
    hi = np.broadcast_to(np.asarray(high, dtype=np.float64), shape)
    where = f" {unit}" if unit else ""
    inside = (
        f"{int(np.prod(shape))} finite number(s){where} of shape {shape} in "
        f"[{_bounds(lo)}, {_bounds(hi)}]"
    )
    if isinstance(value, (str, bytes, Mapping)) or value is None:
        raise _validate.fail(name, inside, value, fix)
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        raise _validate.fail(name, inside, value, fix) from None
    if arr.dtype.kind not in "biuf" or arr.dtype.kind == "b":  # complex, object, bool, text
        raise _validate.fail(name, inside, _shown(arr), fix)
    arr = arr.astype(np.float64)
    if arr.shape != shape:
        raise _validate.fail(name, f"{inside} (got shape {arr.shape})", _shown(arr), fix)
    if not np.all(np.isfinite(arr)):
        raise _validate.fail(name, f"finite ({inside})", _shown(arr), fix)
    if np.any(arr < lo) or np.any(arr > hi):
        raise _validate.fail(name, inside, _shown(arr), fix)
    return arr


def _bounds(b: NDArray[np.float64]) -> str:
    """One bound of a box: a number when all agree, else the list (rounded)."""
    flat = np.unique(b)
    return f"{flat[0]:.4g}" if flat.size == 1 else str([round(float(v), 4) for v in b.ravel()])


def check_action(space: spaces.Space[Any], action: Any, fix: str = "") -> Any:
    """``action`` checked against the action ``space`` (a ``Discrete`` or a ``Box``): an int
    of the space (no bool, no float), or a finite array of the box's shape inside its bounds;
    returned as an ``int`` or a float array. Else one :class:`ConfigError` line."""
    if isinstance(space, spaces.Discrete):
        start, n = int(space.start), int(space.n)
        a = action
        if isinstance(a, np.ndarray) and a.shape == ():
            a = a[()]
        if not _validate.is_int(a) or not start <= int(a) < start + n:
            raise _validate.fail("action", f"an int in [{start}, {start + n})", _shown(action), fix)
        return int(a)
    if isinstance(space, spaces.Box):
        return check_vector(
            "action", action, tuple(space.shape), space.low, space.high, fix=fix
        ).astype(space.dtype)
    raise TypeError(f"no action check for a space of type {type(space).__name__}")


def check_options(
    options: Mapping[str, object] | None, allowed: Collection[str], env: str
) -> dict[str, object]:
    """The reset ``options`` of the environment ``env`` as a dict: a mapping whose names are
    among ``allowed`` (None: no options)."""
    if options is None:
        return {}
    if not isinstance(options, Mapping):
        raise ConfigError(
            f"{env} reset options must be a dict, got {_shown(options)!r}; e.g. "
            + (f"options={{{sorted(allowed)[0]!r}: ...}}" if allowed else "no options")
        )
    unknown = sorted(str(k) for k in options if k not in allowed)
    if unknown:
        valid = ", ".join(repr(a) for a in sorted(allowed)) or "none"
        raise ConfigError(
            f"unknown reset option {unknown[0][:60]!r} of {env}: options must be among "
            f"{valid}; leave {unknown[0][:60]!r} out"
        )
    return dict(options)
