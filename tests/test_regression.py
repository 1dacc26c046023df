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
