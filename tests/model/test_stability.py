"""Long-run numerical stability of the float32 fast kernel and determinism across backends.

The Kohonen update makes every weight a convex combination of its previous value and a data
product ``x'_i y'_j`` in [0, 1] (codes are non-negative and unit length), so weights stay in
``[-init_scale, 1]`` however long the run; the lazy scale factors stay in ``(2**-50, 1]``.
"""

from __future__ import annotations

import numpy as np
import pytest

import sigmapi
from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.kernels import BACKENDS
from sigmapi.rules.geometry import MapGeometry

fast = pytest.importorskip("sigmapi.kernels.fast")


def _long_run(cfg: SOMConfig, n_iter: int, sigma: float, eps: float) -> fast.FastState:
    """``n_iter`` kernel iterations on one block of data repeated (the data's variety is not
    what is under test; the accumulation of float32 rounding and of the scales is)."""
    som = SigmaPiSOM(cfg)
    state = fast.KERNEL.prepare(som.initial_weights(), tol=cfg.kernel_tol)
    b = som.training_block(0)
    sig = np.full(b.x0.shape[0], sigma)
    ep = np.full(b.x0.shape[0], eps)
    for _ in range(n_iter // b.x0.shape[0]):
        fast.KERNEL.train_block(
            state,
            b.x0,
            b.y0,
            b.x1,
            b.y1,
            sig,
            ep,
            geometry=MapGeometry(cfg.map_shape),
            winner_rule="soft",
        )
    return state


def _check_bounded(state: fast.FastState, init_scale: float) -> None:
    w = fast.KERNEL.export(state)
    assert np.all(np.isfinite(w)) and np.all(np.isfinite(state.raw))
    assert w.min() >= -init_scale - 1e-6 and w.max() <= 1.0 + 1e-6
    assert np.all(state.scale > fast.RENORM) and np.all(state.scale <= 1.0)


def test_ten_times_the_papers_length_stays_finite_and_bounded():
    """3,000,000 float32 iterations (10x the paper's run) on a 7-unit 1-D map."""
    cfg = SOMConfig(map_shape=(7,), x_shape=(7,), y_shape=(7,), backend="fast", seed=3)
    state = _long_run(cfg, 3_000_000, sigma=1.0, eps=0.01)
    _check_bounded(state, cfg.init_scale)
    # the weights converged to a mean of data products: the run did not drift away
    assert fast.KERNEL.export(state).max() > 0.05


@pytest.mark.slow
def test_ten_times_the_papers_length_at_paper_scale_1d():
    cfg = sigmapi.load_preset("paper-1d").replace(backend="fast", seed=0)
    state = _long_run(cfg, 3_000_000, sigma=1e-5, eps=0.01)
    _check_bounded(state, cfg.init_scale)


@pytest.mark.parametrize(("eps", "sigma"), [(1.0, 1e-5), (0.999, 1e-5), (1.0, 50.0), (0.5, 1e-9)])
def test_adversarial_schedules_stay_finite(eps, sigma):
    cfg = SOMConfig(map_shape=(3, 3), x_shape=(4, 4), y_shape=(4, 4), code_width=1.0,
                    backend="fast", seed=1)  # fmt: skip
    state = _long_run(cfg, 20_000, sigma=sigma, eps=eps)
    _check_bounded(state, cfg.init_scale)


def test_adversarial_schedule_matches_the_reference():
    """eps = 1 replaces the winner's weights by the data: the lazy scale hits 0 and is folded."""
    cfg = SOMConfig(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, eps=1.0,
                    sigma=1e-5, seed=2, kernel_tol=0.0)  # fmt: skip
    ref = SigmaPiSOM(cfg, backend="reference").fit()
    fst = SigmaPiSOM(cfg, backend="fast").fit()
    np.testing.assert_allclose(fst.weights_, ref.weights_, atol=1e-12)


@pytest.mark.parametrize("backend", list(BACKENDS))
@pytest.mark.parametrize("cut", [500, 1000, 2345])
def test_same_result_on_every_backend_and_resume_point(tmp_path, backend, cut):
    """On every backend a save/load at any iteration continues bit for bit; against the
    reference (the definition), the fast kernel's default float32 at tol 1e-6 gives the same
    winners at >= 99.9 % of test pairs and weights within 1e-5."""
    cfg = SOMConfig(map_shape=(6,), x_shape=(8,), y_shape=(8,), iterations=4000,
                    sigma=((0.0, 3.0), (0.5, 1e-5)), seed=7)  # fmt: skip
    whole = SigmaPiSOM(cfg, backend=backend).fit()
    part = SigmaPiSOM(cfg, backend=backend).fit(iterations=cut)
    back = sigmapi.load(part.save(tmp_path / f"{backend}.npz"))
    assert back.backend == backend
    back.partial_fit()
    np.testing.assert_array_equal(back.weights_, whole.weights_)
    ref = whole if backend == "reference" else SigmaPiSOM(cfg, backend="reference").fit()
    test = ref.sampler.sample(2000, np.random.default_rng(0))
    assert np.mean(ref.winner(test.x0, test.y0) == whole.winner(test.x0, test.y0)) >= 0.999
    np.testing.assert_allclose(whole.weights_, ref.weights_, atol=1e-5)
