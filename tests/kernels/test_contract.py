"""The kernel contract, one suite that every registered backend runs (parametrized over
:data:`sigmapi.kernels.BACKENDS`: a new backend, registered or found through its entry point,
is collected here with no edit); also ``Minimal``, a backend written here with only its
arithmetic, the rest from :class:`~sigmapi.kernels.base.KernelBase`.

What a backend must do, against the reference kernel (the definition): its state round-trips
(dense weights, model file arrays bit for bit); activations, scores and winners agree; the
training iterations (plain, gated, refinement, stream) agree in the exact mode (``tol = 0``)
to ``ATOL`` in the weights and exactly in the winners, whatever the blocks and threads; bad
input is a ``ValueError`` (a :class:`~sigmapi.errors.ConfigError` for bad options). A
backend without the optional refinement or stream methods skips those tests.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from numpy.typing import NDArray

from sigmapi import SigmaPiSOM, SOMConfig, kernels
from sigmapi.errors import ConfigError
from sigmapi.kernels import BACKENDS, BackendOptions, get_backend, reference, register_backend
from sigmapi.kernels.base import (
    CONTRACT,
    KernelBase,
    Refiner,
    Streamer,
    check_codes,
    check_map,
    check_steps,
)
from sigmapi.rules import KOHONEN, WINNER_RULES
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import neighbourhood

REF = reference.KERNEL
ATOL = 1e-10
"""Weights of the exact mode agree with the reference to this (float64 rounding: the same
terms summed in another order)."""

MAPS = [
    MapGeometry((6,)),
    MapGeometry((6,), periodic=True),
    MapGeometry((3, 4), soft_cut=1),
    MapGeometry((3, 4), periodic=True),
]
"""Bounded and periodic maps of one and two dimensions, a narrow smoothing window."""


class Minimal(KernelBase[NDArray[np.float64]]):
    """A backend written here with only its arithmetic (dense weights, one iteration after
    another); everything else is the base's. It neither refines nor learns from streams."""

    NAME = "minimal"

    def prepare(self, weights, tol=0.0):
        return np.array(weights, dtype=np.float64)

    def export(self, state):
        return state

    def activation(self, state, x, y):
        check_codes(state.shape, x=x, y=y)
        return np.einsum("kij,bi,bj->bk", state, x, y)

    def train_block(
        self,
        state,
        x0,
        y0,
        x1,
        y1,
        sigmas,
        eps,
        *,
        geometry,
        winner_rule,
        gates=None,
        threads=False,
    ):
        n = check_codes(state.shape, x0=x0, y0=y0, x1=x1, y1=y1)
        check_map(geometry, state.shape[0])
        check_steps(n, state.shape[0], sigmas=sigmas, eps=eps, gates=gates)
        won = np.empty(n, dtype=np.int64)
        for t in range(n):
            k = self.winners_of(
                state, x0[t : t + 1], y0[t : t + 1], geometry, winner_rule, sigmas[t]
            )
            a = self.neighbourhood(k, geometry, sigmas[t])[0]
            KOHONEN.update(state, a if gates is None else a * gates[t], x1[t], y1[t], eps[t])
            won[t] = k[0]
        return won


@pytest.fixture(params=[*BACKENDS, "minimal"])
def kernel(request, monkeypatch):
    if request.param == "minimal":  # registered for this test alone
        monkeypatch.setattr(kernels, "REGISTRY", dict(kernels.REGISTRY))
        register_backend("minimal", Minimal())
    try:
        return get_backend(request.param)
    except ConfigError as e:  # a registered backend that does not import here
        pytest.skip(str(e))


def _problem(geometry: MapGeometry, n: int = 120, seed: int = 0):
    """Initial weights, the views of ``n`` iterations and their schedule on ``geometry``."""
    cfg = SOMConfig(
        map_shape=geometry.shape,
        x_shape=(5,),
        y_shape=(6,),
        code_width=0.8,
        map_periodic=geometry.periodic,
        soft_cut=geometry.soft_cut,
        iterations=n,
        ordering="none",
        seed=seed,
        backend="reference",
    )
    som = SigmaPiSOM(cfg)
    b = som.training_block(0)
    views = tuple(np.asarray(getattr(b, f)[:n]) for f in ("x0", "y0", "x1", "y1"))
    t = np.arange(n)
    return som.initial_weights(), views, som.sigma_at(t), som.eps_at(t)


def test_names_options_and_the_contract(kernel):
    assert all(hasattr(kernel, n) for n in CONTRACT)
    assert kernel.NAME in BACKENDS and get_backend(kernel.NAME) is kernel
    assert kernel.options == BackendOptions() and kernel.with_options(BackendOptions()) is kernel
    with pytest.raises(ConfigError, match=r"device must be one of \(.*'cpu'.*\), got 'tpu'"):
        kernel.with_options(BackendOptions(device="tpu"))
    with pytest.raises(ConfigError, match=r"dtype must be one of .*got 'float16'"):
        get_backend(kernel.NAME, BackendOptions(dtype="float16"))
    with pytest.raises(ConfigError, match=r"options must be a sigmapi\.kernels\.BackendOptions"):
        kernel.with_options({"device": "cpu"})


@pytest.mark.parametrize("tol", [0.0, 1e-6])
def test_the_state_round_trips(kernel, tol):
    w, *_ = _problem(MAPS[2])
    state = kernel.prepare(w, tol)
    assert tuple(state.shape) == w.shape
    dense = kernel.export(state)
    np.testing.assert_allclose(dense, w, rtol=0 if tol == 0 else 1e-6, atol=0)
    arrays = kernel.file_arrays(state)
    assert arrays and all(k == "weights" or k.startswith("state_") for k in arrays)
    assert all(a.dtype in (np.float32, np.float64) for a in arrays.values())
    back = kernel.from_file_arrays(w.shape, arrays, tol)
    np.testing.assert_array_equal(kernel.export(back), dense)
    np.testing.assert_array_equal(kernel.file_weights(w.shape, arrays), dense)
    assert kernel.max_abs(state) == float(np.abs(dense).max())
    np.testing.assert_allclose(kernel.sqnorms(state), REF.sqnorms(dense), rtol=1e-12)
    assert kernel.memory_bytes(w.shape, tol) >= 4 * w.size
    with pytest.raises(ValueError):
        kernel.from_file_arrays((w.shape[0] + 1, *w.shape[1:]), arrays, tol)


@pytest.mark.parametrize("geometry", MAPS, ids=str)
def test_inference_agrees_with_the_reference(kernel, geometry):
    w, (x0, y0, *_), *_ = _problem(geometry, n=40)
    state = kernel.prepare(w, 0.0)
    h = kernel.activation(state, x0, y0)
    np.testing.assert_allclose(h, REF.activation(w, x0, y0), rtol=1e-12, atol=1e-15)
    for name, rule in WINNER_RULES.items():
        if not kernel.supports(rule):
            continue
        want = REF.winners_of(w, x0, y0, geometry, rule, 0.9)
        scores = kernel.scores(state, h, geometry, name, 0.9)
        np.testing.assert_array_equal(np.argmax(scores, axis=1), want)
        np.testing.assert_array_equal(kernel.winners(state, h, geometry, rule, 0.9), want)
        np.testing.assert_array_equal(kernel.winners_of(state, x0, y0, geometry, rule, 0.9), want)
        one = kernel.winners_of(state, x0[:1], y0[:1], geometry, rule, 0.9)
        np.testing.assert_array_equal(one, want[:1])
    k = np.array([0, geometry.units - 1])
    np.testing.assert_array_equal(
        kernel.neighbourhood(k, geometry, 1.2),
        neighbourhood(k, geometry, 1.2),
    )


def _train(kernel, w, views, sigmas, eps, geometry, cuts=(), **kw):
    """``train_block`` on the rows cut at ``cuts``; the state and the winners."""
    state = kernel.prepare(w, 0.0)
    edges = [0, *cuts, views[0].shape[0]]
    won = [
        kernel.train_block(
            state,
            *(v[a:b] for v in views),
            sigmas[a:b],
            eps[a:b],
            geometry=geometry,
            winner_rule="soft",
            **{k: (g[a:b] if k == "gates" else g) for k, g in kw.items()},
        )
        for a, b in itertools.pairwise(edges)
    ]
    return kernel.export(state), np.concatenate(won)


@pytest.mark.parametrize("geometry", MAPS, ids=str)
def test_training_agrees_with_the_reference(kernel, geometry):
    w, views, sigmas, eps = _problem(geometry)
    want_w, want_k = _train(REF, w, views, sigmas, eps, geometry)
    got_w, got_k = _train(kernel, w, views, sigmas, eps, geometry)
    np.testing.assert_array_equal(got_k, want_k)
    np.testing.assert_allclose(got_w, want_w, rtol=0, atol=ATOL)
    # the blocks and the threads change nothing, bit for bit
    cut_w, cut_k = _train(kernel, w, views, sigmas, eps, geometry, cuts=(1, 8, 60))
    np.testing.assert_array_equal(cut_k, got_k)
    np.testing.assert_array_equal(cut_w, got_w)
    threaded_w, _ = _train(kernel, w, views, sigmas, eps, geometry, threads=True)
    np.testing.assert_array_equal(threaded_w, got_w)


def test_gated_training_agrees_with_the_reference(kernel):
    geometry = MAPS[3]
    w, views, sigmas, eps = _problem(geometry, n=80, seed=1)
    rng = np.random.default_rng(2)
    gates = rng.random((80, geometry.units)) * (rng.random((80, geometry.units)) < 0.5)
    want_w, want_k = _train(REF, w, views, sigmas, eps, geometry, gates=gates)
    got_w, got_k = _train(kernel, w, views, sigmas, eps, geometry, cuts=(30,), gates=gates)
    np.testing.assert_array_equal(got_k, want_k)
    np.testing.assert_allclose(got_w, want_w, rtol=0, atol=ATOL)
    # open gates are the ungated rule; shut gates leave the weights as they were
    ones = np.ones_like(gates)
    np.testing.assert_array_equal(
        _train(kernel, w, views, sigmas, eps, geometry, gates=ones)[0],
        _train(kernel, w, views, sigmas, eps, geometry)[0],
    )
    shut = _train(kernel, w, views, sigmas, eps, geometry, gates=np.zeros_like(gates))[0]
    np.testing.assert_array_equal(shut, kernel.export(kernel.prepare(w, 0.0)))


def test_refinement_agrees_with_the_reference(kernel):
    if not isinstance(kernel, Refiner):
        pytest.skip(f"backend {kernel.NAME!r} does not refine")
    geometry = MAPS[1]
    w, views, *_ = _problem(geometry, n=90, seed=3)
    for sigma in (0.0, 0.7):
        out = []
        for k, cuts in ((REF, ()), (kernel, ()), (kernel, (1, 40))):
            state = k.prepare(w, 0.0)
            acc = k.refine_start(state)
            edges = [0, *cuts, 90]
            won = [
                k.refine_block(
                    state,
                    acc,
                    *(v[a:b] for v in views),
                    geometry=geometry,
                    winner_rule="argmax",
                    sigma=sigma,
                )
                for a, b in itertools.pairwise(edges)
            ]
            out.append((np.concatenate(won), k.export(k.refine_finish(state, acc))))
        (want_k, want_w), (got_k, got_w), (cut_k, cut_w) = out
        np.testing.assert_array_equal(got_k, want_k)
        np.testing.assert_allclose(got_w, want_w, rtol=0, atol=ATOL)
        np.testing.assert_array_equal(cut_k, got_k)
        np.testing.assert_array_equal(cut_w, got_w)


def test_stream_learning_agrees_with_the_reference(kernel):
    if not isinstance(kernel, Streamer):
        pytest.skip(f"backend {kernel.NAME!r} does not learn from streams")
    geometry = MAPS[2]
    w, (x, y, *_), sigmas, eps = _problem(geometry, n=70, seed=4)
    out = []
    for k, cuts in ((REF, ()), (kernel, ()), (kernel, (1, 33))):
        state, trace, won = k.prepare(w, 0.0), None, []
        edges = [0, *cuts, 70]
        for a, b in itertools.pairwise(edges):
            kw, trace = k.train_stream(
                state,
                x[a:b],
                y[a:b],
                trace,
                sigmas[a:b],
                eps[a:b],
                lam=0.6,
                geometry=geometry,
                winner_rule="soft",
            )
            won.append(kw)
        out.append((np.concatenate(won), k.export(state), trace))
    (want_k, want_w, want_t), (got_k, got_w, got_t), (cut_k, cut_w, cut_t) = out
    np.testing.assert_array_equal(got_k, want_k)
    np.testing.assert_allclose(got_w, want_w, rtol=0, atol=ATOL)
    np.testing.assert_allclose(got_t, want_t, rtol=0, atol=ATOL)
    np.testing.assert_array_equal(cut_k, got_k)
    np.testing.assert_array_equal(cut_w, got_w)
    np.testing.assert_array_equal(cut_t, got_t)


def test_bad_input_is_a_value_error(kernel):
    geometry = MAPS[0]
    w, (x0, y0, x1, y1), sigmas, eps = _problem(geometry, n=10)
    state = kernel.prepare(w, 0.0)
    kw = {"geometry": geometry, "winner_rule": "soft"}
    with pytest.raises(ValueError, match=r"y must have shape \(B, 6\)"):
        kernel.activation(state, x0, y0[:, :5])
    with pytest.raises(ValueError, match="same number of rows"):
        kernel.activation(state, x0, y0[:4])
    with pytest.raises(ValueError, match="holds 12 units"):
        kernel.winners_of(state, x0, y0, MapGeometry((3, 4)), "soft", 1.0)
    with pytest.raises(ValueError, match="holds 12 units"):
        kernel.train_block(state, x0, y0, x1, y1, sigmas, eps, **{**kw, "geometry": MAPS[2]})
    with pytest.raises(ValueError, match="x1 must have shape"):
        kernel.train_block(state, x0, y0, x1[:, :3], y1, sigmas, eps, **kw)
    with pytest.raises(ValueError, match="sigmas"):
        kernel.train_block(state, x0, y0, x1, y1, sigmas[:5], eps, **kw)
    with pytest.raises(ValueError, match=r"gates must have shape \(10, 6\)"):
        kernel.train_block(state, x0, y0, x1, y1, sigmas, eps, gates=np.ones((10, 5)), **kw)
    if isinstance(kernel, Streamer):
        with pytest.raises(ValueError, match=r"trace must have shape \(6,\)"):
            kernel.train_stream(state, x0, y0, np.ones(5), sigmas, eps, lam=0.5, **kw)
    with pytest.raises(ValueError, match="rule must be one of"):
        kernel.winners_of(state, x0, y0, geometry, "nearest", 1.0)
    np.testing.assert_array_equal(kernel.export(state), kernel.export(kernel.prepare(w, 0.0)))


def test_a_map_geometry_checks_its_fields():
    g = MapGeometry((3, 4), periodic=True, soft_cut=2)
    assert (g.units, g.ndim, g.strides) == (12, 2, (4, 1))
    assert g == MapGeometry([3, 4], True, 2) and hash(g) == hash(MapGeometry((3, 4), True, 2))
    with pytest.raises(ConfigError, match=r"map_shape must be a positive int .*got \(3, 0\)"):
        MapGeometry((3, 0))
    with pytest.raises(ConfigError, match="map_periodic must be true or false, got 'yes'"):
        MapGeometry((3,), periodic="yes")
    with pytest.raises(ConfigError, match="soft_cut must be an int >= 0, got -1"):
        MapGeometry((3,), soft_cut=-1)
    cfg = SOMConfig(map_shape=(5,), map_periodic=True, soft_cut=4)
    assert cfg.geometry == MapGeometry((5,), True, 4) and cfg.geometry is cfg.geometry
