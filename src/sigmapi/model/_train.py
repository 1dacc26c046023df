"""Training on view pairs, and reward-gated iterations: functions on a
:class:`~sigmapi.model._run.RunState`.

Iteration ``t`` finds the winner from view 0 and learns view 1 at the schedule's width and
rate at ``t`` (the kernel's ``train_block``). The built-in task's data of block ``b`` comes
from the run's child stream ``(1, b)``; your own rows come in passes, each in a fresh random
order from child ``(3, pass)`` (:func:`fit`; a pass over more than :data:`PERMUTED_ROWS` rows
that uses only some of them draws those without permuting them all), or once in the given
order (:func:`partial_fit`).
A run that reaches the configured length goes on to the refinement
(:mod:`sigmapi.model._refine`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.errors import ConfigError
from sigmapi.model._grids import sampler_of
from sigmapi.model._refine import check_refiner, refine, refine_total
from sigmapi.model._run import (
    BLOCK,
    Notify,
    RunState,
    eps_at,
    initial_weights,
    rng,
    sigma_at,
    training_rule,
)
from sigmapi.model.views import Array, CodeViews
from sigmapi.tasks import Batch

__all__ = ["PERMUTED_ROWS", "fit", "learn_gated", "partial_fit", "start", "training_block"]

PERMUTED_ROWS = 1 << 22
"""Most rows a pass of :func:`fit` permutes in full; of more rows, a pass that uses only some
draws them without replacement instead (``Generator.choice``): ``fit`` on 10^8 rows then
costs its iterations, not the permutation of 10^8 rows."""


def start(run: RunState, views: CodeViews | None) -> None:
    """A fresh run from the initial weights (the ordered start from ``views`` when given)."""
    run.reset(run.prepared(initial_weights(run, views), run.config.kernel_tol))


def training_block(run: RunState, b: int) -> Batch:
    """The built-in task's data of block ``b`` (iterations ``b*BLOCK`` to ``(b+1)*BLOCK - 1``),
    from child stream ``(1, b)``; the last block drawn is kept."""
    if run.block is not None and run.block[0] == b:
        return run.block[1]
    batch = sampler_of(run.config).sample(BLOCK, rng(run.entropy, 1, b))
    run.block = (b, batch)
    return batch


def fit(run: RunState, data: CodeViews | None, total: int, notify: Notify) -> None:
    """A whole run from fresh initial weights: ``total`` iterations on the built-in task
    (``data`` None) or in passes over the rows of ``data``, then the refinement if the run
    reached the configured length."""
    c = run.config
    check_refiner(c, run.kernel)
    start(run, data)
    if data is None:
        _task(run, total, notify)
    else:
        rows = data[0].shape[0]
        npass = 0
        while run.t < total:
            need, draw = total - run.t, rng(run.entropy, 3, npass)
            if rows > PERMUTED_ROWS and need < rows:
                order = draw.choice(rows, size=need, replace=False)
            else:
                order = draw.permutation(rows)[:need]
            _rows(run, data, order, notify)
            npass += 1
    if run.t >= c.iterations:
        refine(run, data, notify)


def partial_fit(
    run: RunState,
    data: CodeViews | None,
    iterations: int | None,
    notify: Notify,
) -> None:
    """Continue the run: every row of ``data`` once, in order; or ``iterations`` on the
    built-in task (None: the rest of the configured run, its refinement included). An
    unfitted run starts from the initial weights."""
    c = run.config
    if run.state is None:
        start(run, data)
    if data is not None:
        _rows(run, data, None, notify)
        return
    rest = iterations is None  # the rest of the configured run, refinement included
    if iterations is None:
        iterations = c.iterations - run.t
        if iterations <= 0 and run.refined < refine_total(run):
            check_refiner(c, run.kernel)
            refine(run, None, notify)  # the configured run continues
            return
        if iterations <= 0:
            raise ConfigError(
                f"the configured run of {c.iterations} iterations is complete "
                f"(t_ = {run.t}); pass iterations to train further, e.g. "
                "partial_fit(iterations=1000)"
            )
    _task(run, iterations, notify)
    if rest and run.refined < refine_total(run):
        check_refiner(c, run.kernel)
        refine(run, None, notify)


def _task(run: RunState, iterations: int, notify: Notify) -> None:
    """``iterations`` on the built-in task from ``run.t`` on, block by block."""
    end = run.t + iterations
    while run.t < end:
        b, off = divmod(run.t, BLOCK)
        stop = min(BLOCK, off + end - run.t)
        batch = training_block(run, b)
        sl = slice(off, stop)
        _views(run, batch.x0[sl], batch.y0[sl], batch.x1[sl], batch.y1[sl])
        if notify is not None:
            notify()


def _rows(run: RunState, data: CodeViews, order: NDArray[np.intp] | None, notify: Notify) -> None:
    """Iterations on the rows ``order`` of ``data`` (None: all, as given), in chunks of at
    most ``BLOCK`` rows, calling ``notify`` after each."""
    n = data[0].shape[0] if order is None else order.size
    for s in range(0, n, BLOCK):
        rows = slice(s, s + BLOCK) if order is None else order[s : s + BLOCK]
        x0, y0, x1, y1 = (v[rows] for v in data)
        _views(run, x0, y0, x1, y1)
        if notify is not None:
            notify()


def _views(
    run: RunState,
    x0: Array,
    y0: Array,
    x1: Array,
    y1: Array,
) -> None:
    """One stretch of iterations on view pairs; the ablation ``same_view`` learns view 0."""
    c = run.config
    x1, y1 = (x0, y0) if c.same_view else (x1, y1)
    t = np.arange(run.t, run.t + x0.shape[0])
    run.kernel.train_block(
        run.state,
        x0,
        y0,
        x1,
        y1,
        sigma_at(c, t),
        eps_at(c, t),
        geometry=c.geometry,
        winner_rule=training_rule(c),
        threads=c.threads,
    )
    run.t += x0.shape[0]
    run.weights = None


def learn_gated(
    run: RunState,
    data: CodeViews,
    g: NDArray[np.float64],
    sigma: float | None,
    eps: float | None,
) -> None:
    """Reward-gated iterations outside the schedule (``run.t`` stays): the winner of view 0,
    unit ``k`` moved towards view 1 by ``eps g[t, k] a_k``, at ``sigma`` and ``eps`` (None:
    the schedule's at ``run.t``)."""
    c, n = run.config, data[0].shape[0]
    kernel = run.kernel
    s = (
        run.sigma_now()
        if sigma is None
        else _validate.width(
            "sigma",
            sigma,
            0.0,
            lo_open=True,
            fix="map units; e.g. 1e-5 moves the winner alone",
        )
    )
    e = (
        float(eps_at(c, run.t))
        if eps is None
        else _validate.number("eps", eps, 0.0, 1.0, fix="a learning rate, e.g. 0.01")
    )
    kernel.train_block(
        run.state,
        *data,
        np.full(n, s),
        np.full(n, e),
        geometry=c.geometry,
        winner_rule=training_rule(c),
        gates=g,
    )
    run.weights = None
