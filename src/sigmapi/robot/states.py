"""The states a learner sees on the robot: the map's response, the codes, or the true z.

These wrappers depend on the observation space alone (a ``Dict`` with ``retina`` and ``gaze``
``Box`` entries, the codes), never on the environment's class; ``true_z`` reads ``info["z"]``
(a position in ``[0, 1]^d``). Each gives a float32 feature vector of L2 length 1, as the
gaze-and-reach wrappers (:mod:`sigmapi.reach.wrappers`) do for their world; when the
environments' own protocol (issue 20, ``sigmapi.envs``) lands, these give way to its wrappers.
"""

from __future__ import annotations

from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from sigmapi.codes import PopulationCode
from sigmapi.errors import ConfigError
from sigmapi.reach.wrappers import STATES, bump_features
from sigmapi.som import SigmaPiSOM

__all__ = ["STATES", "code_sizes", "make_state"]

Features = NDArray[np.float32]


def code_sizes(space: gym.Space[Any]) -> tuple[int, int]:
    """The sizes of the ``retina`` and ``gaze`` codes of an observation space; a ConfigError
    naming what is missing when the space is not a Dict of two 1-D Boxes with those keys."""
    if not isinstance(space, spaces.Dict) or {"retina", "gaze"} - set(space.spaces):
        raise ConfigError(
            f"the observation space must be a Dict with 'retina' and 'gaze' entries, got {space}"
        )
    sizes = []
    for key in ("retina", "gaze"):
        box = space.spaces[key]
        if not isinstance(box, spaces.Box) or len(box.shape) != 1:
            raise ConfigError(f"observation {key!r} must be a 1-D Box (a code), got {box}")
        sizes.append(int(box.shape[0]))
    return sizes[0], sizes[1]


def _unit(v: NDArray[np.float64]) -> Features:
    norm = float(np.linalg.norm(v))
    return (v / norm if norm > 0 else v).astype(np.float32)


class _Features(gym.ObservationWrapper[Features, Any, Any]):
    """Features computed from the ``{"retina", "gaze"}`` codes by ``fn`` (``(x, y) -> (n,)``)."""

    def __init__(self, env: gym.Env[Any, Any], n: int, fn: Any) -> None:
        super().__init__(env)
        code_sizes(env.observation_space)
        self._fn = fn
        self.observation_space = spaces.Box(0.0, 1.0, (n,), dtype=np.float32)

    def observation(self, observation: Any) -> Features:
        x = np.asarray(observation["retina"], dtype=np.float64)
        y = np.asarray(observation["gaze"], dtype=np.float64)
        return _unit(self._fn(x, y))


class _TrueZ(gym.Wrapper[Features, Any, Any, Any]):
    """Oracle: a bump code of ``info["z"]`` (clipped to ``[0, 1]^d``) on the grid ``shape``."""

    def __init__(self, env: gym.Env[Any, Any], shape: tuple[int, ...]) -> None:
        super().__init__(env)
        self.code = PopulationCode(shape, width=1.0)
        self.observation_space = spaces.Box(0.0, 1.0, (self.code.size,), dtype=np.float32)

    def encode(self, z: NDArray[np.float64]) -> Features:
        g = np.clip(np.atleast_2d(z), 0.0, 1.0) * self.code.scale
        return bump_features(g, self.code.coords, 1.0)[0].astype(np.float32)

    def reset(self, **kwargs: Any) -> tuple[Features, dict[str, Any]]:
        _, info = self.env.reset(**kwargs)
        return self.encode(info["z"]), info

    def step(self, action: Any) -> tuple[Features, SupportsFloat, bool, bool, dict[str, Any]]:
        _, r, terminated, truncated, info = self.env.step(action)
        return self.encode(info["z"]), r, terminated, truncated, info


def make_state(
    env: gym.Env[Any, Any], state: str, model: SigmaPiSOM | None = None
) -> gym.Env[Features, Any]:
    """Wrap ``env`` so that it observes ``state``, one of :data:`STATES`.

    ``"map"``: the map's response ``max(h, 0)`` to the two codes, L2-normalised (needs
    ``model``, whose ``x_shape`` and ``y_shape`` must match the codes' sizes); ``"retina"``:
    the retina code; ``"retina_gaze"``: the two codes side by side; ``"true_z"``: a bump code
    of the true z on the map's grid (``model``'s, else 8 x 8).
    """
    n_x, n_y = code_sizes(env.observation_space)
    if state == "map":
        if model is None:
            raise ConfigError("state 'map' needs a trained model")
        if (int(np.prod(model.x_shape)), int(np.prod(model.y_shape))) != (n_x, n_y):
            raise ConfigError(
                f"the map reads codes of {model.x_shape} and {model.y_shape} units but the "
                f"environment's have {n_x} and {n_y}; make them on the same grid"
            )

        def respond(x: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
            assert model is not None
            return np.maximum(model.respond(x[None, :], y[None, :])[0], 0.0)

        return _Features(env, model.n_units, respond)
    if state == "retina":
        return _Features(env, n_x, lambda x, y: x)
    if state == "retina_gaze":
        return _Features(env, n_x + n_y, lambda x, y: np.concatenate([x, y]))
    if state == "true_z":
        return _TrueZ(env, tuple(model.map_shape) if model is not None else (8, 8))
    raise ConfigError(f"state must be one of {STATES}, got {state!r}")
