"""Learning from a stream of frames (the trace rule, :mod:`sigmapi.rules.trace`):
:class:`StreamMixin`.

A stream is one view per frame in time order, ``(x, y)`` of shapes ``(T, n_x)`` and
``(T, n_y)``, with no pair labels: the object stays put for a few frames and moves at moments
nobody marks. Iteration ``i`` (``t_`` counts them, as in training on pairs) learns one frame
under the trace of the winners' neighbourhoods of the frames before it; its rate and width
follow the run's schedules at ``i``, so a stream and a two-view run of the same length share
one schedule. At trace 0 the stream's iterations are exactly those of ``partial_fit`` on its
consecutive pairs ``(frame t, frame t + 1)``.

The trace is kept in memory between calls, so a stream cut into several
:meth:`~StreamMixin.partial_fit_stream` calls learns what one call learns. A model file does
not hold it: a saved and loaded model starts a fresh trace at its next frame (as after a
move).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.kernels.base import STREAMER
from sigmapi.model.views import CodeViews, StreamFrames, check_frames
from sigmapi.rules.trace import check_trace

if TYPE_CHECKING:
    from sigmapi.rules import WinnerRule

__all__ = ["StreamMixin", "consecutive_pairs"]

BLOCK = 1000
"""Frames per call of the kernel (the callback is called after each)."""

Array = NDArray[np.float64]


def consecutive_pairs(x: Array, y: Array) -> CodeViews:
    """The two-view data of a stream's consecutive frames, ``(x[:-1], y[:-1], x[1:], y[1:])``
    (views, no copies): what the ordered start and the refinement of a stream learn from."""
    return x[:-1], y[:-1], x[1:], y[1:]


class StreamMixin:
    """``fit_stream`` and ``partial_fit_stream`` for a model with a kernel and schedules."""

    config: SOMConfig
    _kernel: Any
    _state: Any
    _lock: threading.RLock
    _t: int
    _refined: int
    _refine_acc: Any
    _trace: Array | None
    _weights_cache: Any

    if TYPE_CHECKING:

        @property
        def map_shape(self) -> tuple[int, ...]: ...
        @property
        def x_shape(self) -> tuple[int, ...]: ...
        @property
        def y_shape(self) -> tuple[int, ...]: ...
        @property
        def backend(self) -> str: ...
        @property
        def winner_rule_(self) -> WinnerRule: ...
        def initial_weights(self, views: CodeViews | None = None) -> Array: ...
        def _set_weights(self, weights: Array) -> None: ...
        def _check_refiner(self) -> None: ...
        def _refine(self, data: CodeViews | None, callback: Any) -> Any: ...
        def sigma_at(self, t: NDArray[np.int64]) -> Array: ...
        def eps_at(self, t: NDArray[np.int64]) -> Array: ...

    def fit_stream(
        self,
        frames: StreamFrames,
        *,
        trace: float = 0.0,
        iterations: int | None = None,
        callback: Callable[[Any], None] | None = None,
    ) -> Any:
        """Train from fresh initial weights on a stream of frames; returns ``self``.

        Parameters
        ----------
        frames : (x, y)
            Codes of shape ``(T, n_x)`` and ``(T, n_y)``, ``T >= 2``: row t is the view of
            frame t, in time order (e.g. :meth:`sigmapi.tasks.TwoViewSampler.stream`). No
            pair labels: when the object moved is not given.
        trace : float
            The trace constant ``lam`` in [0, 1) (:mod:`sigmapi.rules.trace`): the share of
            the winners' neighbourhood trace carried from one frame to the next. 0 (the
            default) learns each frame under the previous frame's winner alone: the two-view
            rule on consecutive frames.
        iterations : int, optional
            Iterations to run (default ``config.iterations``); each learns one frame. A
            stream shorter than that is replayed in order, in passes; the jump from its last
            frame back to its first is one more unmarked move.
        callback : callable, optional
            ``callback(model)``, called at least once per ``BLOCK`` frames.

        Notes
        -----
        The ordered start (``ordering="crossview"``) and the refinement (``refine_rounds``)
        learn from the stream's consecutive frames as their pairs,
        ``(x[:-1], y[:-1], x[1:], y[1:])``, each refinement round one pass over them in
        order; pairs that straddle a move are wrong pairs there as in training.

        Examples
        --------
        >>> import sigmapi
        >>> som = sigmapi.SigmaPiSOM(map_shape=(6,), x_shape=(6,), y_shape=(6,),
        ...                          iterations=2000, seed=0)
        >>> f = som.sampler.stream(2001, 4, np.random.default_rng(0))
        >>> som.fit_stream((f.x, f.y), trace=0.5).t_
        2000
        """
        with self._lock:
            x, y = check_frames(frames, self.x_shape, self.y_shape, least=2)
            lam = check_trace(trace)
            total = self.config.iterations if iterations is None else iterations
            total = _validate.integer("iterations", total, 0)
            self._check_streamer()
            self._check_refiner()
            pairs = consecutive_pairs(x, y)
            self._set_weights(self.initial_weights(pairs))
            self._t = 0
            self._refined = 0
            self._refine_acc = None
            self._trace = None
            while self._t < total:
                need = total - self._t + (1 if self._trace is None else 0)
                self._run_frames(x[:need], y[:need], lam, callback)
            if self._t >= self.config.iterations:
                self._refine(pairs, callback)
            return self

    def partial_fit_stream(
        self,
        frames: StreamFrames,
        *,
        trace: float = 0.0,
        callback: Callable[[Any], None] | None = None,
    ) -> Any:
        """Continue learning from the next frames of a stream; returns ``self``.

        ``frames`` ``(x, y)``: codes ``(T, n_x)``, ``(T, n_y)`` that follow the frames of
        the calls before (the trace carries over, so a stream cut anywhere into several
        calls learns what one call learns). Each frame is one iteration, but the very first
        frame of a model, which only starts the trace; an unfitted model starts from the
        initial weights of its config (the ordered start from this call's consecutive
        frames, which must then be at least 2). ``trace``: as in :meth:`fit_stream`. No
        refinement (:meth:`refine` runs it on pairs).
        """
        with self._lock:
            least = 2 if self._state is None else 1
            x, y = check_frames(frames, self.x_shape, self.y_shape, least=least)
            lam = check_trace(trace)
            self._check_streamer()
            if self._state is None:
                self._set_weights(self.initial_weights(consecutive_pairs(x, y)))
                self._trace = None
            self._run_frames(x, y, lam, callback)
            return self

    def _check_streamer(self) -> None:
        """A ConfigError if the backend cannot learn from streams or the config asks for the
        ``same_view`` ablation (a stream has no second view to leave out)."""
        missing = [m for m in STREAMER if not hasattr(self._kernel, m)]
        if missing:
            from sigmapi.kernels import REGISTRY

            able = sorted(n for n, k in REGISTRY.items() if all(hasattr(k, m) for m in STREAMER))
            raise ConfigError(
                f"backend {self.backend!r} does not learn from streams (it lacks "
                f"{', '.join(missing)}); use a backend that does: {', '.join(able)}"
            )
        if self.config.same_view:
            raise ConfigError(
                "same_view must be false to learn from a stream, got true: the ablation learns "
                "the view that chose the winner, and a stream's frames have no pairs to swap"
            )

    def _run_frames(
        self, x: Array, y: Array, lam: float, callback: Callable[[Any], None] | None
    ) -> None:
        """The frames in order, ``BLOCK`` at a time; ``t_`` counts the frames learned."""
        c = self.config
        for s in range(0, x.shape[0], BLOCK):
            xs, ys = x[s : s + BLOCK], y[s : s + BLOCK]
            primed = self._trace is not None
            first = self._t - (0 if primed else 1)  # the iteration that learns frame s
            it = first + np.arange(xs.shape[0])
            self._trace = self._kernel.train_stream(
                self._state,
                xs,
                ys,
                self._trace,
                self.sigma_at(it + 1),
                self.eps_at(np.maximum(it, 0)),
                lam=lam,
                geometry=c.geometry,
                winner_rule=self.winner_rule_,
                threads=c.threads,
            )[1]
            self._t = first + xs.shape[0]
            self._weights_cache = None
            if callback is not None:
                callback(self)
