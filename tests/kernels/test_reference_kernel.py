"""The reference arithmetic (the reference kernel and the rules it runs): hand-computed tiny
cases and equality with plain loops."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi.kernels import reference as ref
from sigmapi.rules import KOHONEN
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import smooth


def test_activation_hand_computed():
    W = np.zeros((2, 2, 2))
    W[0] = [[1.0, 2.0], [3.0, 4.0]]
    W[1] = [[0.0, 1.0], [1.0, 0.0]]
    x = np.array([[1.0, 2.0]])
    y = np.array([[3.0, 5.0]])
    # h_0 = 1*1*3 + 1*2*5 + 2*3*3 + 2*4*5 = 3 + 10 + 18 + 40
    # h_1 = 1*1*5 + 2*1*3 = 11
    np.testing.assert_allclose(ref.activation(W, x, y), [[71.0, 11.0]])


def test_activation_equals_plain_loop():
    rng = np.random.default_rng(0)
    W = rng.normal(size=(6, 5, 4))
    x = rng.random((7, 5))
    y = rng.random((7, 4))
    loop = np.zeros((7, 6))
    for b in range(7):
        for k in range(6):
            for i in range(5):
                for j in range(4):
                    loop[b, k] += W[k, i, j] * x[b, i] * y[b, j]
    np.testing.assert_allclose(ref.activation(W, x, y), loop, rtol=1e-12)


def test_winner_rules_hand_computed():
    h = np.array([[1.0, 0.0, 0.9, 0.9, 0.0]])
    W = np.zeros((5, 1, 1))
    # plain argmax takes unit 0; smoothing with sigma 1 favours the pair 2, 3 (ties: lowest)
    assert ref.KERNEL.winners(W, h, MapGeometry((5,)), "argmax", 1.0)[0] == 0
    assert ref.KERNEL.winners(W, h, MapGeometry((5,)), "soft", 1.0)[0] == 2
    # sigma -> 0: soft is argmax
    assert ref.KERNEL.winners(W, h, MapGeometry((5,)), "soft", 1e-5)[0] == 0
    # at the border the summed rule hands the end unit's input to its neighbour; the
    # border-normalised rule does not: sums 1.587 vs 1.689, means 0.905 vs 0.716
    hb = np.array([[1.0, 0.9, 0.3, 0.0, 0.0]])
    assert ref.KERNEL.winners(W, hb, MapGeometry((5,)), "soft", 1.0)[0] == 1
    assert ref.KERNEL.winners(W, hb, MapGeometry((5,)), "soft_mean", 1.0)[0] == 0
    # min distance: argmax(2h - |w|^2); make unit 0 expensive
    W[0, 0, 0] = 1.5
    assert ref.KERNEL.winners(W, h, MapGeometry((5,)), "min_distance", 1.0)[0] == 2
    with pytest.raises(ValueError, match="rule must be"):
        ref.KERNEL.winners(W, h, MapGeometry((5,)), "nearest", 1.0)


def test_soft_winner_window_cut():
    # with cut 0 the smoothing is the identity
    h = np.array([[1.0, 0.0, 0.9, 0.9, 0.0]])
    np.testing.assert_allclose(smooth(h, MapGeometry((5,), soft_cut=0), 1.0), h)
    g1 = np.exp(-0.5)
    np.testing.assert_allclose(
        smooth(h, MapGeometry((5,), soft_cut=1), 1.0)[0, 1], g1 * 1.0 + 0.0 + g1 * 0.9
    )


def test_smoothing_2d_equals_plain_loop():
    rng = np.random.default_rng(1)
    h = rng.random((3, 12))
    shape = (3, 4)
    sigma, cut = 1.3, 1
    loop = np.zeros_like(h)
    for b in range(3):
        g = h[b].reshape(shape)
        for r in range(3):
            for c in range(4):
                for rr in range(3):
                    for cc in range(4):
                        if abs(rr - r) <= cut and abs(cc - c) <= cut:
                            w = np.exp(-((rr - r) ** 2 + (cc - c) ** 2) / (2 * sigma**2))
                            loop[b, r * 4 + c] += w * g[rr, cc]
    np.testing.assert_allclose(smooth(h, MapGeometry(shape, soft_cut=cut), sigma), loop, rtol=1e-12)


def test_neighbourhood_hand_computed():
    a = ref.KERNEL.neighbourhood(np.array([1]), MapGeometry((3,)), 1.0)[0]
    raw = np.exp(-np.array([1.0, 0.0, 1.0]) / 2.0)
    np.testing.assert_allclose(a, raw / np.linalg.norm(raw))
    a2 = ref.KERNEL.neighbourhood(np.array([0]), MapGeometry((2, 2)), 1.0)[0]
    raw2 = np.exp(-np.array([0.0, 1.0, 1.0, 2.0]) / 2.0)
    np.testing.assert_allclose(a2, raw2 / np.linalg.norm(raw2))
    # tiny sigma: only the winner learns
    np.testing.assert_allclose(
        ref.KERNEL.neighbourhood(np.array([2]), MapGeometry((4,)), 1e-5)[0], [0, 0, 1, 0]
    )


def test_one_update_hand_computed():
    W = np.ones((2, 2, 2))
    a = np.array([1.0, 0.5])
    x1 = np.array([1.0, 0.0])
    y1 = np.array([0.0, 2.0])
    KOHONEN.update(W, a, x1, y1, eps=0.1)
    # w += eps a (x y^T - w); x y^T = [[0, 2], [0, 0]]
    np.testing.assert_allclose(W[0], [[0.9, 1.1], [0.9, 0.9]])
    np.testing.assert_allclose(W[1], [[0.95, 1.05], [0.95, 0.95]])


def test_train_block_equals_plain_loop():
    rng = np.random.default_rng(2)
    K, nx, ny, T = 5, 4, 3, 30
    W = rng.uniform(-0.1, 0.1, (K, nx, ny))
    x0, y0, x1, y1 = (
        rng.random((T, nx)),
        rng.random((T, ny)),
        rng.random((T, nx)),
        rng.random((T, ny)),
    )
    sig = np.linspace(2.0, 0.5, T)
    eps = np.full(T, 0.05)
    W_loop = W.copy()
    win_loop = []
    for t in range(T):
        h = np.array(
            [
                sum(W_loop[k, i, j] * x0[t, i] * y0[t, j] for i in range(nx) for j in range(ny))
                for k in range(K)
            ]
        )
        sm = np.array(
            [
                sum(np.exp(-((k - m) ** 2) / (2 * sig[t] ** 2)) * h[m] for m in range(K))
                for k in range(K)
            ]
        )
        kw = int(np.argmax(sm))
        a = np.exp(-((np.arange(K) - kw) ** 2) / (2 * sig[t] ** 2))
        a /= np.sqrt((a**2).sum())
        for k in range(K):
            for i in range(nx):
                for j in range(ny):
                    W_loop[k, i, j] += eps[t] * a[k] * (x1[t, i] * y1[t, j] - W_loop[k, i, j])
        win_loop.append(kw)
    win = ref.KERNEL.train_block(
        W, x0, y0, x1, y1, sig, eps, geometry=MapGeometry((K,)), winner_rule="soft"
    )
    np.testing.assert_array_equal(win, win_loop)
    np.testing.assert_allclose(W, W_loop, rtol=1e-12, atol=1e-15)


def test_wrapped_neighbourhood_hand_computed():
    """On a ring of 5 the winner 0 has the units 1 and 4 at distance 1, 2 and 3 at distance 2;
    on a 3 x 4 torus unit (0, 0) has (2, 3) as a diagonal neighbour (distance^2 = 2)."""
    a = ref.KERNEL.neighbourhood(np.array([0]), MapGeometry((5,), True), 1.0)[0]
    raw = np.exp(-np.array([0.0, 1.0, 4.0, 4.0, 1.0]) / 2.0)
    np.testing.assert_allclose(a, raw / np.linalg.norm(raw))
    t = ref.KERNEL.neighbourhood(np.array([0]), MapGeometry((3, 4), True), 1.0)[0].reshape(3, 4)
    d2 = np.array([[0, 1, 4, 1], [1, 2, 5, 2], [1, 2, 5, 2]], dtype=float)
    raw2 = np.exp(-d2 / 2.0)
    np.testing.assert_allclose(t, raw2 / np.linalg.norm(raw2))
    # the fast kernel's compiled neighbourhood: the same numbers (times eps) and a cover
    from sigmapi.kernels import fast

    ea = np.zeros(12)
    dims, strides = np.array([3, 4]), np.array([4, 1])
    lo, hi = fast._neighbourhood(0, 1.0, 0.5, 0.5, dims, strides, True, ea)
    np.testing.assert_allclose(ea, 0.5 * t.ravel(), rtol=1e-12)
    kept = np.flatnonzero(t.ravel() > 0.5 * t.max())
    assert lo <= kept.min() and kept.max() < hi  # units 0, 1, 3, 4, 8 kept: [0, 9)
    assert (lo, hi) == (0, 9)


def test_wrapped_smoothing_hand_computed():
    """A ring of 5: one active unit spreads to both sides of the wrap, every unit counted once
    at its distance the shorter way round; the window cut applies to that distance. On a ring
    "soft" and "soft_mean" pick the same unit (the window weight is the same everywhere)."""
    h = np.array([[1.0, 0.0, 0.0, 0.0, 0.0]])
    g = smooth(h, MapGeometry((5,), True), 1.0)
    np.testing.assert_allclose(g[0], np.exp(-np.array([0.0, 1.0, 4.0, 4.0, 1.0]) / 2.0))
    g1 = smooth(h, MapGeometry((5,), True, 1), 1.0)
    np.testing.assert_allclose(g1[0], [1.0, np.exp(-0.5), 0.0, 0.0, np.exp(-0.5)])
    bounded = smooth(h, MapGeometry((5,)), 1.0)
    assert bounded[0, 4] == pytest.approx(np.exp(-8.0))  # the bounded map: 4 units away
    rng = np.random.default_rng(1)
    hs = rng.random((50, 6))
    w = np.zeros((6, 1, 1))  # six units (the rules below do not read the weights)
    for shape in ((6,), (2, 3)):
        soft = ref.KERNEL.winners(w, hs, MapGeometry(shape, True), "soft", 1.3)
        mean = ref.KERNEL.winners(w, hs, MapGeometry(shape, True), "soft_mean", 1.3)
        np.testing.assert_array_equal(soft, mean)
