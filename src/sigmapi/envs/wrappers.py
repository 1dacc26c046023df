"""Observation wrappers: the state a learner sees.

Each wrapper turns the environment's ``{"retina", "gaze"}`` codes into one float32 feature
vector of L2 length 1 (so that one learning rate means the same for every state). They read
the environment through its interface only (:mod:`sigmapi.envs.protocols`): the observation
space (a ``Dict`` of 1-D ``Box`` codes), ``info["z"]`` for the oracle, and, where the world
offers them, its codes (``x_code``, ``y_code`` of a :class:`~sigmapi.envs.ViewSource`) to check
that a map reads them as it was trained. The gaze-and-reach world is one such environment,
not the only one.

- :class:`MapObservation`: the learned Sigma-Pi map's reading of ``(x, y)`` (the paper's
  route: "the output is a suitable input to a reinforcement-learnt network");
- :class:`CodeObservation`: the raw codes, the retina alone or retina and gaze side by side;
- :class:`TrueZObservation`: a population code of the true ``z`` from ``info`` (an oracle,
  the upper bound for a learner over linear features).

:func:`make_state_env` builds any of them by name (``"map"``, ``"retina"``, ``"retina_gaze"``,
``"true_z"``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.codes import PopulationCode, grid_coordinates
from sigmapi.envs.protocols import Obs, PlacedViewSource, ViewSource, check_view_space
from sigmapi.errors import ConfigError
from sigmapi.model.som import SigmaPiSOM

__all__ = [
    "FEATURES",
    "STATES",
    "STATE_WRAPPERS",
    "CodeObservation",
    "Features",
    "MapObservation",
    "TrueZObservation",
    "bump_features",
    "make_state_env",
]

FEATURES = ("response", "bump")
"""How the map's reading becomes features (see :class:`MapObservation`)."""

Features = NDArray[np.float32]
"""A state: one float32 feature vector of L2 length 1."""


def _codes_of(env: gym.Env[Any, Any]) -> ViewSource | None:
    """The world under ``env`` if it declares its codes (a view source), else None."""
    base = env.unwrapped
    return base if isinstance(base, ViewSource) else None


def _unit(v: NDArray[np.float64]) -> Features:
    norm = float(np.linalg.norm(v))
    return (v / norm if norm > 0 else v).astype(np.float32)


def bump_features(
    centres: NDArray[np.float64], coords: NDArray[np.float64], width: float
) -> NDArray[np.float64]:
    """Gaussian bumps ``exp(-|g_u - c|^2 / (2 width^2))`` on a grid, L2-normalised.

    ``centres`` ``(B, d)`` and ``coords`` ``(n, d)`` in grid units; returns ``(B, n)``.
    """
    d2 = ((coords[None, :, :] - centres[:, None, :]) ** 2).sum(axis=2)
    b = np.exp(-d2 / (2.0 * width**2))
    return b / np.linalg.norm(b, axis=1, keepdims=True)


class MapObservation(gym.ObservationWrapper[Features, Any, Obs]):
    """The observation becomes the Sigma-Pi map's reading of the retina and gaze codes.

    Parameters
    ----------
    env : gym.Env
        An environment whose ``"retina"`` and ``"gaze"`` codes are the model's (sizes
        checked on the observation space; the codes themselves, width included, where the
        world declares them as a :class:`~sigmapi.envs.ViewSource`).
    model : SigmaPiSOM
        A trained map (``sigmapi.load(path)`` or :func:`~sigmapi.envs.learn_map_in_env`).
    features : {"response", "bump"}
        ``"response"`` (default): the activations ``h_k`` clipped at 0 and L2-normalised, a
        sparse localized code of z (each unit is tuned to a patch of z, and a few
        neighbouring units carry the pattern); it degrades gracefully when the two views of
        a z pick neighbouring winners. ``"bump"``: a
        Gaussian bump of width ``width`` map units around the winning unit on the map grid
        (all-or-nothing per winner; relies on the map's topography for generalisation).
    width : float
        Width of the bump in map grid units.

    The result is L2-normalised: ``Box(0, 1, (n_units,), float32)``. Each step asks the model
    (``model.respond``, or ``model.winner`` for bumps), so it reads the model as it is then.
    """

    def __init__(
        self,
        env: gym.Env[Obs, Any],
        model: SigmaPiSOM,
        features: str = "response",
        width: float = 1.0,
    ):
        super().__init__(env)
        if features not in FEATURES:
            raise ConfigError(f"features must be one of {FEATURES}, got {features!r}")
        sizes = check_view_space(env.observation_space)
        for key, axis, code in (("retina", "x", model.x_code), ("gaze", "y", model.y_code)):
            if sizes[key] != code.size:
                raise ConfigError(
                    f"the map reads {axis} on {code.shape} units ({code.size} values) but the "
                    f"environment's {key!r} observation has {sizes[key]} values; make the "
                    f"environment with the map's codes ({axis} on {code.shape} units)"
                )
        source = _codes_of(env)
        if source is not None:
            for axis, mine, theirs in (
                ("x", model.x_code, source.x_code),
                ("y", model.y_code, source.y_code),
            ):
                if mine != theirs:
                    raise ConfigError(
                        f"the map was trained on {axis} codes {mine} but the environment codes "
                        f"{axis} as {theirs}; make the environment with the map's code (e.g. "
                        f"its width {mine.width})"
                    )
        self.model = model
        self.features = features
        self.width = _validate.width(
            "width", width, 0.0, lo_open=True, fix="in map grid units, e.g. 1.0"
        )
        self._coords = grid_coordinates(tuple(model.map_shape))
        self.observation_space = spaces.Box(0.0, 1.0, (model.n_units,), dtype=np.float32)

    def observation(self, observation: Obs) -> Features:
        x = np.asarray(observation["retina"], dtype=np.float64)[None, :]
        y = np.asarray(observation["gaze"], dtype=np.float64)[None, :]
        if self.features == "bump":
            k = self.model.winner(x, y)
            return bump_features(self._coords[k], self._coords, self.width)[0].astype(np.float32)
        return _unit(np.maximum(self.model.respond(x, y)[0], 0.0))


class CodeObservation(gym.ObservationWrapper[Features, Any, Obs]):
    """The raw codes as features: ``keys=("retina",)`` or ``("retina", "gaze")`` side by side.

    Concatenated, then L2-normalised: ``Box(0, 1, (sum of the entries' sizes,), float32)``. A
    learner linear in these features sums a function of x and a function of y; it cannot form
    their conjunction (what a Sigma-Pi unit computes).
    """

    def __init__(self, env: gym.Env[Obs, Any], keys: tuple[str, ...] = ("retina",)):
        super().__init__(env)
        keys = tuple(keys)
        if (
            not keys
            or any(k not in ("retina", "gaze") for k in keys)
            or len(set(keys)) != len(keys)
        ):
            raise ConfigError(f"keys must be distinct names from ('retina', 'gaze'), got {keys!r}")
        sizes = check_view_space(env.observation_space, keys)
        self.keys = keys
        self.observation_space = spaces.Box(0.0, 1.0, (sum(sizes.values()),), dtype=np.float32)

    def observation(self, observation: Obs) -> Features:
        v = np.concatenate([np.asarray(observation[k], dtype=np.float64) for k in self.keys])
        return _unit(v)


class TrueZObservation(gym.Wrapper[Features, Any, Any, Any]):
    """Oracle state: a Gaussian bump code of the true ``z`` (``info["z"]``) on a grid.

    Parameters
    ----------
    env : gym.Env
        An environment whose ``info`` holds ``"z"``, the body-centred position in
        ``[0, 1]^d`` (:mod:`sigmapi.envs.protocols`).
    shape : tuple of int, optional
        Grid of the code, one axis per dimension of ``z``; give the map's shape for a
        like-for-like comparison. Default: the grid of the world's retina code
        (``x_code.shape`` of a :class:`~sigmapi.envs.ViewSource`).
    width : float
        Width of the bump in grid units (as :class:`MapObservation`'s ``width``).

    ``z`` outside the workspace (a terminal step) is clipped to it.
    """

    def __init__(
        self, env: gym.Env[Obs, Any], shape: tuple[int, ...] | None = None, width: float = 1.0
    ):
        super().__init__(env)  # type: ignore[arg-type]  # (gymnasium's stubs bind the wrong type var)
        if shape is None:
            source = _codes_of(env)
            if source is None:
                raise ConfigError(
                    f"shape must be given: {type(env.unwrapped).__name__} declares no x_code "
                    "to take the grid from; pass e.g. shape=model.map_shape"
                )
            shape = source.x_code.shape
        self.code = PopulationCode(shape, width=1.0)
        base = env.unwrapped
        if isinstance(base, PlacedViewSource) and self.code.ndim != base.z_dim:
            raise ConfigError(
                f"shape must have {base.z_dim} axes for a {base.z_dim}-D z, got {shape!r}"
            )
        self.width = _validate.width(
            "width", width, 0.0, lo_open=True, fix="in grid units, e.g. 1.0"
        )
        self.observation_space = spaces.Box(0.0, 1.0, (self.code.size,), dtype=np.float32)

    def encode(self, z: NDArray[np.float64]) -> Features:
        """Features of positions ``z`` ``(B, d)`` (clipped to [0, 1]); ``(B, n)``."""
        g = np.clip(np.atleast_2d(z), 0.0, 1.0) * self.code.scale
        return bump_features(g, self.code.coords, self.width).astype(np.float32)

    def _features(self, info: dict[str, object]) -> Features:
        z = np.asarray(info.get("z", ()), dtype=np.float64)
        if z.shape != (self.code.ndim,):
            raise ConfigError(
                f"the true_z state reads info['z'], the body-centred position ({self.code.ndim} "
                f"numbers for a code on {self.code.shape}), got {info.get('z')!r}"
            )
        return self.encode(z)[0]

    def reset(
        self, *, seed: int | None = None, options: dict[str, object] | None = None
    ) -> tuple[Features, dict[str, object]]:
        _, info = self.env.reset(seed=seed, options=options)
        return self._features(info), info

    def step(self, action: object) -> tuple[Features, SupportsFloat, bool, bool, dict[str, object]]:
        _, r, terminated, truncated, info = self.env.step(action)
        return self._features(info), r, terminated, truncated, info


StateWrapper = Callable[[gym.Env[Obs, Any], SigmaPiSOM | None, str, float], gym.Env[Features, Any]]
"""Builds a state: ``(env, model, features, width) -> wrapped env``."""


def _map_state(
    env: gym.Env[Obs, Any], model: SigmaPiSOM | None, features: str, width: float
) -> gym.Env[Features, Any]:
    if model is None:
        raise ConfigError("state 'map' needs a trained model: pass model=sigmapi.load(path)")
    return MapObservation(env, model, features=features, width=width)


def _true_z_state(
    env: gym.Env[Obs, Any], model: SigmaPiSOM | None, features: str, width: float
) -> gym.Env[Features, Any]:
    shape = tuple(model.map_shape) if model is not None else None
    return TrueZObservation(env, shape=shape, width=width)


STATE_WRAPPERS: dict[str, StateWrapper] = {
    "map": _map_state,
    "retina": lambda env, model, features, width: CodeObservation(env, ("retina",)),
    "retina_gaze": lambda env, model, features, width: CodeObservation(env, ("retina", "gaze")),
    "true_z": _true_z_state,
}
"""The states a learner can observe, by name: one entry per state (:data:`STATES`)."""

STATES = tuple(STATE_WRAPPERS)
"""State representations compared by the experiment."""


def make_state_env(
    env: gym.Env[Obs, Any],
    state: str,
    model: SigmaPiSOM | None = None,
    features: str = "response",
    width: float = 1.0,
) -> gym.Env[Features, Any]:
    """Wrap ``env`` so that it observes ``state`` (one of :data:`STATES`).

    ``"map"`` needs ``model``; ``"true_z"`` codes z on the model's map grid when a model is
    given (like for like), else on the grid of the world's retina code.
    """
    if state not in STATE_WRAPPERS:
        raise ConfigError(f"state must be one of {STATES}, got {state!r}")
    return STATE_WRAPPERS[state](env, model, features, width)
