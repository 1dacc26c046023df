"""The chain of frames (retina + eye -> head -> body) against one map on the whole task."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import sigmapi
import sigmapi.experiments
from sigmapi.cli import main
from sigmapi.experiments.chain.run import (
    TARGET_RATIO,
    ChainResult,
    chain_config,
    head_code,
    run_chain,
    sample_triples,
)
from sigmapi.metrics import winner_metrics

SMALL = sigmapi.load_preset("paper-1d-authors").replace(
    ordering="crossview", map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=15_000,
    winner_rule="argmax",
)  # fmt: skip
"""The examples' small size: 9-unit codes and maps, 15,000 iterations per map."""


@pytest.fixture(scope="module")
def small_run():
    return run_chain((0, 1, 2), config=SMALL, train_pairs=3000, n_test=2000)


def test_triples_share_z_and_stay_in_the_unit_interval():
    t = sample_triples(5000, np.random.default_rng(3))
    for v in (0, 1):
        x, e, u = t.view(v)
        assert np.allclose(((x + e) / 2 + u) / 2, t.z)
        assert all(p.shape == (5000, 1) and p.min() >= 0 and p.max() <= 1 for p in (x, e, u))
    # z is uniform: threshold: every tenth of [0, 1] holds 10 % +- 2 % of the 5000 draws
    counts = np.histogram(t.z, bins=10, range=(0, 1))[0] / 5000
    assert np.all(np.abs(counts - 0.1) <= 0.02), counts


def test_the_chain_learns_z_about_as_well_as_the_single_map(small_run):
    # thresholds: on each of 3 seeds at the small size, map A and both routes order (R^2 >=
    # 0.95), the chain's z error is below 0.45 grid spacings (quantisation floor of 9 units:
    # 0.257; measured 0.30-0.31) and at most TARGET_RATIO x the single map's (measured 0.95-0.98)
    for r in small_run["seeds"]:
        assert r["map_a"]["order_r2"] >= 0.95, r
        assert r["chain"]["order_r2"] >= 0.95 and r["single"]["order_r2"] >= 0.95, r
        assert r["chain"]["z_error"] < 0.45, r
        assert r["ratio"] <= TARGET_RATIO, r
        assert r["chain"]["weights"] == 2 * 9**3 and r["single"]["weights"] == 9 * 9**3
    s = small_run["summary"]
    assert s["met"] == s["n_seeds"] == 3
    assert s["ratio_worst"] == max(r["ratio"] for r in small_run["seeds"])


def test_same_seed_same_result(small_run):
    again = run_chain((1,), config=SMALL, train_pairs=3000, n_test=2000)["seeds"][0]
    first = small_run["seeds"][1]
    for route in ("chain", "single"):
        assert again[route]["z_error"] == first[route]["z_error"]
        assert again[route]["view_consistency"] == first[route]["view_consistency"]


def test_head_code_is_a_unit_length_code_of_map_a():
    a = sigmapi.SigmaPiSOM(SMALL, seed=0).fit()
    x, e = np.array([[0.1], [0.5], [0.9]]), np.array([[0.3], [0.5], [0.7]])
    resp = head_code(a, x, e, "response")
    win = head_code(a, x, e, "winner")
    assert resp.shape == win.shape == (3, 9)
    assert np.allclose(np.linalg.norm(resp, axis=1), 1) and np.all(resp >= 0)
    # the winner code's peak sits on A's hard winner
    k = a.winner(a.x_code.encode(x), a.y_code.encode(e), hard=True)
    assert np.array_equal(win.argmax(axis=1), k)
    # a = 0.2, 0.5, 0.8: A is ordered like the retina, so the peaks move up the map
    assert np.all(np.diff(resp.argmax(axis=1)) > 0)


def test_winner_metrics_on_a_perfect_map():
    z = np.linspace(0, 1, 900)[:, None]
    w = np.minimum((z[:, 0] * 9).astype(np.int64), 8)
    m = winner_metrics(w, z, w, w, z, np.arange(9.0)[:, None], 8.0)
    # the quantisation floor: cells of 1/9, error 1/9/sqrt(12) of z, 8/9/sqrt(12) spacings
    assert m["z_error"] == pytest.approx(8 / 9 / np.sqrt(12), rel=0.01)
    assert m["view_consistency"] == m["usage"] == 1.0 and m["order_r2"] > 0.98


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"config": sigmapi.load_preset("paper-2d")}, "config.map_shape must be 1-D"),
        ({"config": SMALL.replace(relation="sum")}, "relation 'mean'"),
        ({"config": "paper-1d"}, "config must be a sigmapi.SOMConfig"),
        ({"code": "spikes"}, "code must be one of ('response', 'winner')"),
        ({"iterations": 0}, "iterations must be an int >= 1"),
    ],
)
def test_bad_settings_are_named(kwargs, message):
    with pytest.raises(sigmapi.ConfigError, match=re.escape(message)):
        run_chain((0,), **{"config": SMALL, **kwargs})


def test_no_seed_is_refused():
    with pytest.raises(sigmapi.ConfigError, match="seeds must name at least one seed"):
        run_chain((), config=SMALL)


def test_default_config_is_paper_1d_with_crossview():
    cfg = chain_config()
    assert cfg.map_shape == (15,) and cfg.ordering == "crossview" and cfg.iterations == 300_000


def test_the_single_maps_joint_code_is_the_outer_product_of_eye_and_head_codes():
    # what makes the single map's units third-order: y = e_code (x) u_code, flattened
    p = np.random.default_rng(0).random((50, 2))
    one = sigmapi.PopulationCode((15,))
    outer = one.encode(p[:, :1])[:, :, None] * one.encode(p[:, 1:])[:, None, :]
    joint = sigmapi.PopulationCode((15, 15)).encode(p)
    assert np.allclose(joint, outer.reshape(50, -1), rtol=0, atol=1e-12)
    retina = sigmapi.PopulationCode((15, 1)).encode(np.hstack([p[:, :1], np.zeros((50, 1))]))
    assert np.array_equal(retina, one.encode(p[:, :1]))


SMALL_FLAGS = ["--set", "map_shape=[9]", "--set", "x_shape=[9]", "--set", "y_shape=[9]",
               "--set", "iterations=15000", "--set", 'winner_rule="argmax"',
               "--train-pairs", "3000", "--n-test", "2000"]  # fmt: skip


def test_command_line_json_is_run_chains_result(capsys, small_run, tmp_path):
    argv = ["chain", *SMALL_FLAGS, "--seeds", "0", "1", "2", "--workers", "1"]
    assert main([*argv, "--json", "--out", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out) == {"settings", "seeds", "summary"}
    for got, want in zip(out["seeds"], small_run["seeds"], strict=True):
        assert got["ratio"] == want["ratio"] and got["map_a"] == want["map_a"]
    assert out["settings"]["config"]["ordering"] == "crossview"
    assert sigmapi.experiments.read_result(tmp_path) == out
    assert ChainResult.from_dict(out).to_dict() == out  # result.json reads back


def test_command_line_table_and_user_mistakes(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["chain", *SMALL_FLAGS, "--seeds", "4"]) == 0  # no --out: nothing written
    out = capsys.readouterr().out
    assert "z error" in out and "of 1 seeds: chain z error <= 2 x" in out
    assert main(["chain", "--preset", "paper-2d"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "config.map_shape must be 1-D" in err[0]
    assert not list(tmp_path.iterdir())


def test_seeds_run_through_the_executor_with_the_same_result():
    from sigmapi.executor import Executor

    tiny = {"config": SMALL.replace(iterations=2000), "train_pairs": 300, "n_test": 200}
    one = run_chain((0, 1), **tiny)
    pool = run_chain((0, 1), **tiny, executor=Executor(workers=2))
    strip = ("train_seconds",)
    for got, want in zip(pool["seeds"], one["seeds"], strict=True):
        for route in ("chain", "single"):
            assert {k: v for k, v in got[route].items() if k not in strip} == {
                k: v for k, v in want[route].items() if k not in strip
            }
        assert got["ratio"] == want["ratio"]
