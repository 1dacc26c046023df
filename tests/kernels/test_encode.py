"""The compiled encoder (sigmapi.kernels._codes) against PopulationCode.encode, bit for bit:
NumPy's pairwise sum of the squares reproduced on runs shorter and longer than its blocks,
every kind of code, and the two-view sampler's batches with and without it."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi import tasks
from sigmapi.codes import PopulationCode
from sigmapi.kernels import BACKENDS

if "fast" not in BACKENDS:
    pytest.skip("numba is not installed", allow_module_level=True)

from sigmapi.kernels import _codes


@pytest.mark.parametrize(
    "n", [1, 2, 7, 8, 9, 15, 16, 17, 127, 128, 129, 225, 256, 257, 300, 1000, 1601, 4099]
)
def test_the_pairwise_sum_is_numpys(n):
    rng = np.random.default_rng(n)
    rows = rng.random((40, n)) * rng.random((40, 1)) ** 8  # magnitudes over many decades
    want = np.add.reduce(rows, axis=-1)
    got = np.array([0.0 + _codes._pairwise(r, 0, n) for r in rows])
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize(
    ("shape", "width", "height", "normalize", "periodic"),
    [
        ((15, 15), 1.0, 1.0, True, False),  # paper-2d
        ((15,), 0.5, 1.0, True, False),  # paper-1d
        ((9, 9), 0.5, 2.5, True, True),
        ((5, 6, 7), 0.7, 1.3, True, False),
        ((15, 15), 1.0, 1.0, False, False),
        ((200,), 0.3, 1.0, True, True),
        ((40, 40), 2.0, 0.5, True, False),
    ],
)
def test_the_codes_are_encodes(shape, width, height, normalize, periodic):
    code = PopulationCode(shape, width, height, normalize, periodic)
    p = np.random.default_rng(7).random((2000, len(shape)))
    p[:3], p[3:6] = 0.0, 1.0  # the borders
    got = _codes.encode(code, p)
    np.testing.assert_array_equal(got, code.encode(p))
    assert got.shape == (2000, code.size) and got.flags.c_contiguous


def test_no_positions_give_no_codes():
    code = PopulationCode((4, 4))
    assert _codes.encode(code, np.zeros((0, 2))).shape == (0, 16)


def test_codes_go_into_out_and_a_wrong_out_is_refused():
    code = PopulationCode((6, 5), 0.8)
    p = np.random.default_rng(2).random((30, 2))
    out = np.full((40, 30), np.nan)
    assert _codes.encode(code, p, out[5:35]) is not None
    np.testing.assert_array_equal(out[5:35], code.encode(p))
    assert np.isnan(out[:5]).all() and np.isnan(out[35:]).all()
    with pytest.raises(ValueError, match="out must be C-contiguous float64 of shape"):
        _codes.encode(code, p, np.empty((30, 31)))


@pytest.mark.parametrize("into", [False, True])
def test_the_sampler_draws_the_same_batches_with_numpys_encoder(monkeypatch, into):
    code = PopulationCode((15, 15), 1.0)
    sampler = tasks.TwoViewSampler("mean", code, code)

    def draw() -> tuple[np.ndarray, ...]:
        out = tuple(np.empty((1000, 225)) for _ in range(4)) if into else None
        batch = sampler.sample(1000, np.random.default_rng(3), out=out)
        if out is not None:
            assert all(a is b for a, b in zip(batch[:4], out, strict=True))
        return (*batch, *sampler.stream(500, 4, np.random.default_rng(4)))

    fast = draw()
    assert tasks._encoder() is _codes.encode
    monkeypatch.setattr(tasks, "_encoder", lambda: tasks._numpy_encode)
    for a, b in zip(fast, draw(), strict=True):
        np.testing.assert_array_equal(a, b)
