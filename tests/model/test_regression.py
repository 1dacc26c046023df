"""Pinned values of a small seeded run: they catch unintended changes to the random streams
and the training arithmetic. A change here is a change of every saved run's meaning."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi import SigmaPiSOM


def test_pinned_regression_values(small_1d):
    """Seeded values of the random streams and a short run; a change here is a format change."""
    som = SigmaPiSOM(small_1d)
    np.testing.assert_allclose(
        som.initial_weights()[0, 0, :3],
        [0.08858751057657588, -0.03673256952290038, 0.044468517729965074], rtol=0, atol=1e-15,
    )  # fmt: skip
    block = som.training_block(0)
    assert block.px0[0, 0] == pytest.approx(0.9164464614133021, abs=1e-14)
    assert block.py1[999, 0] == pytest.approx(0.49188314229816654, abs=1e-14)
    som.fit()
    assert float(som.weights_.sum()) == pytest.approx(12.068579904420085, abs=1e-9)
    assert float(som.weights_[3, 2, 4]) == pytest.approx(0.0039448768137741366, abs=1e-12)


def test_the_authors_preset_is_the_authors_run():
    """paper-1d-authors is the preset paper-1d was before the refinement (its config field
    for field: the same run, bit for bit, as the streams and arithmetic pinned above)."""
    import sigmapi

    cfg = sigmapi.load_preset("paper-1d-authors")
    want = {
        "map_shape": (15,), "x_shape": (15,), "y_shape": (15,), "code_width": 0.5,
        "code_height": 1.0, "code_normalize": True, "periodic": False, "relation": "mean",
        "iterations": 300_000, "eps": 0.01, "winner_rule": "soft", "soft_cut": 15,
        "init_scale": 0.1, "ordering": "none", "refine_rounds": 0, "map_periodic": False,
        "same_view": False, "kernel_tol": 1e-6,
        "sigma": ((0.0, 8.0), (0.11, 3.5), (0.6666666666666666, 1e-5)),
    }  # fmt: skip
    assert {k: getattr(cfg, k) for k in want} == want


@pytest.mark.parametrize(
    ("rule", "raw_sum", "scale_sum", "raw_100_7"),
    [
        ("min_distance", 2949999.638814942, 0.00618240772816806, 61.62022018432617),
        ("soft", 60729349.146619424, 0.052797115526014765, 54.4423713684082),
    ],
)
def test_pinned_fast_kernel_values(rule, raw_sum, scale_sum, raw_100_7):
    """The fast kernel's float32 state after a short 2-D run, pinned: the kernel before its
    loops were vectorised (6b83f92) and after give the same values, bit for bit, here. A speed
    change to the fast kernel must leave these alone; a change here changes what ``fit``
    learns."""
    from sigmapi import SOMConfig

    cfg = SOMConfig(
        map_shape=(6, 6), x_shape=(7, 7), y_shape=(7, 7), code_width=1.0, iterations=2000,
        winner_rule=rule, kernel_tol=1e-4, backend="fast", seed=0,
        sigma=((0.0, 3.0), (0.5, 1e-5)), eps=((0.0, 0.1), (1.0, 0.01)),
    )  # fmt: skip
    state = SigmaPiSOM(cfg).fit()._run.state
    raw = state.raw.astype(np.float64)
    # relative 1e-9: room for another CPU's summation order in numpy's sum and libm's exp,
    # none for a change of the kernel's arithmetic (rounding differences grow over 2,000 steps)
    assert float(raw.sum()) == pytest.approx(raw_sum, rel=1e-9)
    assert float(state.scale.sum()) == pytest.approx(scale_sum, rel=1e-9)
    assert float(raw[100, 7]) == pytest.approx(raw_100_7, rel=1e-9)
