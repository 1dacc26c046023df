"""Learning from a stream of frames: the trace rule (rules/trace.py), its kernels, the estimator's
fit_stream / partial_fit_stream, the stream of the gaze-and-reach world and `sigmapi stream`."""

from __future__ import annotations

import json
import subprocess
import sys

import numba
import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.errors import ConfigError, DataError
from sigmapi.kernels import fast, reference
from sigmapi.model._stream import consecutive_pairs
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.trace import trace_step

SMALL = {"map_shape": (6,), "x_shape": (7,), "y_shape": (7,), "iterations": 600, "seed": 3}


def _frames(som: SigmaPiSOM, n: int, dwell: int = 3, seed: int = 1):
    f = som.sampler.stream(n, dwell, np.random.default_rng(seed))
    return f.x, f.y


def test_trace_step_at_zero_is_the_neighbourhood_bit_for_bit():
    rng = np.random.default_rng(0)
    old, a = rng.random(50), rng.random(50)
    np.testing.assert_array_equal(trace_step(old, a, 0.0), a)
    np.testing.assert_allclose(trace_step(old, a, 0.25), 0.25 * old + 0.75 * a)


def test_the_gaze_reach_stream_holds_z_for_the_dwell_time():
    som = SigmaPiSOM(**SMALL)
    f = som.sampler.stream(100, 8, np.random.default_rng(0))
    assert f.x.shape == (100, 7) and f.y.shape == (100, 7)
    np.testing.assert_allclose((f.px + f.py) / 2, f.z)
    for s in range(0, 100, 8):
        assert np.all(f.z[s : s + 8] == f.z[s])  # one position per dwell
        assert f.moved[s] and not f.moved[s + 1 : s + 8].any()
    assert len(np.unique(f.z)) == 13  # a fresh z per dwell
    assert len(np.unique(f.px)) == 100  # a fresh view per saccade
    with pytest.raises(ConfigError, match="dwell"):
        som.sampler.stream(10, 0, np.random.default_rng(0))


@pytest.mark.parametrize(("backend", "tol"), [("reference", 0.0), ("fast", 0.0)])
def test_trace_zero_is_the_two_view_rule_bit_for_bit(backend, tol):
    # a stream of alternating pairs, x0[0], x1[0], x0[1], x1[1], ...: at trace 0 the stream
    # learns frame t + 1 under frame t's winner, i.e. the two-view rule on its consecutive
    # frames, whose even rows are the given pairs; the refinement too (rounds over them)
    kw = {**SMALL, "backend": backend, "kernel_tol": tol, "refine_rounds": 2}
    som = SigmaPiSOM(**kw)
    b = som.sampler.sample(301, np.random.default_rng(5))
    x = np.stack([b.x0, b.x1], axis=1).reshape(-1, 7)
    y = np.stack([b.y0, b.y1], axis=1).reshape(-1, 7)
    assert np.array_equal(x[0::2], b.x0) and np.array_equal(x[1::2], b.x1)
    stream = som.fit_stream((x[:601], y[:601]), trace=0.0)
    pairs = consecutive_pairs(x[:601], y[:601])
    two_view = SigmaPiSOM(**kw).partial_fit(views=pairs).refine(views=pairs)
    assert stream.t_ == two_view.t_ == 600 and stream.refined_ == two_view.refined_ == 1200
    np.testing.assert_array_equal(stream.weights_, two_view.weights_)


@pytest.mark.parametrize(("backend", "tol"), [("reference", 0.0), ("fast", 0.0), ("fast", 1e-6)])
def test_a_stream_cut_in_two_calls_learns_what_one_call_learns(backend, tol):
    kw = {**SMALL, "backend": backend, "kernel_tol": tol, "ordering": "none"}
    x, y = _frames(SigmaPiSOM(**kw), 601)
    one = SigmaPiSOM(**kw).partial_fit_stream((x, y), trace=0.6)
    cut = SigmaPiSOM(**kw).partial_fit_stream((x[:250], y[:250]), trace=0.6)
    cut.partial_fit_stream((x[250:251], y[250:251]), trace=0.6)
    cut.partial_fit_stream((x[251:], y[251:]), trace=0.6)
    assert one.t_ == cut.t_ == 600
    np.testing.assert_array_equal(one.weights_, cut.weights_)
    np.testing.assert_array_equal(one._run.trace, cut._run.trace)


def test_fit_stream_replays_a_short_stream_in_passes():
    kw = {**SMALL, "backend": "reference", "ordering": "none"}
    x, y = _frames(SigmaPiSOM(**kw), 201)
    som = SigmaPiSOM(**kw).fit_stream((x, y), trace=0.5)
    assert som.t_ == 600
    # the same as the frames laid end to end: 201 + 201 + 199 frames, 600 learned (the first
    # frame only starts the trace)
    xs, ys = np.concatenate([x, x, x[:199]]), np.concatenate([y, y, y[:199]])
    again = SigmaPiSOM(**kw).partial_fit_stream((xs, ys), trace=0.5)
    assert again.t_ == 600
    np.testing.assert_array_equal(som.weights_, again.weights_)


@pytest.mark.parametrize("tol", [0.0, 1e-6])
def test_fast_stream_matches_the_reference(tol):
    kw = {**SMALL, "kernel_tol": tol}
    x, y = _frames(SigmaPiSOM(**kw), 601, dwell=4)
    for rule in ("soft", "min_distance"):
        ref = SigmaPiSOM(**kw, backend="reference", winner_rule=rule)
        fst = SigmaPiSOM(**kw, backend="fast", winner_rule=rule)
        ref.fit_stream((x, y), trace=0.7)
        fst.fit_stream((x, y), trace=0.7)
        atol = 1e-12 if tol == 0 else 1e-5  # float32 storage and truncation at tol > 0
        np.testing.assert_allclose(fst.weights_, ref.weights_, atol=atol)
        got = fst.winner(x[:300], y[:300], hard=True)
        assert np.array_equal(got, ref.winner(x[:300], y[:300], hard=True))


def test_kernels_agree_on_winners_and_trace():
    som = SigmaPiSOM(**SMALL, ordering="none")
    x, y = _frames(som, 400)
    t = np.arange(400)
    args = (som.sigma_at(t + 1), som.eps_at(t))
    kw = {"lam": 0.8, "geometry": MapGeometry((6,)), "winner_rule": "soft"}
    w = som.initial_weights()
    wr = w.copy()
    kr, tr = reference.KERNEL.train_stream(wr, x, y, None, *args, **kw)
    st = fast.KERNEL.prepare(w, 0.0)
    kf, tf = fast.KERNEL.train_stream(st, x, y, None, *args, **kw)
    np.testing.assert_array_equal(kr, kf)
    np.testing.assert_allclose(tf, tr, atol=1e-14)
    np.testing.assert_allclose(fast.KERNEL.export(st), wr, atol=1e-12)
    assert (
        reference.KERNEL.train_stream(wr, x[:0], y[:0], None, *(a[:0] for a in args), **kw)[1]
        is None
    )


def test_same_stream_result_for_any_thread_count():
    som = SigmaPiSOM(map_shape=(8, 8), x_shape=(8, 8), y_shape=(8, 8), code_width=1.0,
                     iterations=200, seed=4, backend="reference", ordering="none")  # fmt: skip
    assert som.n_units * 64 * 64 >= fast.PARALLEL_MIN_WORK
    x, y = _frames(som, 200, dwell=4)
    t = np.arange(200)
    args = (som.sigma_at(t + 1), som.eps_at(t))
    kw = {"lam": 0.5, "geometry": MapGeometry((8, 8)), "winner_rule": "soft"}
    serial = fast.KERNEL.prepare(som.initial_weights())
    k_serial, tr_serial = fast.KERNEL.train_stream(serial, x, y, None, *args, **kw, threads=False)
    before = numba.get_num_threads()
    try:
        for n in sorted({1, getattr(numba.config, "NUMBA_NUM_THREADS", 1)}):
            numba.set_num_threads(n)
            par = fast.KERNEL.prepare(som.initial_weights())
            k_par, tr_par = fast.KERNEL.train_stream(par, x, y, None, *args, **kw, threads=True)
            np.testing.assert_array_equal(k_par, k_serial)
            np.testing.assert_array_equal(tr_par, tr_serial)
            np.testing.assert_array_equal(par.raw, serial.raw)
    finally:
        numba.set_num_threads(before)


def test_stream_input_errors_name_the_parameter():
    som = SigmaPiSOM(**SMALL)
    x, y = _frames(som, 20)
    with pytest.raises(DataError, match="frames must be a tuple"):
        som.fit_stream((x, y, x, y))
    with pytest.raises(DataError, match=r"x must have shape \(B, 7\)"):
        som.fit_stream((x[:, :3], y))
    with pytest.raises(DataError, match="at least 2 frames"):
        som.fit_stream((x[:1], y[:1]))
    with pytest.raises(DataError, match="same number of rows"):
        som.fit_stream((x, y[:5]))
    with pytest.raises(ConfigError, match=r"trace must be a number in \[0, 1\)"):
        som.fit_stream((x, y), trace=1.0)
    with pytest.raises(ConfigError, match="same_view"):
        SigmaPiSOM(**SMALL, same_view=True).fit_stream((x, y))


def test_the_stream_command_writes_its_json_and_figure(tmp_path):
    out = tmp_path / "stream"
    r = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "stream", "--quick", "--json", "--quiet",
         "--out", str(out)],
        capture_output=True, text=True, timeout=600, check=False,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    result = json.loads(r.stdout)
    assert result == json.loads((out / "result.json").read_text())
    names = {m["name"] for m in result["methods"]}
    assert names == {"pairs", "stream trace 0", "stream trace 0.5"}
    for m in result["methods"]:
        for key in ("view_consistency", "z_error", "order_r2", "fold_rate", "dwell", "trace"):
            assert key in m
        assert 0.0 <= m["view_consistency"] <= 1.0 and m["n_seeds"] == 1
    assert sorted({m["dwell"] for m in result["methods"] if m["dwell"]}) == [1, 4, 16]
    assert result["settings"]["seeds"] == [0]
    assert (out / "stream.png").stat().st_size > 10_000
    assert "explicit pairs" in (out / "stream.txt").read_text()
    r = subprocess.run([sys.executable, "-m", "sigmapi.cli", "stream", "--traces", "1.5"],
                       capture_output=True, text=True, timeout=120, check=False)  # fmt: skip
    assert r.returncode == 2 and "traces" in r.stderr and "Traceback" not in r.stderr


def test_collect_stream_from_the_gaze_reach_world():
    from sigmapi.envs import GazeReachEnv, collect_stream

    env = GazeReachEnv()
    x, y = collect_stream(env, 41, 4, seed=0)
    assert x.shape == (41, env.x_code.size) and y.shape == (41, env.y_code.size)
    again = collect_stream(env, 41, 4, seed=0)
    np.testing.assert_array_equal(x, again[0])
    # one place for 4 saccades: the retina and the gaze change, their mean z does not
    z = (env.x_code.decode(x) + env.y_code.decode(y)) / 2
    assert not np.allclose(x[0], x[1]) and not np.allclose(y[0], y[1])
    for s in range(0, 40, 4):
        np.testing.assert_allclose(z[s : s + 4], np.broadcast_to(z[s], (4, 2)), atol=0.05)
    moves = [np.abs(z[s] - z[s - 4]).max() > 0.05 for s in range(4, 41, 4)]
    assert sum(moves) >= 8
    with pytest.raises(ConfigError, match="dwell"):
        collect_stream(env, 10, 0)
