"""Hostile callers of every Gymnasium environment registered under ``sigmapi/``: one table of
bad actions and reset options, each refused with one ConfigError line, never a NaN reward, a
silent clip or a raw numpy error (round five of the hostile user: tests/cli/test_hostile_*.py).
"""

from __future__ import annotations

import os
import time

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

import sigmapi  # registers the environments
from sigmapi.errors import ConfigError

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported: headless rendering

IDS = sorted(k for k in gym.registry if k.startswith("sigmapi/"))
NAN = float("nan")


def test_the_table_covers_the_registered_environments():
    assert sigmapi.__name__ == "sigmapi"
    assert {"sigmapi/GazeReach-v0", "sigmapi/RobotDock-v0", "sigmapi/ICubReach-v0"} <= set(IDS)


@pytest.fixture(scope="module", params=IDS)
def env(request):
    """Each registered environment, made once (the MuJoCo ones take seconds)."""
    e = gym.make(request.param)
    e.reset(seed=0)
    yield e
    e.close()


def _bad_actions(space):
    if isinstance(space, spaces.Discrete):
        n = int(space.start + space.n)
        return [NAN, 1.5, -1, n, True, "0", None, [0], np.array([0, 1]), 1 + 0j]
    assert isinstance(space, spaces.Box), space
    shape, hi = space.shape, np.asarray(space.high, dtype=np.float64)
    mid = (np.asarray(space.low, dtype=np.float64) + hi) / 2
    bad = [np.full(shape, NAN), np.full(shape, np.inf), mid[..., :-1], np.append(mid, 0.0)]
    bad += [hi + 1.0, mid.astype(complex), "x", None, np.array(mid, dtype=object)]
    return bad


def _one_line(exc):
    text = str(exc.value)
    assert "\n" not in text and text, text
    return text


def test_every_bad_action_is_one_config_error(env):
    space = env.action_space
    for action in _bad_actions(space):
        env.reset(seed=1)
        start = time.perf_counter()
        with pytest.raises(ConfigError, match="action") as exc:
            env.step(action)
        assert time.perf_counter() - start < 2.0
        _one_line(exc)
    env.reset(seed=1)
    _, reward, *_ = env.step(space.sample())  # a good one still steps
    assert np.isfinite(float(reward))


BAD_VALUES = [NAN, [NAN] * 2, [NAN] * 3, [NAN] * 6, [NAN] * 7, [1e6] * 2, [100, 100], [-1e6] * 6,
              [], "x", [[0.5, 0.5]], {"a": 1}]  # fmt: skip


def test_every_bad_reset_option_is_one_config_error(env):
    names = type(env.unwrapped).reset_options
    for options in ({"not_an_option": 1}, [("z", 0.5)], "z"):
        with pytest.raises(ConfigError, match="reset option") as exc:
            env.reset(seed=2, options=options)
        _one_line(exc)
    for name in names:
        for value in BAD_VALUES:
            with pytest.raises(ConfigError, match=rf"options\['{name}'\]") as exc:
                env.reset(seed=2, options={name: value})
            _one_line(exc)
    obs, _ = env.reset(seed=2)  # the environment still works
    assert all(np.all(np.isfinite(v)) for v in obs.values())


def test_icub_reach_refuses_nan_and_far_balls():
    e = gym.make("sigmapi/ICubReach-v0")
    try:
        e.reset(seed=0)
        with pytest.raises(ConfigError, match="action must be finite"):
            e.step(np.full(7, NAN))  # was: reward 1.0, is_success True
        with pytest.raises(ConfigError, match=r"options\['gaze'\] must be finite"):
            e.reset(options={"gaze": [NAN] * 6})
        with pytest.raises(ConfigError, match=r"options\['ball'\].*table"):
            e.reset(options={"ball": (100, 100)})
        with pytest.raises(ConfigError, match="action must be"):
            e.step(np.full(7, 1.5))  # was: clipped silently
        ball = e.unwrapped.ball_region.mean(axis=1)
        _, info = e.reset(options={"ball": ball, "gaze": np.zeros(6)})
        np.testing.assert_allclose(info["ball"][:2], ball)
    finally:
        e.close()
