"""The environment layer's interface: a world that is not sigmapi's trains a map through the
view-source protocol and a learner through the wrappers; what breaks the interface is refused
with an error that says what was found."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from gymnasium.wrappers import TimeLimit

from sigmapi import PopulationCode, SigmaPiSOM, SOMConfig
from sigmapi.agents import ActorCriticConfig, actor_critic_for, run_episodes
from sigmapi.envs import (
    STATES,
    CodeObservation,
    MapObservation,
    PlacedViewSource,
    TrueZObservation,
    ViewSource,
    check_view_space,
    collect_saccade_views,
    learn_map_in_env,
    make_state_env,
    view_source,
)
from sigmapi.errors import ConfigError
from sigmapi.experiments.reach.run import value_over_z


class LineWorld(gym.Env):
    """A third party's world, written against Gymnasium and the documented interface only.

    A 1-D body: the object at ``z`` in [0, 1], the eye at ``y``, the retina sees ``x = z - y +
    0.5`` (another relation than the gaze-and-reach world's), all coded on 9 units. Actions:
    stay, left, right; success within 0.1 of the middle, failure once the object leaves the
    line. No time limit of its own (``TimeLimit`` adds one).
    """

    def __init__(self, n: int = 9) -> None:
        self._code = PopulationCode((n,), width=1.0)
        self.observation_space = spaces.Dict(
            {
                "retina": spaces.Box(0.0, 1.0, (n,), dtype=np.float32),
                "gaze": spaces.Box(0.0, 1.0, (n,), dtype=np.float32),
            }
        )
        self.action_space = spaces.Discrete(3)
        self._z = 0.5
        self._y = 0.5

    # the view-source protocol
    @property
    def x_code(self) -> PopulationCode:
        return self._code

    @property
    def y_code(self) -> PopulationCode:
        return self._code

    @property
    def z_dim(self) -> int:
        return 1

    def views_of(self, z: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = np.maximum(z - 0.5, 0.0), np.minimum(z + 0.5, 1.0)  # keep x in [0, 1]
        y = lo + (hi - lo) * rng.random(z.shape)
        return self._code.encode(z - y + 0.5), self._code.encode(y)

    def sample_views(self, n: int, rng: np.random.Generator):
        z = rng.random((n, 1))
        x0, y0 = self.views_of(z, rng)
        x1, y1 = self.views_of(z, rng)
        return x0, y0, x1, y1

    # the Gymnasium API
    def _obs(self) -> dict[str, np.ndarray]:
        z = np.clip(np.array([[self._z]]), 0.0, 1.0)
        x, y = self._code.encode(np.clip(z - self._y + 0.5, 0, 1)), self._code.encode([[self._y]])
        return {"retina": x[0].astype(np.float32), "gaze": y[0].astype(np.float32)}

    def _info(self, success: bool) -> dict[str, Any]:
        return {"z": np.array([self._z]), "is_success": success}

    def _look(self) -> None:
        z = float(np.clip(self._z, 0.0, 1.0))
        self._y = float(self.np_random.uniform(max(z - 0.5, 0.0), min(z + 0.5, 1.0)))

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self._z = float(self.np_random.choice([self.np_random.uniform(0, 0.4),
                                               self.np_random.uniform(0.6, 1)]))  # fmt: skip
        self._look()
        return self._obs(), self._info(False)

    def step(self, action: Any):
        self._z += (0.0, -0.05, 0.05)[int(action)]
        success = abs(self._z - 0.5) <= 0.1
        failed = not 0.0 <= self._z <= 1.0
        self._look()
        return self._obs(), 1.0 if success else -0.3 if failed else 0.0, success or failed, False, (
            self._info(success)
        )  # fmt: skip


def test_a_third_party_world_trains_a_map_and_a_learner_through_the_interface() -> None:
    world = LineWorld()
    assert isinstance(world, ViewSource) and isinstance(world, PlacedViewSource)
    cfg = SOMConfig(map_shape=(8,), x_shape=(9,), y_shape=(9,), code_width=1.0,
                    iterations=3000, backend="reference", seed=1)  # fmt: skip
    model = learn_map_in_env(TimeLimit(world, 30), cfg, seed=0)  # wrapped: the world is found
    assert model.t_ == 3000

    # the map learned the world's z without being told: the two views of a z mostly share a
    # winner (chance: 1 in 8); threshold well below what an ordered map gives
    x0, y0, x1, y1 = collect_saccade_views(world, 500, seed=9)
    same = np.mean(model.winner(x0, y0) == model.winner(x1, y1))
    assert same > 0.5, same

    starts = np.arange(40)
    for state in STATES:
        env = make_state_env(TimeLimit(LineWorld(), 30), state, model)
        agent = actor_critic_for(env, ActorCriticConfig(), seed=np.random.default_rng(0))
        ep = run_episodes(env, agent, starts)
        assert ep.success.shape == ep.failed.shape == ep.steps.shape == (40,)
        assert not np.any(ep.success & ep.failed) and np.all(ep.steps >= 1)
        axis, v = value_over_z(agent, env, n=11)
        assert axis.shape == v.shape == (11,) and np.all(np.isfinite(v))
    assert make_state_env(TimeLimit(LineWorld(), 30), "true_z").observation_space.shape == (9,)


class Blind(gym.Env):
    """A world that declares no codes and has a Box observation: what the wrappers refuse."""

    def __init__(self, space: spaces.Space) -> None:
        self.observation_space = space
        self.action_space = spaces.Discrete(2)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action):
        return self.observation_space.sample(), 0.0, False, False, {}


def test_the_interface_refuses_what_it_cannot_read() -> None:
    with pytest.raises(ConfigError, match="must be a Dict with entries"):
        CodeObservation(Blind(spaces.Box(0, 1, (9,))))
    flat = spaces.Dict({"retina": spaces.Box(0, 1, (3, 3)), "gaze": spaces.Box(0, 1, (9,))})
    with pytest.raises(ConfigError, match="entry 'retina' must be a 1-D Box"):
        check_view_space(flat)
    with pytest.raises(ConfigError, match="must be a view source"):
        view_source(Blind(spaces.Box(0, 1, (9,))))
    good = spaces.Dict({"retina": spaces.Box(0, 1, (9,)), "gaze": spaces.Box(0, 1, (9,))})
    with pytest.raises(ConfigError, match="shape must be given"):
        TrueZObservation(Blind(good))
    with pytest.raises(ConfigError, match=r"reads info\['z'\]"):
        TrueZObservation(Blind(good), shape=(5,)).reset(seed=0)
    with pytest.raises(ConfigError, match="shape must have 1 axes for a 1-D z"):
        TrueZObservation(LineWorld(), shape=(3, 3))
    model = SigmaPiSOM(map_shape=(4,), x_shape=(9,), y_shape=(9,), backend="reference")
    assert MapObservation(Blind(good), model).observation_space.shape == (4,)  # sizes suffice
    with pytest.raises(ConfigError, match="trained on x codes"):
        MapObservation(LineWorld(), model)  # the world declares codes of width 1.0, not 0.5


def test_views_of_the_wrong_shape_and_a_mismatched_map_are_refused() -> None:
    class Short(LineWorld):
        def sample_views(self, n, rng):
            x0, y0, x1, y1 = super().sample_views(n, rng)
            return x0[:-1], y0, x1, y1

    with pytest.raises(ConfigError, match=r"gave x0 of shape \(9, 9\), expected \(10, 9\)"):
        collect_saccade_views(Short(), 10, seed=0)
    wrong = SOMConfig(map_shape=(4,), x_shape=(7,), y_shape=(9,), code_width=1.0, iterations=5)
    with pytest.raises(ConfigError, match="the map codes x as"):
        learn_map_in_env(LineWorld(), wrong)
