"""Reward-gated plasticity: the gate rule, the gated update in both kernels, the gated episode
loop and the ``sigmapi reward`` experiment (run as a user would)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.agents import ActorCritic, Gating, run_gated_episodes
from sigmapi.envs import GazeReachConfig, MapObservation, learn_map_in_env
from sigmapi.errors import ConfigError, DataError
from sigmapi.experiments.reward.config import RewardConfig
from sigmapi.experiments.reward.result import RewardResult, episodes_to_target
from sigmapi.experiments.reward.run import REWARD, map_scores, probe_objects
from sigmapi.kernels import fast, reference
from sigmapi.rules.gating import action_feedback, reward_gate, surprise
from sigmapi.rules.geometry import MapGeometry

MAP = (4, 5)
CODE = (5, 5)
K = MAP[0] * MAP[1]


# ---------------------------------------------------------------------------- the gate rule


def test_zero_td_error_closes_every_surprise_gate_but_the_constant():
    w = np.array([0.3, -0.2, 0.1])
    assert np.all(reward_gate(0.0, w, "positive") == 0.0)
    assert np.all(reward_gate(0.0, w, "absolute") == 0.0)
    assert np.array_equal(reward_gate(0.0, w, "constant"), action_feedback(w))


def test_gate_sign_positive_surprise_opens_only_for_better_than_expected():
    w = np.array([0.3, -0.2, 0.1])
    assert np.all(reward_gate(-0.4, w, "positive") == 0.0)
    up = reward_gate(0.4, w, "positive", scale=0.8)
    assert np.allclose(up, [0.5, 0.0, 0.5 / 3])
    assert np.allclose(reward_gate(-0.4, w, "absolute", scale=0.8), up)


def test_surprise_is_clipped_to_one_and_feedback_is_relative_to_the_largest_weight():
    assert surprise(5.0, "positive", scale=0.5) == 1.0
    assert np.array_equal(action_feedback([-1.0, -2.0]), [0.0, 0.0])  # no support: no learning
    assert np.array_equal(action_feedback([-1.0, 2.0], "none"), [1.0, 1.0])
    with pytest.raises(ConfigError, match="surprise must be one of"):
        surprise(0.1, "negative")


# ---------------------------------------------------------------------------- the kernels


def _problem(n: int = 300, seed: int = 3):
    som = SigmaPiSOM(map_shape=MAP, x_shape=CODE, y_shape=CODE, iterations=n, seed=seed,
                     backend="reference")  # fmt: skip
    b = som.training_block(0)
    data = tuple(np.asarray(getattr(b, f)[:n]) for f in ("x0", "y0", "x1", "y1"))
    rng = np.random.default_rng(seed)
    gates = rng.random((n, K)) * (rng.random((n, K)) < 0.5)  # half the units shut per step
    return som.initial_weights(), data, gates


def _gated(kernel, w, data, gates, sigma=1.5, eps=0.05, tol=None):
    state = kernel.KERNEL.prepare(w) if tol is None else kernel.KERNEL.prepare(w, tol)
    n = data[0].shape[0]
    won = kernel.KERNEL.train_block(
        state,
        *data,
        np.full(n, sigma),
        np.full(n, eps),
        geometry=MapGeometry(MAP),
        winner_rule="soft",
        gates=gates,
    )
    return kernel.KERNEL.export(state), won


@pytest.mark.parametrize("kernel", [reference, fast], ids=["reference", "fast"])
def test_zero_gates_change_nothing(kernel):
    w, data, gates = _problem(50)
    after, _ = _gated(kernel, w, data, np.zeros_like(gates), tol=0.0 if kernel is fast else None)
    assert np.array_equal(after, w)


def test_open_gates_are_the_ungated_rule():
    w, data, _ = _problem(200)
    n = data[0].shape[0]
    gated, won = _gated(reference, w, data, np.ones((n, K)))
    plain = w.copy()
    won_plain = reference.KERNEL.train_block(
        plain,
        *data,
        np.full(n, 1.5),
        np.full(n, 0.05),
        geometry=MapGeometry(MAP),
        winner_rule="soft",
    )
    assert np.array_equal(won, won_plain)
    assert np.array_equal(gated, plain)


def test_fast_gated_update_equals_reference():
    w, data, gates = _problem(300)
    ref_w, ref_won = _gated(reference, w, data, gates)
    fast_w, fast_won = _gated(fast, w, data, gates, tol=0.0)
    assert np.array_equal(fast_won, ref_won)
    assert np.max(np.abs(fast_w - ref_w)) < 1e-10
    f32_w, f32_won = _gated(fast, w, data, gates)  # the default tolerance, float32 storage
    assert np.mean(f32_won == ref_won) >= 0.99
    assert np.max(np.abs(f32_w - ref_w)) < 1e-5


def test_a_gated_unit_moves_towards_the_sample_and_a_shut_one_stays():
    w, data, _ = _problem(1)
    gates = np.zeros((1, K))
    gates[0, :10] = 1.0
    after, _ = _gated(reference, w, data, gates, sigma=50.0)  # every unit in the neighbourhood
    target = np.outer(data[2][0], data[3][0])
    before_d = np.linalg.norm((w - target).reshape(K, -1), axis=1)
    after_d = np.linalg.norm((after - target).reshape(K, -1), axis=1)
    assert np.all(after_d[:10] < before_d[:10])
    assert np.array_equal(after[10:], w[10:])


def test_learn_gated_checks_gates_and_keeps_the_schedule_clock():
    som = SigmaPiSOM(map_shape=MAP, x_shape=CODE, y_shape=CODE, iterations=200, seed=1)
    som.fit()
    t, w = som.t_, som.weights_.copy()
    _, data, gates = _problem(20)
    with pytest.raises(DataError, match=r"gates must have shape \(20, 20\)"):
        som.learn_gated(data, gates[:, :3])
    with pytest.raises(DataError, match=r"gates must be finite numbers in \[0, 1\]"):
        som.learn_gated(data, gates * 2.0)
    som.learn_gated(data, gates, sigma=1.0, eps=0.1)
    assert som.t_ == t
    assert not np.array_equal(som.weights_, w)


# ---------------------------------------------------------------------------- the loop


def _world_and_map(seed: int = 0):
    env_cfg = GazeReachConfig(grid=5, code_width=0.5)
    cfg = RewardConfig().replace(grid=5, map_shape=(5, 5), iterations=500)
    model = learn_map_in_env(env_cfg.make_env(), cfg.som_config(seed), seed=seed)
    return env_cfg, model


def test_gated_loop_is_deterministic_and_the_replay_uses_the_given_factors():
    env_cfg, model = _world_and_map()

    def once(replay=None):
        m = SigmaPiSOM.from_arrays(*model.to_arrays())
        env = MapObservation(env_cfg.make_env(), m)
        agent = ActorCritic(m.n_units, 5, seed=4)
        got = run_gated_episodes(env, agent, [11, 12, 13, 14], Gating(eps=0.2),
                                 np.random.default_rng(5), surprises=replay)  # fmt: skip
        return got, m.weights_

    a, wa = once()
    b, wb = once()
    assert np.array_equal(a.surprises, b.surprises) and np.array_equal(wa, wb)
    assert a.updates > 0 and not np.array_equal(wa, model.weights_)
    shut, ws = once(replay=np.zeros(3))  # every factor 0: the map never changes
    assert shut.updates == 0 and np.array_equal(ws, model.weights_)


def test_map_scores_count_units_near_the_goal():
    _, model = _world_and_map()
    from sigmapi.envs import GazeReachEnv

    world = GazeReachEnv(grid=5, code_width=0.5)
    probes = probe_objects(world, 400, np.random.default_rng(0))
    s = map_scores(model, probes, np.array([0.5, 0.5]), 0.5)  # the whole workspace is "near"
    assert s["units_near"] == s["units_used"] and s["magnification"] == pytest.approx(1.0)
    assert np.isnan(s["view_consistency_away"])  # nothing is away
    s = map_scores(model, probes, np.array([0.5, 0.5]), 0.2)
    assert 0 < s["units_near"] < s["units_used"] <= model.n_units
    assert 0.0 < s["view_consistency_away"] <= 1.0 and s["order_r2_away"] > 0.5


def test_episodes_to_target_is_the_end_of_the_first_block_at_the_rate():
    s = np.array([0, 0, 1, 0, 1, 1, 1, 1], dtype=bool)
    assert episodes_to_target(s, 2, 0.8) == 6
    assert episodes_to_target(s, 4, 0.8) == 8
    assert episodes_to_target(~s | True, 4, 0.8) == 4
    assert episodes_to_target(np.zeros(8, dtype=bool), 4, 0.8) is None


def test_shuffled_control_needs_the_gated_run():
    with pytest.raises(ConfigError, match="'shuffled' replays the gated run"):
        RewardConfig().replace(methods=("frozen", "shuffled"))


def test_run_rules_are_the_episode_runs_with_methods_for_states():
    with pytest.raises(ConfigError, match="block must be <= episodes"):
        RewardConfig().replace(episodes=10, final_episodes=5)
    with pytest.raises(ConfigError, match=r"methods must be distinct names from \('frozen'"):
        RewardConfig().replace(methods=("gated", "gated"))
    assert RewardConfig().replace(methods=["frozen"]).run.methods == ("frozen",)


# ---------------------------------------------------------------------------- the command


def test_reward_quick_via_the_command_line(tmp_path):
    out = tmp_path / "r"
    proc = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "reward", "--quick", "--json", "--quiet",
         "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr
    data = json.loads(proc.stdout)
    names = [m["name"] for m in data["methods"]]
    assert names == ["frozen", "gated", "shuffled"]
    for m in data["methods"]:
        for key in ("final_success", "episodes_to_target", "magnification",
                    "magnification_ratio", "view_consistency_away", "order_r2_away"):  # fmt: skip
            assert key in m, key
    assert data["methods"][0]["magnification_ratio"]["median"] == pytest.approx(1.0)
    assert (out / "reward.png").stat().st_size > 10_000
    assert json.loads((out / "result.json").read_text()) == data
    assert json.loads(json.dumps(RewardResult.from_dict(data).to_dict())) == data  # reads back
    assert REWARD.quick is not None and data["config"]["seeds"] == list(REWARD.quick_seeds)
