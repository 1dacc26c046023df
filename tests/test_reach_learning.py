"""Wrappers, the actor-critic, the experiment and the ``sigmapi reach`` command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.cli import main
from sigmapi.errors import ConfigError
from sigmapi.reach import (
    ActorCritic,
    CodeObservation,
    GazeReachEnv,
    MapObservation,
    ReachConfig,
    TrueZObservation,
    make_state_env,
    run_reach,
)
from sigmapi.reach.plots import plot_reach_curves, plot_value_function, reach_figure


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


TINY = {"dim": 1, "grid": 7, "map_shape": (6,), "map_pairs": 500, "episodes": 20, "seeds": 2,
        "block": 10, "final_episodes": 10, "max_steps": 30, "backend": "reference"}  # fmt: skip


def test_experiment_is_deterministic_and_shapes_are_right() -> None:
    a = run_reach(**TINY)
    b = run_reach(**TINY, workers=2)  # seeds in two processes: the same result
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
    json.dumps(d)
    for s in a.success:  # counted: never a rounding residue such as -8.7e-17
        last = ~a.success[s][:, -10:] & ~a.lost[s][:, -10:]
        assert d["timed_out"][s] == last.sum() / last.size  # exactly, not 1 - success - lost
        assert d["success"][s] + d["lost"][s] + d["timed_out"][s] == pytest.approx(1.0)
    fig = reach_figure(a)
    assert len(fig.axes) >= 6
    assert plot_reach_curves(a, "steps") is not None
    assert plot_value_function(a, "true_z") is not None


def test_true_z_learner_learns_to_reach_1d() -> None:
    """Upper-bound learner in the 1-D task: success rises well above its first block."""
    res = run_reach(dim=1, grid=7, episodes=150, seeds=1, block=50, final_episodes=50,
                    states=("true_z",))  # fmt: skip
    c = res.curves()["true_z"]["success"]
    assert c[-1] >= 0.8 and c[-1] > c[0]


def test_reach_config_validation() -> None:
    with pytest.raises(ConfigError, match="final_episodes must be <= episodes"):
        ReachConfig(episodes=10, final_episodes=20)
    with pytest.raises(ConfigError, match="states must be distinct names"):
        ReachConfig(states=("map", "eye"))
    with pytest.raises(ConfigError, match="unknown ReachConfig field"):
        ReachConfig().replace(episode=3)


def test_the_map_learns_with_the_paper_2d_preset_or_the_small_map_schedule() -> None:
    from sigmapi import load_preset
    from sigmapi.reach.config import SMALL_MAP

    cfg = ReachConfig()
    som = cfg.som_config(seed=3)
    p2 = load_preset("paper-2d")
    assert (som.map_shape, som.x_shape, som.y_shape) == ((15, 15),) * 3
    assert som.code_width == cfg.code_width == p2.code_width
    for name in ("winner_rule", "ordering", "ordering_sigma", "kernel_tol", "eps", "sigma"):
        assert getattr(som, name) == getattr(p2, name), name
    assert (som.iterations, som.seed, som.backend) == (cfg.map_pairs, 3, "auto")
    small = ReachConfig(**SMALL_MAP).som_config(seed=3)
    assert small.map_shape == (7, 7) and small.x_shape == (7, 7) and small.code_width == 0.5
    assert small.winner_rule == "soft" and small.iterations == 10_000
    with pytest.raises(ConfigError, match="map_preset must be one of"):
        ReachConfig(map_preset="paper-3d")


def test_cli_reach_json_and_figure(tmp_path, capsys) -> None:
    out = tmp_path / "reach.png"
    rc = main(["reach", "--dim", "1", "--grid", "7", "--map-shape", "6", "--map-pairs", "500",
               "--episodes", "20", "--seeds", "1", "--block", "10", "--final-episodes", "10",
               "--max-steps", "30",
               "--backend", "reference", "--out", str(out), "--json", "--quiet"])  # fmt: skip
    assert rc == 0 and out.stat().st_size > 10_000
    data = json.loads(capsys.readouterr().out)
    assert set(data["success"]) == {"map", "retina", "retina_gaze", "true_z"}


def test_cli_reach_user_mistakes_exit_2(tmp_path, capsys) -> None:
    assert (
        main(["reach", "--dim", "1", "--map-shape", "4x4", "--out", str(tmp_path / "a.png")]) == 2
    )
    assert "--map-shape must have 1 axes" in capsys.readouterr().err
    assert main(["reach", "--episodes", "0", "--out", str(tmp_path / "a.png")]) == 2
    assert "episodes must be an int >= 1" in capsys.readouterr().err
    assert (
        main(["reach", "--model", str(tmp_path / "none.npz"), "--out", str(tmp_path / "a.png")])
        == 2
    )


@pytest.mark.slow
def test_acceptance_map_reaches_95_percent_of_true_z_2d() -> None:
    """The acceptance run: 2-D task, saccade on every step, the 15x15 paper-2d map, 5 seeds:
    map >= 0.95 x true-z success (measured 1.001; per seed 0.98-1.04, README)."""
    res = run_reach(ReachConfig(states=("map", "true_z")))
    final = res.final_success()
    assert final["map"] >= 0.95 * final["true_z"], final
