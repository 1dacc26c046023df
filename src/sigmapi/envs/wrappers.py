"""Observation wrappers: the state a learner sees in the gaze-and-reach task.

Each wrapper turns the environment's ``{"retina", "gaze"}`` codes into one float32 feature
vector of L2 length 1 (so that one learning rate means the same for every state):

- :class:`MapObservation`: the learned Sigma-Pi map's reading of ``(x, y)`` (the paper's
  route: "the output is a suitable input to a reinforcement-learnt network");
- :class:`CodeObservation`: the raw codes, the retina alone or retina and gaze side by side;
- :class:`TrueZObservation`: a population code of the true ``z`` from ``info`` (an oracle,
  the upper bound for a learner over linear features).

:func:`make_state_env` builds any of them by name (``"map"``, ``"retina"``, ``"retina_gaze"``,
``"true_z"``).
"""

from __future__ import annotations

from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.codes import PopulationCode, grid_coordinates
from sigmapi.envs.gaze_reach import GazeReachEnv, Obs
from sigmapi.errors import ConfigError
from sigmapi.som import SigmaPiSOM

__all__ = [
    "FEATURES",
    "STATES",
    "CodeObservation",
    "MapObservation",
    "TrueZObservation",
    "bump_features",
    "make_state_env",
]

STATES = ("map", "retina", "retina_gaze", "true_z")
"""State representations compared by the experiment."""
FEATURES = ("response", "bump")
"""How the map's reading becomes features (see :class:`MapObservation`)."""

Features = NDArray[np.float32]


def _base(env: gym.Env[Any, Any]) -> GazeReachEnv:
    base = env.unwrapped
    if not isinstance(base, GazeReachEnv):
        raise ConfigError(f"env must wrap a GazeReachEnv, got {type(base).__name__}")
    return base


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
        A (wrapped) :class:`GazeReachEnv` whose codes match the model's ``x_shape`` and
        ``y_shape`` (same grid, same code width).
    model : SigmaPiSOM
        A trained map (``sigmapi.load(path)`` or :func:`~sigmapi.envs.learn_map_in_env`).
    features : {"response", "bump"}
        ``"response"`` (default): the activations ``h_k`` clipped at 0 and L2-normalised, a
        sparse localized code of z (each unit is tuned to a patch of z; on a trained 7x7 map
        about 8 units carry the pattern, the top 4 hold 64 % of its energy); it degrades
        gracefully when the two views of a z pick neighbouring winners. ``"bump"``: a
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
        base = _base(env)
        if features not in FEATURES:
            raise ConfigError(f"features must be one of {FEATURES}, got {features!r}")
        shape = (base.grid,) * base.dim
        if tuple(model.x_shape) != shape or tuple(model.y_shape) != shape:
            raise ConfigError(
                f"the map reads x on {model.x_shape} and y on {model.y_shape} units but the "
                f"environment codes them on {shape}; make the env with grid={model.x_shape[0]}, "
                f"dim={len(model.x_shape)}"
            )
        if model.config.code_width != base.code_width:
            raise ConfigError(
                f"the map was trained on codes of width {model.config.code_width} but the env "
                f"uses code_width={base.code_width}; make the env with the model's width"
            )
        self.model = model
        self.features = features
        self.width = _validate.positive("width", width, fix="in map grid units, e.g. 1.0")
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

    Concatenated, then L2-normalised: ``Box(0, 1, (len(keys) * grid**dim,), float32)``. A
    learner linear in these features sums a function of x and a function of y; it cannot form
    their conjunction (what a Sigma-Pi unit computes).
    """

    def __init__(self, env: gym.Env[Obs, Any], keys: tuple[str, ...] = ("retina",)):
        super().__init__(env)
        base = _base(env)
        keys = tuple(keys)
        if (
            not keys
            or any(k not in ("retina", "gaze") for k in keys)
            or len(set(keys)) != len(keys)
        ):
            raise ConfigError(f"keys must be distinct names from ('retina', 'gaze'), got {keys!r}")
        self.keys = keys
        self.observation_space = spaces.Box(
            0.0, 1.0, (len(keys) * base.code.size,), dtype=np.float32
        )

    def observation(self, observation: Obs) -> Features:
        v = np.concatenate([np.asarray(observation[k], dtype=np.float64) for k in self.keys])
        return _unit(v)


class TrueZObservation(gym.Wrapper[Features, Any, Any, Any]):
    """Oracle state: a Gaussian bump code of the true ``z`` (from ``info``) on a grid.

    Parameters
    ----------
    env : gym.Env
        A (wrapped) :class:`GazeReachEnv`.
    shape : tuple of int, optional
        Grid of the code (default: ``(grid,) * dim`` of the env); give the map's shape for a
        like-for-like comparison.
    width : float
        Width of the bump in grid units (as :class:`MapObservation`'s ``width``).

    ``z`` outside the workspace (a terminal step) is clipped to it.
    """

    def __init__(
        self, env: gym.Env[Obs, Any], shape: tuple[int, ...] | None = None, width: float = 1.0
    ):
        super().__init__(env)  # type: ignore[arg-type]  # (gymnasium's stubs bind the wrong type var)
        base = _base(env)
        self.code = PopulationCode(
            shape if shape is not None else (base.grid,) * base.dim, width=1.0
        )
        if self.code.ndim != base.dim:
            raise ConfigError(
                f"shape must have {base.dim} axes for a {base.dim}-D task, got {shape!r}"
            )
        self.width = _validate.positive("width", width, fix="in grid units, e.g. 1.0")
        self.observation_space = spaces.Box(0.0, 1.0, (self.code.size,), dtype=np.float32)

    def encode(self, z: NDArray[np.float64]) -> Features:
        """Features of positions ``z`` ``(B, d)`` (clipped to [0, 1]); ``(B, n)``."""
        g = np.clip(np.atleast_2d(z), 0.0, 1.0) * self.code.scale
        return bump_features(g, self.code.coords, self.width).astype(np.float32)

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[Features, dict[str, Any]]:
        _, info = self.env.reset(seed=seed, options=options)
        return self.encode(info["z"])[0], info

    def step(self, action: Any) -> tuple[Features, SupportsFloat, bool, bool, dict[str, Any]]:
        _, r, terminated, truncated, info = self.env.step(action)
        return self.encode(info["z"])[0], r, terminated, truncated, info


def make_state_env(
    env: gym.Env[Obs, Any],
    state: str,
    model: SigmaPiSOM | None = None,
    features: str = "response",
    width: float = 1.0,
) -> gym.Env[Features, Any]:
    """Wrap ``env`` so that it observes ``state`` (one of :data:`STATES`).

    ``"map"`` needs ``model``; ``"true_z"`` codes z on the model's map grid when a model is
    given (like for like), else on the env's input grid.
    """
    if state == "map":
        if model is None:
            raise ConfigError("state 'map' needs a trained model: pass model=sigmapi.load(path)")
        return MapObservation(env, model, features=features, width=width)
    if state == "retina":
        return CodeObservation(env, ("retina",))
    if state == "retina_gaze":
        return CodeObservation(env, ("retina", "gaze"))
    if state == "true_z":
        shape = tuple(model.map_shape) if model is not None else None
        return TrueZObservation(env, shape=shape, width=width)
    raise ConfigError(f"state must be one of {STATES}, got {state!r}")
