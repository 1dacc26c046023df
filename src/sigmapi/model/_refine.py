"""The batch refinement after the training (section 6.3; :mod:`sigmapi.rules.refinement`):
functions on a :class:`~sigmapi.model._run.RunState`.

Round ``r`` on the built-in task draws ``config.refine_pairs`` pairs from the run's child
streams ``(4, r, block)`` (``refine_draw = "quasi"``: at the points of one Kronecker sequence
shifted by stream ``(5, r)``, block ``b`` at its points ``b * BLOCK ..``); with
``fit(views)`` a round is one pass over the rows. A round's winners use the weights of its
start, which stay unchanged until the round ends, so a model saved within a round
(``refined_`` is in the model file) replays that round's pairs so far and continues to the
same weights, bit for bit. A refinement in progress continues only on what it started on
(the built-in task, or the same rows: ``refine_rows`` is in the model file too); other
views, or none where it ran on rows, raise a DataError naming what to pass.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, DataError
from sigmapi.kernels.base import REFINER
from sigmapi.model._grids import sampler_of
from sigmapi.model._run import BLOCK, Notify, RunState, rng, training_rule
from sigmapi.model.views import CodeViews
from sigmapi.tasks import kronecker

__all__ = ["GROUP", "check_refiner", "per_round", "refine", "refine_total"]

GROUP = 10
"""Blocks per call of the kernel (at most ``GROUP * BLOCK`` pairs): the fast kernel sorts a
call's pairs by the units they need, so larger calls read the same weights and sums more
often from cache (the sums do not depend on how the stream is cut)."""


def per_round(run: RunState) -> int:
    """Pairs a round: the built-in task's ``refine_pairs``, or the rows the refinement in
    progress runs on."""
    return run.config.refine_pairs if run.refine_rows is None else run.refine_rows


def refine_total(run: RunState) -> int:
    """Refinement pairs of the configured run: rounds x pairs a round."""
    return run.config.refine_rounds * per_round(run)


def check_refiner(c: SOMConfig, kernel: Any) -> None:
    """A ConfigError if the config refines and the backend lacks the methods."""
    missing = [m for m in REFINER if not hasattr(kernel, m)]
    if c.refine_rounds > 0 and missing:
        from sigmapi.kernels import REGISTRY

        able = sorted(n for n, k in REGISTRY.items() if all(hasattr(k, m) for m in REFINER))
        raise ConfigError(
            f"backend {str(kernel.NAME)!r} does not refine (it lacks {', '.join(missing)}), "
            f"got refine_rounds = {c.refine_rounds}; set refine_rounds = 0 or "
            f"use a backend that refines: {', '.join(able)}"
        )


def _check_same_rows(run: RunState, data: CodeViews | None) -> None:
    """A refinement in progress continues only on what it started on (its pairs so far
    count rounds of that many rows): a DataError naming what to pass otherwise."""
    rows = None if data is None else int(data[0].shape[0])
    was = run.refine_rows
    if run.refined == 0 or rows == was:
        return
    done = f"its refinement ran {run.refined:,} pairs on"
    if was is None:
        raise DataError(
            f"this model's refinement continues on the built-in task ({done} "
            f"it), got views of {rows:,} rows; call refine() without views, "
            "or fit() again to refine on your rows"
        )
    raise DataError(
        f"this model's refinement continues on the {was:,} view pairs it "
        f"started on ({done} them), got "
        f"{'no views' if rows is None else f'{rows:,} rows'}; pass the same "
        f"{was:,} rows to refine() (for a stream: its consecutive pairs "
        "x[:-1], y[:-1], x[1:], y[1:])"
    )


def refine(run: RunState, data: CodeViews | None, notify: Notify) -> None:
    """The rest of the configured refinement: on the built-in task (``data`` None) or one
    pass over the rows of ``data`` a round; ``notify`` after every block of pairs."""
    c = run.config
    _check_same_rows(run, data)
    run.refine_rows = None if data is None else int(data[0].shape[0])
    per = c.refine_pairs if data is None else data[0].shape[0]
    kernel: Any = run.kernel
    rule = training_rule(c).hard
    drawn: list[NDArray[np.float64]] = []  # the groups' codes, drawn into the same memory
    while run.refined < c.refine_rounds * per:
        r, done = divmod(run.refined, per)
        if run.refine_acc is None or run.refine_acc[0] != r:
            # a round's winners use the weights of its start: replay its pairs so far
            run.refine_acc = (r, kernel.refine_start(run.state, tol=c.refine_tol))
            run.refine_acc[1].code_shapes = (c.x_shape, c.y_shape)
        acc = run.refine_acc[1]
        while acc.pairs < per:
            lo = acc.pairs
            if data is None:
                b = lo // BLOCK
                last = min(b + GROUP, -(-per // BLOCK))  # blocks b .. last - 1
                hi = min(per, last * BLOCK)
                views = _draw(run, r, b, last, lo - b * BLOCK, hi - b * BLOCK, drawn)
                ends = [min(per, (i + 1) * BLOCK) for i in range(b, last)]
            else:
                hi = min(per, lo + GROUP * BLOCK)
                views = (data[0][lo:hi], data[1][lo:hi], data[2][lo:hi], data[3][lo:hi])
                ends = [*range(lo + BLOCK, hi, BLOCK), hi]
            x0, y0, x1, y1 = views
            if c.same_view:
                x1, y1 = x0, y0
            kernel.refine_block(
                run.state,
                acc,
                x0,
                y0,
                x1,
                y1,
                geometry=c.geometry,
                winner_rule=rule,
                sigma=c.refine_sigma,
            )
            for end in ends[:-1]:  # the round's weights stay those of its start until its end
                _block_done(run, r * per + end, done < end, notify)
            if acc.pairs >= per:
                run.changed(kernel.refine_finish(run.state, acc))
                run.refine_acc = None
            _block_done(run, r * per + hi, done < hi, notify)
            if run.refine_acc is None:
                break


def _block_done(run: RunState, refined: int, new: bool, notify: Notify) -> None:
    """A block of pairs is in the sums: if it was not before (``new``; a round replayed
    after loading repeats its first blocks), count it and call ``notify``. A model saved
    then replays the round's pairs so far, whatever the kernel already added."""
    if new:
        run.refined = refined
        if notify is not None:
            notify()


def _draw(
    run: RunState,
    r: int,
    first: int,
    last: int,
    lo: int,
    hi: int,
    out: list[NDArray[np.float64]],
) -> CodeViews:
    """Pairs ``lo .. hi - 1`` of blocks ``first .. last - 1`` of round ``r`` (counted from
    the first block's start), each block from its own stream, drawn in place one block at
    a time into ``out`` (the four codes of a group; made on first use, then reused)."""
    c, n = run.config, (last - first) * BLOCK
    if not out or out[0].shape[0] < n:
        out[:] = [np.empty((n, int(np.prod(s)))) for s in (c.x_shape, c.y_shape) * 2]
    sampler = sampler_of(c)
    shift = rng(run.entropy, 5, r).random(3 * sampler.ndim) if c.refine_draw == "quasi" else None
    for i in range(first, last):
        at = slice((i - first) * BLOCK, (i - first + 1) * BLOCK)
        views = (out[0][at], out[1][at], out[2][at], out[3][at])
        exact = c.refine_tol == 0
        if shift is None:
            sampler.sample(BLOCK, rng(run.entropy, 4, r, i), out=views, exact=exact)
        else:  # the round's points i * BLOCK .. of one shifted sequence
            sampler.sample_at(kronecker(i * BLOCK, BLOCK, shift), out=views, exact=exact)
    return out[0][lo:hi], out[1][lo:hi], out[2][lo:hi], out[3][lo:hi]
