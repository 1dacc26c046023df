"""Learning from a stream of frames (the trace rule, :mod:`sigmapi.rules.trace`): functions
on a :class:`~sigmapi.model._run.RunState`.

A stream is one view per frame in time order, ``(x, y)`` of shapes ``(T, n_x)`` and
``(T, n_y)``, with no pair labels: the object stays put for a few frames and moves at moments
nobody marks. Iteration ``i`` (``t_`` counts them, as in training on pairs) learns one frame
under the trace of the winners' neighbourhoods of the frames before it; its rate and width
follow the run's schedules at ``i``, so a stream and a two-view run of the same length share
one schedule. At trace 0 the stream's iterations are exactly those of ``partial_fit`` on its
consecutive pairs ``(frame t, frame t + 1)``.

The trace is kept in the run state between calls, so a stream cut into several
``partial_fit_stream`` calls learns what one call learns. A model file does not hold it: a
saved and loaded model starts a fresh trace at its next frame (as after a move).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi.errors import ConfigError
from sigmapi.kernels.base import STREAMER
from sigmapi.model._refine import check_refiner, refine
from sigmapi.model._run import BLOCK, Notify, RunState, eps_at, sigma_at, training_rule
from sigmapi.model._train import start
from sigmapi.model.views import CodeViews

__all__ = ["check_streamer", "consecutive_pairs", "fit_stream", "partial_fit_stream"]

Array = NDArray[np.float64]


def consecutive_pairs(x: Array, y: Array) -> CodeViews:
    """The two-view data of a stream's consecutive frames, ``(x[:-1], y[:-1], x[1:], y[1:])``
    (views, no copies): what the ordered start and the refinement of a stream learn from."""
    return x[:-1], y[:-1], x[1:], y[1:]


def check_streamer(run: RunState) -> None:
    """A ConfigError if the backend cannot learn from streams or the config asks for the
    ``same_view`` ablation (a stream has no second view to leave out)."""
    missing = [m for m in STREAMER if not hasattr(run.kernel, m)]
    if missing:
        from sigmapi.kernels import REGISTRY

        able = sorted(n for n, k in REGISTRY.items() if all(hasattr(k, m) for m in STREAMER))
        raise ConfigError(
            f"backend {str(run.kernel.NAME)!r} does not learn from streams (it lacks "
            f"{', '.join(missing)}); use a backend that does: {', '.join(able)}"
        )
    if run.config.same_view:
        raise ConfigError(
            "same_view must be false to learn from a stream, got true: the ablation learns "
            "the view that chose the winner, and a stream's frames have no pairs to swap"
        )


def fit_stream(run: RunState, x: Array, y: Array, lam: float, total: int, notify: Notify) -> None:
    """A whole run on the frames from fresh initial weights: ``total`` iterations, the
    stream replayed in passes if shorter, then the refinement on its consecutive pairs if
    the run reached the configured length."""
    check_streamer(run)
    check_refiner(run.config, run.kernel)
    pairs = consecutive_pairs(x, y)
    start(run, pairs)
    while run.t < total:
        need = total - run.t + (1 if run.trace is None else 0)
        _frames(run, x[:need], y[:need], lam, notify)
    if run.t >= run.config.iterations:
        refine(run, pairs, notify)


def partial_fit_stream(run: RunState, x: Array, y: Array, lam: float, notify: Notify) -> None:
    """The next frames of the stream (an unfitted run starts from the initial weights, the
    ordered start from these frames' consecutive pairs)."""
    check_streamer(run)
    if run.state is None:
        start(run, consecutive_pairs(x, y))
    _frames(run, x, y, lam, notify)


def _frames(run: RunState, x: Array, y: Array, lam: float, notify: Notify) -> None:
    """The frames in order, ``BLOCK`` at a time; ``run.t`` counts the frames learned."""
    c = run.config
    for s in range(0, x.shape[0], BLOCK):
        xs, ys = x[s : s + BLOCK], y[s : s + BLOCK]
        primed = run.trace is not None
        first = run.t - (0 if primed else 1)  # the iteration that learns frame s
        it = first + np.arange(xs.shape[0])
        run.trace = run.kernel.train_stream(  # type: ignore[attr-defined]
            run.state,
            xs,
            ys,
            run.trace,
            sigma_at(c, it + 1),
            eps_at(c, np.maximum(it, 0)),
            lam=lam,
            geometry=c.geometry,
            winner_rule=training_rule(c),
            threads=c.threads,
        )[1]
        run.t = first + xs.shape[0]
        run.weights = None
        if notify is not None:
            notify()
