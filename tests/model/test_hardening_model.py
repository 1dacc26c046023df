"""Hardening of the model object: pickles, copies and threads carry its whole state; views
scaled by 1e300, empty, ragged or repeated by stride 0 are data errors. (Files: test_files.py.)"""

from __future__ import annotations

import copy
import pickle
import threading
import time

import numpy as np
import pytest

from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.kernels import BACKENDS


def _cfg(backend="fast"):
    return SOMConfig(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=6000, seed=3,
                     backend=backend, ordering="none")  # fmt: skip


# ---------------------------------------------------------------------------- the model object


@pytest.mark.parametrize("backend", BACKENDS)
def test_pickle_and_deepcopy_carry_state_arrays_and_continue_bit_exact(backend):
    som = SigmaPiSOM(_cfg(backend)).fit(iterations=1500)
    data = pickle.dumps(som)
    assert b"sigmapi.kernels" not in data and b"numba" not in data  # arrays, not modules
    for twin in (pickle.loads(data), copy.deepcopy(som)):
        assert twin.t_ == som.t_ and twin.config == som.config and twin.backend == backend
        assert twin.seed_entropy == som.seed_entropy
        np.testing.assert_array_equal(twin.weights_, som.weights_)
        np.testing.assert_array_equal(
            twin.partial_fit(iterations=700).weights_,
            copy.deepcopy(som).partial_fit(iterations=700).weights_,
        )
    fresh = pickle.loads(pickle.dumps(SigmaPiSOM(_cfg(backend))))
    assert not fresh.is_fitted and fresh.seed_entropy == SigmaPiSOM(_cfg(backend)).seed_entropy


def test_copy_copy_does_not_share_the_weights():
    som = SigmaPiSOM(_cfg()).fit(iterations=1000)
    before = som.weights_.copy()
    twin = copy.copy(som)
    twin.partial_fit(iterations=500)
    assert twin.t_ == 1500 and som.t_ == 1000
    np.testing.assert_array_equal(som.weights_, before)
    assert not np.array_equal(twin.weights_, before)


@pytest.mark.parametrize("backend", BACKENDS)
def test_partial_fit_from_two_threads_loses_no_iteration(backend):
    som = SigmaPiSOM(_cfg(backend)).fit(iterations=0)
    threads = [
        threading.Thread(target=som.partial_fit, kwargs={"iterations": 2500}) for _ in range(2)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert som.t_ == 5000
    # each call ran whole, one after the other: the same as one run of 5,000 iterations
    np.testing.assert_array_equal(
        som.weights_, SigmaPiSOM(_cfg(backend)).fit(iterations=5000).weights_
    )


@pytest.mark.parametrize("ordering", ["none", "crossview"])
@pytest.mark.parametrize("which", [(0, 1), (2, 3)])
def test_views_scaled_by_1e300_are_a_data_error(ordering, which):
    from sigmapi.errors import DataError

    rng = np.random.default_rng(0)
    views = [rng.random((20, 5)) for _ in range(4)]
    for i in which:
        views[i] = views[i] * 1e300
    som = SigmaPiSOM(_cfg("reference").replace(ordering=ordering, iterations=50))
    with pytest.raises(DataError, match="scale your codes"):
        som.fit(tuple(views))


def test_empty_and_ragged_views_are_data_errors():
    from sigmapi.errors import DataError

    som = SigmaPiSOM(_cfg("reference"))
    with pytest.raises(DataError, match="px0 holds no positions"):
        som.encode_views([], [], [], [])
    with pytest.raises(DataError, match="rectangular"):
        som.encode_views([[0.1], [0.2, 0.3]], [0.1], [0.1], [0.1])
    with pytest.raises(DataError, match="rectangular"):
        som.fit(([[0.1] * 5, [0.2] * 4], [[0.1] * 5], [[0.1] * 5], [[0.1] * 5]))


def test_views_repeated_by_stride_0_are_checked_at_the_cost_of_their_data():
    from sigmapi.errors import DataError
    from sigmapi.model.views import check_views

    row = np.float32([0.1, 0.2, 0.3, 0.4, 0.5])
    big = np.broadcast_to(row, (10**12, 5))
    t0 = time.perf_counter()
    views = check_views((big,) * 4, (5,), (5,))
    assert time.perf_counter() - t0 < 1 and views[0].shape == (10**12, 5)
    assert views[0].dtype == np.float64 and 0 in views[0].strides  # no (B, n) copy
    bad = np.broadcast_to(np.float32([0.1, np.nan, 0.3, 0.4, 0.5]), (10**12, 5))
    with pytest.raises(DataError, match="finite"):
        check_views((big, big, bad, big), (5,), (5,))
