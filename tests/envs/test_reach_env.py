"""The gaze-and-reach environment: Gymnasium API, rules on hand-built states, determinism."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.wrappers import TimeLimit

import sigmapi
from sigmapi.envs import ENV_ID, GazeReachConfig, GazeReachEnv, collect_saccade_views
from sigmapi.errors import ConfigError

# action indices: 0 stay, 1 +axis0, 2 -axis0, 3 +axis1, 4 -axis1
STAY, RIGHT, LEFT, UP, DOWN = range(5)


@pytest.mark.parametrize(
    "kwargs", [{"dim": 1}, {"dim": 2}, {"dim": 2, "diagonal": True, "saccade_rate": 0.3}]
)
def test_check_env_passes(kwargs: dict) -> None:
    check_env(GazeReachEnv(grid=7, **kwargs), skip_render_check=True)


def test_registered_id_makes_the_env_and_reimport_is_harmless() -> None:
    import importlib

    importlib.reload(sigmapi)  # registration is guarded against a second run
    env = gym.make(ENV_ID, dim=1, grid=7)
    obs, info = env.reset(seed=3)
    assert env.observation_space.contains(obs)
    assert set(info) >= {"z", "x", "y", "saccade", "event", "is_success"}
    env.close()


def test_import_sigmapi_alone_registers_the_id() -> None:
    code = (
        "import gymnasium, sigmapi, sys; assert 'sigmapi.envs' not in sys.modules; "
        "env = gymnasium.make('sigmapi/GazeReach-v0', dim=1, grid=7); env.reset(seed=0)"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr


def rollout(env: gym.Env, seed: int, n: int = 200) -> list:
    out = []
    obs, info = env.reset(seed=seed)
    actions = np.random.default_rng(99).integers(0, env.action_space.n, size=n)
    for a in actions:
        obs, r, term, trunc, info = env.step(int(a))
        out.append((obs["retina"].copy(), obs["gaze"].copy(), r, term, trunc, info["z"].copy()))
        if term or trunc:
            obs, info = env.reset()
    return out


def test_same_seed_same_rollout_other_seed_differs() -> None:
    a = rollout(GazeReachEnv(grid=7, saccade_rate=0.5), seed=5)
    b = rollout(GazeReachEnv(grid=7, saccade_rate=0.5), seed=5)
    c = rollout(GazeReachEnv(grid=7, saccade_rate=0.5), seed=6)
    for u, v in zip(a, b, strict=True):
        assert all(np.array_equal(p, q) for p, q in zip(u, v, strict=True))
    assert not all(np.array_equal(u[5], v[5]) for u, v in zip(a, c, strict=True))


def make(**kw) -> GazeReachEnv:
    kw.setdefault("grid", 7)
    kw.setdefault("step_size", 0.05)
    kw.setdefault("goal_radius", 0.1)
    return GazeReachEnv(**kw)


def test_reaching_the_goal_gives_plus_one_and_terminates() -> None:
    env = make(saccade_rate=0.0)
    env.reset(seed=0, options={"z": [0.65, 0.5], "y": [0.5, 0.5]})
    _, r, term, trunc, info = env.step(LEFT)  # z0 0.65 -> 0.60: on the goal box's edge
    assert (r, term, trunc, info["event"], info["is_success"]) == (
        1.0,
        True,
        False,
        "reached",
        True,
    )
    np.testing.assert_allclose(info["z"], [0.6, 0.5])


def test_a_step_that_misses_the_goal_gives_zero() -> None:
    env = make(saccade_rate=0.0)
    env.reset(seed=0, options={"z": [0.75, 0.5], "y": [0.5, 0.5]})
    _, r, term, trunc, info = env.step(LEFT)  # 0.70: still outside
    assert (r, term, trunc, info["event"]) == (0.0, False, False, "")


def test_leaving_the_workspace_gives_minus_0_3_and_terminates() -> None:
    env = make(saccade_rate=0.0)
    env.reset(seed=0, options={"z": [0.02, 0.5], "y": [0.0, 0.5]})
    obs, r, term, trunc, info = env.step(LEFT)  # z0 = -0.03: no gaze sees it any more
    assert (r, term, trunc, info["event"]) == (-0.3, True, False, "left_view")
    assert env.observation_space.contains(obs)


def test_time_limit_is_gymnasiums_and_termination_counts_on_the_last_step() -> None:
    env = TimeLimit(make(saccade_rate=0.0), max_episode_steps=3)
    env.reset(seed=0, options={"z": [0.8, 0.8], "y": [0.7, 0.7]})
    flags = [env.step(STAY)[2:4] for _ in range(3)]
    assert flags == [(False, False), (False, False), (False, True)]
    env.reset(seed=0, options={"z": [0.7, 0.5], "y": [0.5, 0.5]})
    env.step(LEFT)
    env.step(STAY)
    _, r, term, _, info = env.step(LEFT)  # reached on the last allowed step
    assert (r, term, info["is_success"]) == (1.0, True, True)
    raw = make(saccade_rate=0.0)  # the world alone never truncates
    raw.reset(seed=0, options={"z": [0.8, 0.8], "y": [0.7, 0.7]})
    assert not any(raw.step(STAY)[3] for _ in range(500))


def test_one_set_of_defaults_for_make_the_class_and_the_config() -> None:
    cfg = GazeReachConfig()
    made = gym.make(ENV_ID)
    assert made.spec.max_episode_steps == cfg.max_episode_steps == 50
    for env in (made.unwrapped, GazeReachEnv()):
        assert (env.dim, env.grid, env.code_width, env.step_size, env.goal_radius,
                env.saccade_rate) == (cfg.dim, cfg.grid, cfg.code_width, cfg.step_size,
                                      cfg.goal_radius, cfg.saccade_rate)  # fmt: skip
    assert (cfg.dim, cfg.grid, cfg.code_width) == (2, 15, 1.0)  # the reach experiment's
    built = cfg.make_env()
    assert isinstance(built, TimeLimit)
    assert built._max_episode_steps == cfg.max_episode_steps  # (TimeLimit has no public name)
    made.close()


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"max_episode_steps": 0}, r"max_episode_steps must be an int in \[1, 100000\], got 0"),
        ({"grid": 1}, "grid must be an int >= 2"),
        ({"goal_radius": 0.5}, "leave 5 % of the workspace outside the goal box"),
    ],
)
def test_config_checks_the_world_without_building_it(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        GazeReachConfig(**kwargs)


def test_no_saccade_keeps_gaze_and_a_move_off_the_retina_forces_one() -> None:
    env = make(saccade_rate=0.0)
    env.reset(seed=0, options={"z": [0.8, 0.3], "y": [0.6, 0.3]})  # x = (1.0, 0.3)
    _, _, _, _, info = env.step(STAY)
    assert not info["saccade"]
    np.testing.assert_allclose(info["y"], [0.6, 0.3])
    _, _, _, _, info = env.step(RIGHT)  # x0 would be 1.1: corrective saccade
    assert info["saccade"]
    assert np.all((info["x"] >= 0) & (info["x"] <= 1))
    np.testing.assert_allclose((info["x"] + info["y"]) / 2, info["z"])


def test_saccade_every_step_keeps_z_and_moves_the_eye() -> None:
    env = make(saccade_rate=1.0)
    _, info0 = env.reset(seed=1, options={"z": [0.3, 0.8]})
    _, _, _, _, info = env.step(STAY)
    assert info["saccade"]
    np.testing.assert_array_equal(info["z"], info0["z"])
    assert not np.array_equal(info["y"], info0["y"])


def test_observation_is_the_code_of_x_and_y() -> None:
    env = make(dim=2)
    obs, info = env.reset(seed=4)
    for _ in range(5):
        obs, *_, info = env.step(STAY)
        np.testing.assert_allclose(obs["retina"], env.code.encode(info["x"][None])[0], atol=1e-6)
        np.testing.assert_allclose(obs["gaze"], env.code.encode(info["y"][None])[0], atol=1e-6)
        assert obs["retina"].dtype == np.float32


def test_random_restart_never_starts_in_the_goal() -> None:
    env = make(dim=1, goal_radius=0.3)
    for s in range(50):
        _, info = env.reset(seed=s)
        assert abs(info["z"][0] - 0.5) > 0.3


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"dim": 3}, "dim must be 1 or 2"),
        ({"grid": 1}, "grid must be an int >= 2"),
        ({"saccade_rate": 1.5}, r"saccade_rate must be a number in \[0, 1\], got 1.5"),
        ({"step_size": 0.0}, "step_size"),
        ({"goal": [0.5, 2.0]}, "goal must be"),
        ({"dim": 1, "diagonal": True}, "diagonal"),
    ],
)
def test_constructor_errors_name_the_parameter(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        GazeReachEnv(**kwargs)


def test_bad_reset_options_and_actions_are_refused() -> None:
    env = make()
    with pytest.raises(ConfigError, match="off the retina"):
        env.reset(options={"z": [0.1, 0.1], "y": [0.9, 0.1]})
    with pytest.raises(ConfigError, match="unknown reset option"):
        env.reset(options={"goal": 1})
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action must be"):
        env.step(7)


def test_saccade_views_show_the_same_z() -> None:
    env = make(dim=2, saccade_rate=0.5)
    x0, y0, x1, y1 = collect_saccade_views(env, 40, seed=0)
    dec = env.code.decode
    z0 = (dec(x0) + dec(y0)) / 2
    z1 = (dec(x1) + dec(y1)) / 2
    np.testing.assert_allclose(z0, z1, atol=1e-3)
    assert np.abs(dec(y0) - dec(y1)).max() > 0.05  # the eye really moved


# ------------------------------------------------------- construction, stepping, rendering


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"goal_radius": 0.5}, "leave 5 % of the workspace outside the goal box"),
        ({"goal_radius": 0.48, "dim": 1}, "the box covers 96 %"),
        ({"code_width": 0.02}, "code_width must be a finite number >= 0.1, got 0.02"),
        ({"render_mode": "human"}, r"render_mode must be one of \(None, 'rgb_array'\)"),
    ],
)
def test_construction_refuses_what_would_hang_or_give_nan(kwargs, match) -> None:
    with pytest.raises(ConfigError, match=match):
        GazeReachEnv(**kwargs)


def test_observations_stay_in_the_box_at_the_narrowest_width() -> None:
    env = GazeReachEnv(grid=7, code_width=0.1, saccade_rate=0.5)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(2000):
        obs, _, terminated, truncated, _ = env.step(int(rng.integers(env.action_space.n)))
        assert env.observation_space.contains(obs), obs
        if terminated or truncated:
            env.reset()


def test_stepping_after_the_episode_ended_needs_reset() -> None:
    env = GazeReachEnv(dim=1, grid=7)
    with pytest.raises(gym.error.ResetNeeded):
        env.step(STAY)
    env.reset(seed=0, options={"z": [0.2], "y": [0.2]})
    terminated = False
    while not terminated:
        *_, terminated, _, _ = env.step(LEFT)  # walks out of view
    with pytest.raises(gym.error.ResetNeeded, match="call reset"):
        env.step(STAY)
    env.reset()
    env.step(STAY)


@pytest.mark.parametrize("dim", [1, 2])
def test_rgb_array_render_shows_workspace_goal_gaze_and_object(dim) -> None:
    env = gym.make(ENV_ID, dim=dim, grid=7, render_mode="rgb_array").unwrapped
    check_env(env)  # with the render check
    env.reset(seed=0, options={"z": [0.2] * dim, "y": [0.3] * dim})
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    colours = {tuple(c) for c in img.reshape(-1, 3)}
    assert {(225, 225, 225), (150, 220, 150), (40, 90, 220), (220, 40, 40)} <= colours
    red = np.argwhere(np.all(img == (220, 40, 40), axis=2))[:, 1].mean()
    green = np.argwhere(np.all(img == (150, 220, 150), axis=2))[:, 1].mean()
    assert red < green  # the object (z = 0.2) is drawn left of the goal (z = 0.5)
    assert GazeReachEnv(dim=dim, grid=7).render() is None


def test_saccade_views_cover_the_whole_workspace_goal_included() -> None:
    env = make(dim=1)
    x0, y0, _, _ = collect_saccade_views(env, 400, seed=1)
    z = (env.code.decode(x0) + env.code.decode(y0))[:, 0] / 2
    in_goal = np.abs(z - 0.5) <= env.goal_radius
    # the goal box is 20 % of the 1-D workspace: 80 expected of 400; 50 is 3.8 sd below
    assert in_goal.sum() >= 50
    assert z.min() < 0.05 and z.max() > 0.95
