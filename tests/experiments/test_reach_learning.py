"""Wrappers, the actor-critic, the experiment and the ``sigmapi reach`` command."""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.agents import ActorCritic, ActorCriticConfig, actor_critic_for, run_episodes
from sigmapi.cli import main
from sigmapi.envs import (
    CodeObservation,
    GazeReachEnv,
    MapObservation,
    TrueZObservation,
    make_state_env,
)
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor
from sigmapi.experiments.reach.config import (
    SMALL_PRESET,
    MapConfig,
    ReachConfig,
    ReachRunConfig,
    preset_setting,
)
from sigmapi.experiments.reach.figures import plot_reach_curves, plot_value_function, reach_figure
from sigmapi.experiments.reach.result import ReachResult
from sigmapi.experiments.reach.run import PLAN, REACH


@pytest.fixture(scope="module")
def tiny_map() -> SigmaPiSOM:
    som = SigmaPiSOM(
        map_shape=(4, 4), x_shape=(5, 5), y_shape=(5, 5), code_width=1.0, iterations=300,
        sigma=((0.0, 2.0), (0.8, 0.7)), backend="reference", seed=0,
    )  # fmt: skip
    return som.fit()


def test_actor_critic_td_step_by_hand() -> None:
    ac = ActorCritic(n_features=2, n_actions=2, gamma=0.9, critic_lr=0.1, actor_lr=0.1, seed=0)
    ac.v_[:] = [0.5, 1.0]
    s, s2 = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    delta = ac.update(s, 1, 0.0, s2, terminated=False)  # 0 + 0.9 * 1.0 - 0.5
    assert delta == pytest.approx(0.4)
    np.testing.assert_allclose(ac.v_, [0.54, 1.0])
    np.testing.assert_allclose(ac.w_, [[0.0, 0.0], [0.04, 0.0]])
    delta = ac.update(s2, 0, -0.3, s, terminated=True)  # terminal: no bootstrap
    assert delta == pytest.approx(-1.3)


def test_actor_critic_softmax_and_seeded_choices() -> None:
    ac = ActorCritic(3, 3, beta=2.0, seed=1)
    ac.w_[:, 0] = [0.0, 1.0, 0.0]
    p = ac.policy([1.0, 0.0, 0.0])
    np.testing.assert_allclose(p, np.exp([0, 2, 0]) / np.exp([0, 2, 0]).sum())
    a = [ActorCritic(3, 3, seed=7).act([1, 0, 0]) for _ in range(2)]
    assert a[0] == a[1]
    with pytest.raises(ConfigError, match="gamma must be a number in"):
        ActorCritic(3, 3, gamma=1.5)
    with pytest.raises(ConfigError, match="beta must be a number in"):
        ActorCriticConfig(beta=-1)
    assert ActorCritic(3, 3).config == ActorCriticConfig()  # one set of defaults


def test_the_episode_loop_refuses_what_the_actor_critic_cannot_learn() -> None:
    env = make_state_env(ReachConfig().env.make_env(), "retina")
    boxed = gym.wrappers.TransformAction(
        env, lambda a: 0, gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
    )
    with pytest.raises(ConfigError, match="discrete actions, but the environment's action"):
        actor_critic_for(boxed, ActorCriticConfig())
    with pytest.raises(ConfigError, match="1-D Box observation"):
        actor_critic_for(ReachConfig().env.make_env(), ActorCriticConfig())
    with pytest.raises(ConfigError, match="discrete actions"):
        run_episodes(boxed, ActorCritic(10, 2), [0])


def test_wrappers_give_unit_float32_features_in_their_space(tiny_map: SigmaPiSOM) -> None:
    # (check_env itself runs on the unwrapped env: it warns about any wrapper by design)
    for state in ("map", "retina", "retina_gaze", "true_z"):
        env = make_state_env(GazeReachEnv(grid=5), state, tiny_map)
        obs, _ = env.reset(seed=0)
        for a in [1, 2, 3, 4, 0] * 4:
            assert obs.dtype == np.float32 and env.observation_space.contains(obs)
            assert np.linalg.norm(obs) == pytest.approx(1.0, abs=1e-5)
            obs, _, term, trunc, _ = env.step(a)
            if term or trunc:
                obs, _ = env.reset()
    assert make_state_env(GazeReachEnv(grid=5), "retina_gaze").observation_space.shape == (50,)
    assert make_state_env(GazeReachEnv(grid=5), "true_z", tiny_map).observation_space.shape == (16,)


def test_map_bump_is_centred_on_the_models_winner(tiny_map: SigmaPiSOM) -> None:
    env = MapObservation(GazeReachEnv(grid=5), tiny_map, features="bump", width=0.5)
    obs, _ = env.reset(seed=2)
    raw, _ = GazeReachEnv(grid=5).reset(seed=2)  # what the wrapper read
    k = tiny_map.winner(raw["retina"][None].astype(float), raw["gaze"][None].astype(float))[0]
    assert int(np.argmax(obs)) == k
    resp = MapObservation(GazeReachEnv(grid=5), tiny_map, features="response").observation(raw)
    h = np.maximum(
        tiny_map.respond(raw["retina"][None].astype(float), raw["gaze"][None].astype(float))[0], 0
    )
    np.testing.assert_allclose(resp, h / np.linalg.norm(h), rtol=1e-5)


def test_wrapper_errors(tiny_map: SigmaPiSOM) -> None:
    with pytest.raises(ConfigError, match=r"the map reads x on \(5, 5\) units \(25 values\)"):
        MapObservation(GazeReachEnv(grid=7), tiny_map)
    with pytest.raises(ConfigError, match="make the environment with the map's code"):
        MapObservation(GazeReachEnv(grid=5, code_width=0.5), tiny_map)
    with pytest.raises(ConfigError, match="keys must be"):
        CodeObservation(GazeReachEnv(grid=5), ("retina", "nose"))
    with pytest.raises(ConfigError, match="needs a trained model"):
        make_state_env(GazeReachEnv(grid=5), "map")
    with pytest.raises(ConfigError, match="state must be one of"):
        make_state_env(GazeReachEnv(grid=5), "z")
    with pytest.raises(ConfigError, match="width must be"):
        TrueZObservation(GazeReachEnv(grid=5), width=0)


TINY = {"dim": 1, "grid": 7, "map_shape": (6,), "iterations": 500, "episodes": 20, "block": 10,
        "final_episodes": 10, "max_episode_steps": 30, "backend": "reference"}  # fmt: skip


def test_experiment_is_deterministic_and_shapes_are_right(tmp_path) -> None:
    cfg = ReachConfig().replace(**TINY)
    a = REACH.run(cfg, seeds=[0, 1])
    b = REACH.run(cfg, seeds=[0, 1], executor=Executor(workers=2))  # two processes
    for s in a.success:
        assert a.success[s].shape == (2, 20)
        np.testing.assert_array_equal(a.success[s], b.success[s])
        np.testing.assert_array_equal(a.steps[s], b.steps[s])
        np.testing.assert_array_equal(a.values[s], b.values[s])
    assert a.map_metrics == b.map_metrics
    assert set(a.final_success()) == {"map", "retina", "retina_gaze", "true_z"}
    assert a.values["map"].shape == (51,)
    c = a.curves()["true_z"]
    assert c["success"].shape == (2,)
    d = a.to_dict()
    back = json.loads(json.dumps(d))
    assert ReachResult.from_dict(back).to_dict() == back  # result.json reads back
    assert set(d) == {"success", "success_per_seed", "lost", "timed_out", "ratio_map_to_true_z",
                      "final_rise", "final_rise_se", "levelled_off", "curves", "map_metrics",
                      "config", "seconds"}  # fmt: skip
    assert d["config"]["seeds"] == [0, 1] and d["config"]["map"]["iterations"] == 500
    assert set(d["config"]) == {"env", "map", "agent", "run", "seeds"}
    for s in a.success:  # counted: never a rounding residue such as -8.7e-17
        last = ~a.success[s][:, -10:] & ~a.lost[s][:, -10:]
        assert d["timed_out"][s] == last.sum() / last.size  # exactly, not 1 - success - lost
        assert d["success"][s] + d["lost"][s] + d["timed_out"][s] == pytest.approx(1.0)
    assert "final success rate over the last 10 of 20 episodes, 2 seeds:" in a.table()
    fig = reach_figure(a)
    assert len(fig.axes) >= 6
    assert plot_reach_curves(a, "steps") is not None
    assert plot_value_function(a, "true_z") is not None
    assert a.figure(tmp_path) == [tmp_path / "reach.png"] and (tmp_path / "reach.png").is_file()


def test_a_seed_draws_the_same_streams_alone_or_beside_others() -> None:
    cfg = ReachConfig().replace(**TINY, states=("retina",))
    both = REACH.run(cfg, seeds=[0, 1])
    second = REACH.run(cfg, seeds=[1])
    np.testing.assert_array_equal(both.steps["retina"][1], second.steps["retina"][0])
    assert not np.array_equal(both.steps["retina"][0], second.steps["retina"][0])
    assert PLAN.sequence(1, "starts").spawn_key == (6,)  # child (key,) of SeedSequence(1)
    for bad in ([], [0, 0], [-1]):
        with pytest.raises(ConfigError, match="seeds must"):
            REACH.run(cfg, seeds=bad)


def test_true_z_learner_learns_to_reach_1d() -> None:
    """Upper-bound learner in the 1-D task: success rises well above its first block."""
    cfg = ReachConfig().replace(dim=1, grid=7, episodes=150, block=50, final_episodes=50,
                                states=("true_z",))  # fmt: skip
    c = REACH.run(cfg, seeds=[0]).curves()["true_z"]["success"]
    assert c[-1] >= 0.8 and c[-1] > c[0]


def test_reach_config_parts_check_their_fields() -> None:
    with pytest.raises(ConfigError, match="final_episodes must be <= episodes"):
        ReachRunConfig(episodes=10, final_episodes=20)
    with pytest.raises(ConfigError, match="states must be distinct names"):
        ReachRunConfig(states=("map", "eye"))
    with pytest.raises(ConfigError, match="unknown reach config field 'episode'"):
        ReachConfig().replace(episode=3)
    with pytest.raises(ConfigError, match="preset must be one of"):
        MapConfig(preset="paper-3d")
    with pytest.raises(ConfigError, match="feature_width must be"):
        MapConfig(feature_width=0)
    with pytest.raises(ConfigError, match="env must be a GazeReachConfig"):
        ReachConfig(env=MapConfig())  # type: ignore[arg-type]
    cfg = ReachConfig().replace(grid=7, episodes=250, gamma=0.5, iterations=10)
    assert (cfg.env.grid, cfg.run.episodes, cfg.agent.gamma, cfg.map.iterations) == (
        7, 250, 0.5, 10)  # fmt: skip


def test_the_map_learns_with_the_paper_2d_preset_or_the_small_map_schedule() -> None:
    from sigmapi import load_preset

    cfg = ReachConfig()
    som = cfg.som_config(seed=3)
    p2 = load_preset("paper-2d")
    assert (som.map_shape, som.x_shape, som.y_shape) == ((15, 15),) * 3
    assert som.code_width == cfg.env.code_width == p2.code_width
    for name in ("winner_rule", "ordering", "ordering_sigma", "kernel_tol", "eps", "sigma"):
        assert getattr(som, name) == getattr(p2, name), name
    assert (som.iterations, som.seed, som.backend) == (cfg.map.iterations, 3, "auto")
    small = ReachConfig().replace(**preset_setting(SMALL_PRESET)).som_config(seed=3)
    assert small.map_shape == (7, 7) and small.x_shape == (7, 7) and small.code_width == 0.5
    assert small.winner_rule == "soft" and small.iterations == 10_000


def test_the_small_preset_is_the_small_map_schedule_it_replaced():
    """What ``preset="none"`` built for the 7x7 setting before its schedule became the preset
    small-2d: the default config on the world's codes, with sigma 7 -> 2 at 30 % -> 0.7 at
    80 % (the neighbourhood from the map's size to 30 % of it, then to 0.7 units)."""
    cfg = ReachConfig().replace(**preset_setting(SMALL_PRESET))
    assert (cfg.env.grid, cfg.env.code_width, cfg.map.map_shape) == (7, 0.5, (7, 7))
    codes = {"x_shape": (7, 7), "y_shape": (7, 7), "code_width": 0.5, "seed": 3}
    before = SOMConfig(map_shape=(7, 7), iterations=10_000, **codes,
                       sigma=((0.0, 7.0), (0.3, 2.0), (0.8, 0.7)))  # fmt: skip
    got, want = cfg.som_config(seed=3).to_dict(), before.to_dict()
    got.pop("extra"), want.pop("extra")
    assert got == want
    with pytest.raises(ConfigError, match="preset must be one of"):
        MapConfig(preset="none")


def test_cli_reach_json_and_figure(tmp_path, capsys) -> None:
    out = tmp_path / "reach"
    rc = main(["reach", "--dim", "1", "--grid", "7", "--map-shape", "6", "--iterations", "500",
               "--episodes", "20", "--seeds", "0", "--block", "10", "--final-episodes", "10",
               "--max-episode-steps", "30",
               "--backend", "reference", "--out", str(out), "--json", "--quiet"])  # fmt: skip
    assert rc == 0 and (out / "reach.png").stat().st_size > 10_000
    data = json.loads(capsys.readouterr().out)
    assert set(data["success"]) == {"map", "retina", "retina_gaze", "true_z"}
    assert data["config"]["seeds"] == [0]
    assert data["config"]["map"]["iterations"] == 500
    assert data["config"]["env"]["max_episode_steps"] == 30
    assert json.loads((out / "result.json").read_text("utf-8")) == data


def test_gym_make_without_arguments_is_the_world_of_sigmapi_reach() -> None:
    """``gymnasium.make(ENV_ID)`` and ``sigmapi reach`` without options build one world: the
    command passes no world setting of its own (its options default to the config's), and
    the config's world is what the registered id makes."""
    from sigmapi.cli import build_parser
    from sigmapi.cli._common import dataclass_values
    from sigmapi.envs import ENV_ID, GazeReachConfig

    args = build_parser().parse_args(["reach"])
    assert dataclass_values(args, GazeReachConfig) == {}  # the command's world: the config's
    world = REACH.config_type().env
    made = gym.make(ENV_ID)
    try:
        for name, value in world.env_kwargs().items():
            assert getattr(made.unwrapped, name) == value, name
        assert made.spec is not None
        assert made.spec.max_episode_steps == world.max_episode_steps
    finally:
        made.close()


def test_cli_reach_user_mistakes_exit_2(tmp_path, capsys) -> None:
    out = str(tmp_path / "r")
    assert main(["reach", "--dim", "1", "--map-shape", "4x4", "--out", out]) == 2
    err = capsys.readouterr().err
    assert "map_shape must have 1 axis for a task of dim 1, got 4x4 (2-D)" in err
    assert "give map_shape 12" in err and "or dim 2" in err  # both settings, each a fix
    for bad in ("0", "3"):  # the flag at fault is --dim, not the map it implies
        assert main(["reach", "--dim", bad, "--out", out]) == 2
        err = capsys.readouterr().err
        assert f"dim must be 1 or 2, got {bad}" in err and "map_shape" not in err
    assert main(["reach", "--episodes", "0", "--out", out]) == 2
    assert "episodes must be an int in [1, 1000000], got 0" in capsys.readouterr().err
    assert main(["reach", "--model", str(tmp_path / "none.npz"), "--out", out, "--force"]) == 2
    assert "does not exist" in capsys.readouterr().err
    cfg = ReachConfig().replace(dim=1)  # the default map follows the task's dimension
    assert cfg.map.map_shape == (12,)


@pytest.mark.slow
def test_acceptance_map_reaches_95_percent_of_true_z_2d() -> None:
    """The acceptance run: 2-D task, saccade on every step, the 15x15 paper-2d map, the
    default seeds: map >= 0.95 x true-z success (the measured values: docs/guide/reach.md)."""
    cfg = ReachConfig().replace(states=("map", "true_z"))
    res = REACH.run(cfg, seeds=REACH.default_seeds(cfg))
    final = res.final_success()
    assert final["map"] >= 0.95 * final["true_z"], final


def _synthetic_result(**run: int) -> ReachResult:
    """A result of 4 seeds x 400 episodes without training: "flat" succeeds on every other
    episode throughout; "ramp" climbs linearly from 0 to 1 over the run (success where a
    fixed pattern lies below the ramp); steps are the episode index mod 40 + seed."""
    cfg = ReachConfig().replace(states=("retina", "true_z"), episodes=400, block=50,
                                final_episodes=200, **run)  # fmt: skip
    res = ReachResult(cfg, (5, 6, 7, 8))
    ep = np.arange(400)
    u = (ep * 0.618034) % 1.0  # an even spread of thresholds, the same for every seed
    flat = np.tile(ep % 2 == 0, (4, 1))
    ramp = np.tile(u < ep / 399.0, (4, 1))
    for state, succ in (("true_z", flat), ("retina", ramp)):
        res.success[state] = succ
        res.lost[state] = np.zeros_like(succ)
        res.steps[state] = (ep % 40 + np.arange(4)[:, None] + 1).astype(np.int64)
    res.values = {s: np.zeros((21, 21)) for s in ("retina", "true_z")}
    res.z_axis = np.linspace(0, 1, 21)
    return res


def test_a_learner_still_rising_at_the_last_episode_is_named_from_the_data() -> None:
    res = _synthetic_result()
    rise = res.final_rise()
    # the ramp rises 199/399 of the way across the last 200 episodes; the flat one not at all
    assert rise["retina"] == pytest.approx(199 / 399, abs=0.05)
    assert abs(rise["true_z"]) < 0.02
    assert res.still_rising() == ["retina"]
    assert res.final_rise_se() == {"retina": 0.0, "true_z": 0.0}  # every seed alike
    d = res.to_dict()
    assert d["levelled_off"] == {"retina": False, "true_z": True}
    assert "not levelled off (rise >= 0.05 over the last 200 of 400 episodes): retina" in (
        res.table()
    )
    calm = _synthetic_result(plateau_rise=0.9)  # a threshold above the ramp's rise
    assert calm.still_rising() == [] and "every learner levelled off" in calm.table()
    with pytest.raises(ConfigError, match="plateau_rise must be"):
        ReachRunConfig(plateau_rise=0.0)


def test_reach_figure_names_rising_learners_and_spreads_and_labels_every_panel() -> None:
    res = _synthetic_result()
    fig = reach_figure(res)
    success, steps = fig.axes[0], fig.axes[1]
    labels = [t.get_text() for t in success.get_legend().get_texts()]
    assert any(t.startswith("retina only (still rising: +0.") for t in labels), labels
    assert not any("still rising" in t for t in labels if t.startswith("true z")), labels
    steps_labels = [t.get_text() for t in steps.get_legend().get_texts()]
    assert len(steps_labels) == 3 and steps_labels[-1] == "band: quartiles over seeds"  # 2 states
    assert len(steps.collections) == 2  # a quartile band per state
    c = res.curves()["true_z"]  # seeds' mean steps differ by 1 each: quartiles of 4 seeds
    np.testing.assert_allclose(c["steps_q75"] - c["steps_q25"], 1.5)
    assert "not levelled off" in fig._suptitle.get_text() and "seed 5" in fig._suptitle.get_text()
    bars = [ax for ax in fig.axes if ax.get_label() == "<colorbar>"]
    assert len(bars) == 2 and all("V(z)" in ax.get_ylabel() for ax in bars)


def test_a_longer_budget_repeats_the_shorter_run_then_goes_on() -> None:
    """docs/guide/reach-levelling.md: the first episodes of a longer run of the same seeds are
    the shorter run's, so one long run shows the learners at the default budget too."""
    cfg = ReachConfig().replace(**{**TINY, "states": ("retina", "true_z")})
    short = REACH.run(cfg, seeds=[2])
    long = REACH.run(cfg.replace(episodes=35), seeds=[2])
    for s in short.success:
        np.testing.assert_array_equal(long.success[s][:, :20], short.success[s])
        np.testing.assert_array_equal(long.steps[s][:, :20], short.steps[s])
