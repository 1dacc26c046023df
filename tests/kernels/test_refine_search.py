"""The fast kernel's refinement helpers (sigmapi.kernels._refining) against the arithmetic they
replace: the winners of the bound-first search are those of the full search (winners_of),
bit for bit and ties to the lowest index, on trained, untrained and degenerate weights; the
sums of the hard assignment and the round's new weights are the general code's, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from sigmapi import SigmaPiSOM
from sigmapi.kernels import BACKENDS

if "fast" not in BACKENDS:
    pytest.skip("numba is not installed", allow_module_level=True)

from sigmapi.kernels import _refining, fast
from sigmapi.rules import BATCH_MEAN
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.refinement import Sums, assignment

MAP, XS = (5, 5), (6, 6)


@pytest.fixture(scope="module")
def trained() -> SigmaPiSOM:
    """A 5x5 map on 6x6 codes, min-distance winner, the fast kernel at tol 1e-4."""
    return SigmaPiSOM(map_shape=MAP, x_shape=XS, y_shape=XS, code_width=1.0, iterations=3000,
                      winner_rule="min_distance", kernel_tol=1e-4, backend="fast",
                      refine_rounds=0, seed=3).fit()  # fmt: skip


def _pairs(model: SigmaPiSOM, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    batch = model.sampler.sample(n, np.random.default_rng(seed))
    return batch.x0, batch.y0


def _both(state, x, y, rule, shapes):
    acc = fast.KERNEL.refine_start(state)
    acc.code_shapes = shapes
    got = fast.KERNEL._refine_winners(state, acc, x, y, MapGeometry(MAP), rule)
    want = fast.KERNEL.winners_of(state, x, y, MapGeometry(MAP), rule, 0.0)
    return got, want, acc


@pytest.mark.parametrize("rule", ["min_distance", "argmax"])
@pytest.mark.parametrize("shapes", [(XS, XS), None])
def test_the_bounds_find_the_full_searchs_winners(trained, rule, shapes):
    x, y = _pairs(trained, 3000, 1)
    got, want, acc = _both(trained._run.state, x, y, rule, shapes)
    assert isinstance(acc.index, _refining.SearchIndex)
    np.testing.assert_array_equal(got, want)
    assert len(np.unique(want)) > 10  # many units win: the test compares real searches


def test_untrained_weights_and_ties_go_to_the_lowest_unit(trained):
    x, y = _pairs(trained, 600, 2)
    rng = np.random.default_rng(0)
    k, nx, ny = trained._run.state.shape
    w = rng.normal(0.0, 0.1, (k, nx, ny))  # a random start: loose bounds, many candidates
    for rule in ("min_distance", "argmax"):
        got, want, _ = _both(fast.KERNEL.prepare(w, tol=1e-4), x, y, rule, (XS, XS))
        np.testing.assert_array_equal(got, want)
    same = np.broadcast_to(w[:1], w.shape).copy()  # every unit alike: unit 0 wins every pair
    got, want, _ = _both(fast.KERNEL.prepare(same, tol=1e-4), x, y, "min_distance", (XS, XS))
    np.testing.assert_array_equal(got, want)
    assert not got.any()
    twins = fast.KERNEL.export(trained._run.state)
    winner = int(
        np.bincount(
            fast.KERNEL.winners_of(trained._run.state, x, y, MapGeometry(MAP), "argmax", 0.0)
        ).argmax()
    )
    twins[[3, 20]] = twins[winner]  # two copies of a winning unit: ties to the lowest index
    got, want, _ = _both(fast.KERNEL.prepare(twins, tol=1e-4), x, y, "argmax", (XS, XS))
    np.testing.assert_array_equal(got, want)
    assert (got == min(3, winner)).any()


def test_a_changed_state_gets_a_new_index(trained):
    model = SigmaPiSOM(trained.config).fit(iterations=500)
    x, y = _pairs(model, 300, 3)
    got, want, acc = _both(model._run.state, x, y, "min_distance", (XS, XS))
    np.testing.assert_array_equal(got, want)
    model.partial_fit(iterations=200)
    assert not acc.index.fits(model._run.state.raw, model._run.state.scale)
    got = fast.KERNEL._refine_winners(model._run.state, acc, x, y, MapGeometry(MAP), "min_distance")
    np.testing.assert_array_equal(
        got, fast.KERNEL.winners_of(model._run.state, x, y, MapGeometry(MAP), "min_distance", 0.0)
    )


def test_the_hard_sums_and_the_new_weights_are_the_general_codes(trained):
    st = trained._run.state
    batch = trained.sampler.sample(800, np.random.default_rng(4))
    k = fast.KERNEL.winners_of(st, batch.x0, batch.y0, MapGeometry(MAP), "min_distance", 0.0)
    k[k == 7] = 8  # unit 7 wins nothing: it keeps its weights
    mine, general = fast.KERNEL.refine_start(st), fast.KERNEL.refine_start(st)
    _refining.hard_sums(mine.sums, mine.mass, k, batch.x1, batch.y1, st.tol)
    jb, pi, pv = st.scratch()[:3]
    a = np.ascontiguousarray(assignment(k, MapGeometry(MAP), 0.0))
    fast._refine_sums(general.sums, general.mass, a, batch.x1, batch.y1, st.tol, jb, pi, pv)
    np.testing.assert_array_equal(mine.sums, general.sums)
    np.testing.assert_array_equal(mine.mass, general.mass)
    mine.pairs = general.pairs = 800
    new = fast.KERNEL.refine_finish(st, mine)
    n, nx, ny = st.shape
    dense = Sums(general.sums.reshape(n, nx, ny), general.mass, 800)
    want = fast.KERNEL.prepare(BATCH_MEAN.finish(fast.KERNEL.export(st), dense), tol=st.tol)
    np.testing.assert_array_equal(new.raw, want.raw)
    np.testing.assert_array_equal(new.scale, want.scale)
    np.testing.assert_array_equal(new.sqnorm, want.sqnorm)
    kept = (st.raw[:, 7].astype(np.float64) * st.scale[7]).astype(st.raw.dtype)
    np.testing.assert_array_equal(new.raw[:, 7], kept)


def test_near_ties_are_settled_in_the_full_searchs_order(trained):
    """Two units whose scores differ by far less than the slack of the scores summed in any
    order: the search sums them again in the order of the full search, so it still agrees."""
    x, y = _pairs(trained, 600, 5)
    st = trained._run.state
    w = fast.KERNEL.export(st)
    won = fast.KERNEL.winners_of(st, x, y, MapGeometry(MAP), "argmax", 0.0)
    winner = int(np.bincount(won).argmax())
    w[2] = w[winner] * (1.0 + 1e-13)  # a near twin: its activation ahead by about 1e-13
    w[winner + 1 if winner < 24 else winner - 1] = w[winner] * (1.0 - 1e-13)
    for rule in ("argmax", "min_distance"):
        got, want, _ = _both(fast.KERNEL.prepare(w, tol=1e-4), x, y, rule, (XS, XS))
        np.testing.assert_array_equal(got, want)
    assert (want == 2).any()  # the near twin wins pairs whose scores went through the exact sums


@pytest.mark.parametrize(("xs", "ys"), [((10,), (7,)), ((7, 5), (4, 8))])
def test_codes_whose_grids_leave_tiles_part_full(xs, ys):
    """Random weights and codes on grids that do not split into whole tiles (the blocks
    padded with zeros), both hard rules: the full search's winners."""
    model = SigmaPiSOM(map_shape=(4, 5), x_shape=xs, y_shape=ys, code_width=1.0,
                       iterations=200, winner_rule="min_distance", kernel_tol=1e-4,
                       backend="fast", refine_rounds=0, seed=8).fit()  # fmt: skip
    x, y = _pairs(model, 800, 6)
    rng = np.random.default_rng(1)
    k, nx, ny = model._run.state.shape
    for w in (fast.KERNEL.export(model._run.state), rng.normal(0.0, 0.1, (k, nx, ny))):
        for rule in ("min_distance", "argmax"):
            state = fast.KERNEL.prepare(w, tol=1e-4)
            acc = fast.KERNEL.refine_start(state)
            acc.code_shapes = (xs, ys)
            got = fast.KERNEL._refine_winners(state, acc, x, y, MapGeometry((4, 5)), rule)
            want = fast.KERNEL.winners_of(state, x, y, MapGeometry((4, 5)), rule, 0.0)
            np.testing.assert_array_equal(got, want)
