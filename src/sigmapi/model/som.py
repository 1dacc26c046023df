"""SigmaPiSOM: a self-organizing map of Sigma-Pi units (Weber & Wermter 2007).

The estimator holds one private run state (:mod:`sigmapi.model._run`: its config, the
entropy of its random streams, the kernel state, counters, caches, the refinement's sums, a
stream's trace, one reset; and how the random streams are cut); ``config`` and
``seed_entropy`` read it. The arithmetic is the kernel's (:mod:`sigmapi.kernels`) and its
rules' (:mod:`sigmapi.rules`); the training modes are functions of the run state alone:
view pairs and reward-gated iterations (:mod:`sigmapi.model._train`), the refinement
(:mod:`sigmapi.model._refine`), streams of frames (:mod:`sigmapi.model._stream`). This
class is their public face; the map's queries (:mod:`sigmapi.model._core`), the cost
(:mod:`sigmapi.model._cost`), scikit-learn's parameters (:mod:`sigmapi.model._params`) and
arrays, files and pickles (:mod:`sigmapi.model._persist`) are its bases.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np  # noqa: F401  (the examples' np)
from numpy.typing import ArrayLike

from sigmapi import _memory, _validate
from sigmapi.errors import ConfigError, DataError
from sigmapi.model import _refine, _stream, _train
from sigmapi.model._cost import CostMixin
from sigmapi.model._params import ParamsMixin
from sigmapi.model._persist import PersistMixin
from sigmapi.model._run import BLOCK, Notify
from sigmapi.model.views import StreamFrames, Views, check_frames, check_gates, fit_views
from sigmapi.rules.trace import check_trace
from sigmapi.tasks import Batch

__all__ = ["BLOCK", "SigmaPiSOM", "load_model"]

Callback = Callable[["SigmaPiSOM"], None]


class SigmaPiSOM(CostMixin, ParamsMixin, PersistMixin):
    """Self-organizing map of Sigma-Pi units, ``h_k = sum_ij w_kij x_i y_j``.

    Trained without a teacher on two views of the same body-centred position z: the winner is
    found from view 0 and the weights learn view 1, so units come to respond to z alone, in a
    topographic map.

    Parameters
    ----------
    config : SOMConfig, optional
        All hyperparameters (default ``SOMConfig()``: the authors' 1-D sizes and schedule with
        sigmapi's ordered start and no refinement; the preset ``paper-1d`` adds the
        refinement, ``paper-1d-authors`` is the paper's random start).
    **overrides
        Fields of :class:`SOMConfig` to change, e.g. ``iterations=20000, seed=0``.

    Attributes
    ----------
    weights_ : ndarray, shape (n_units, n_x, n_y)
        Sigma-Pi weights (float64 copy of the backend's state).
    t_ : int
        Learning iterations done so far (a fitted model's; :class:`NotFittedError` before).
    seed_entropy : int
        Entropy of the run's random streams: ``seed`` when given, else drawn afresh when the
        model is made; a model file keeps it, so that an unseeded run can be replayed.

    References
    ----------
    C. Weber and S. Wermter, "A self-organizing map of Sigma-Pi units", Neurocomputing 70
    (2007) 2552-2560; section 6 of "Neural control of actions involving different coordinate
    systems", in Humanoid Robots, Human-like Machines (2007).

    Examples
    --------
    >>> som = SigmaPiSOM(map_shape=(6,), x_shape=(6,), y_shape=(6,), iterations=2000, seed=0)
    >>> som = som.fit()
    >>> som.weights_.shape, som.t_
    ((6, 6, 6), 2000)
    >>> x = som.x_code.encode([[0.2], [0.2]]); y = som.y_code.encode([[0.6], [0.6]])
    >>> som.winner(x, y).shape
    (2,)
    """

    def _notify(self, callback: Callback | None) -> Notify:
        """What a training mode calls after each block: ``callback(self)`` (during which
        :meth:`set_params` is refused: the run in progress keeps the config it started with)."""
        return self._run.notifier(None if callback is None else lambda: callback(self))

    # ------------------------------------------------------------------ training on pairs
    def training_block(self, b: int) -> Batch:
        """The training data of block ``b`` (iterations ``b*BLOCK`` to ``(b+1)*BLOCK - 1``)."""
        return _train.training_block(self._run, b)

    def fit(
        self,
        views: Views | None = None,
        *,
        iterations: int | None = None,
        callback: Callback | None = None,
    ) -> SigmaPiSOM:
        """Train from fresh initial weights; returns ``self``.

        Parameters
        ----------
        views : (x0, y0, x1, y1), optional
            Your own two-view data: codes of shape ``(B, n_x)``, ``(B, n_y)``, ``(B, n_x)``,
            ``(B, n_y)`` (positions become codes with :meth:`encode_views`); row b holds two
            views of one body-centred position, and the winner found from ``(x0[b], y0[b])``
            learns ``(x1[b], y1[b])``. Without it the model trains on its built-in task (the
            relation and codes of its config).
        iterations : int, optional
            Iterations to run (default: the configured run, ``config.iterations``).
        callback : callable, optional
            ``callback(model)``, called at least once per block of ``BLOCK`` iterations.

        Notes
        -----
        With ``views`` the run has the configured length as well, whatever the number of rows:
        the rows are used in passes, each pass in a fresh random order drawn from the run's
        seed (child stream ``spawn_key=(3, pass)``), so the schedule runs to its end, as
        MiniSom's ``train(data, num_iteration)`` does. ``ordering="crossview"`` computes its
        ordered start from the first rows of ``views`` (never from the built-in task).
        :meth:`partial_fit` with ``views`` instead uses each row once, in the given order.

        Examples
        --------
        >>> som = SigmaPiSOM(map_shape=(6,), x_shape=(6,), y_shape=(6,), iterations=3000, seed=0)
        >>> rng = np.random.default_rng(0)
        >>> z = rng.uniform(0, 1, (500, 1))
        >>> px0 = rng.uniform(np.maximum(0, 2 * z - 1), np.minimum(1, 2 * z))  # x + y = 2 z
        >>> px1 = rng.uniform(np.maximum(0, 2 * z - 1), np.minimum(1, 2 * z))
        >>> views = som.encode_views(px0, 2 * z - px0, px1, 2 * z - px1)
        >>> som.fit(views).t_
        3000
        """
        with self._run.lock:
            data = fit_views(views, self.x_shape, self.y_shape, "fit")
            total = self.config.iterations if iterations is None else iterations
            total = _validate.integer("iterations", total, 0)
            rows = 0 if data is None else data[0].shape[0]
            if data is not None and rows == 0:
                raise DataError("views must hold at least one row (pair of views), got 0 rows")
            if rows:  # a pass's int64 order (of every row, or of those it uses), before work
                fix = "pass fewer rows (a random subset), or partial_fit(views): each row once"
                _memory.check_count(
                    "views rows", min(rows, max(total, _train.PERMUTED_ROWS)), 8, fix
                )
            notify = self._notify(callback)
            _train.fit(self._run, data, total, notify)
            return self

    def partial_fit(
        self,
        views: Views | None = None,
        *,
        iterations: int | None = None,
        callback: Callback | None = None,
    ) -> SigmaPiSOM:
        """Continue training where the schedule stopped; returns ``self``.

        Parameters
        ----------
        views : (x0, y0, x1, y1), optional
            Your own data: codes of shape ``(T, n_x)``, ``(T, n_y)``, ``(T, n_x)``,
            ``(T, n_y)``; iteration t finds the winner from ``(x0[t], y0[t])`` and learns
            ``(x1[t], y1[t])`` (``(x0[t], y0[t])`` with ``same_view``). Each row is used once,
            in order (T iterations); the schedule continues at ``t_``. :meth:`fit` runs a
            whole schedule. Without it the model continues on its built-in task.
        iterations : int, optional
            Iterations to run on the built-in task (default: the rest of the configured run,
            its refinement included).
            Not with ``views``, whose rows are the iterations.
        callback : callable, optional
            ``callback(model)``, called after every chunk of at most ``BLOCK`` iterations.

        Calls from several threads on one model run one after the other (a lock), so no
        iteration is lost; the order in which they run is the threads'.
        """
        with self._run.lock:
            data = fit_views(views, self.x_shape, self.y_shape, "partial_fit")
            if data is not None and iterations is not None:
                raise ConfigError(
                    f"iterations must be None when partial_fit is given views (one iteration "
                    f"per row), got {iterations!r}; pass the first rows, views[i][:n], or "
                    "fit(views, iterations=n) for passes over them"
                )
            n = None if iterations is None else _validate.integer("iterations", iterations, 0)
            notify = self._notify(callback)
            _train.partial_fit(self._run, data, n, notify)
            return self

    def learn_gated(
        self,
        views: Views,
        gates: ArrayLike,
        *,
        sigma: float | None = None,
        eps: float | None = None,
    ) -> SigmaPiSOM:
        """Reward-gated iterations outside the schedule; returns ``self``.

        Iteration ``t`` finds the winner of ``(x0[t], y0[t])`` and moves unit ``k`` towards
        ``x1[t] y1[t]^T`` by ``eps gates[t, k] a_k`` (docs/algorithm.md, "Reward-gated
        plasticity"; the ``gates`` of :meth:`sigmapi.kernels.base.Kernel.train_block`). The
        schedule's clock ``t_`` does not move: these iterations come after (or between) its
        runs.

        Parameters
        ----------
        views : (x0, y0, x1, y1)
            Codes of shape ``(T, n_x)``, ``(T, n_y)``, ``(T, n_x)``, ``(T, n_y)``.
        gates : array, shape (T, n_units)
            Per iteration and unit, in ``[0, 1]`` (:func:`sigmapi.rules.gating.reward_gate`).
        sigma, eps : float, optional
            Neighbourhood width and learning rate (default: the schedule's at ``t_``).
        """
        self._run.fitted()
        with self._run.lock:
            data = fit_views(views, self.x_shape, self.y_shape, "learn_gated")
            if data is None:
                raise DataError(
                    "learn_gated needs views (x0, y0, x1, y1), one row per "
                    "iteration, got None; pass the views the gates belong to"
                )
            g = check_gates(gates, data[0].shape[0], self.n_units)
            _train.learn_gated(self._run, data, g, sigma, eps)
        return self

    # ------------------------------------------------------------------ the refinement
    @property
    def refined_(self) -> int:
        """Refinement pairs done so far, all rounds (:meth:`refine`); 0 before or without."""
        self._run.fitted()
        return self._run.refined

    @property
    def refine_total(self) -> int:
        """Refinement pairs of the configured run: rounds x pairs a round (the built-in
        task's ``refine_pairs``, or the rows the refinement in progress runs on)."""
        return _refine.refine_total(self._run)

    @property
    def refine_rounds_done_(self) -> int:
        """Refinement rounds complete (:attr:`refined_` // pairs a round)."""
        return self.refined_ // _refine.per_round(self._run)

    def refine(self, views: Views | None = None, *, callback: Callback | None = None) -> SigmaPiSOM:
        """Run the rest of the configured refinement (``config.refine_rounds`` rounds,
        :mod:`sigmapi.rules.refinement`) on the trained map; returns ``self``.

        Without ``views`` round ``r`` draws ``config.refine_pairs`` fresh pairs of the
        built-in task from the run's child streams ``(4, r, b)``, so a model saved during the
        refinement (:attr:`refined_` is in the model file) continues to the same weights,
        bit for bit. With ``views`` each round is one pass over the rows in the given order
        (give the same rows to continue). ``fit`` calls this after the training.
        ``callback(model)`` is called after every block of at most ``BLOCK`` pairs.
        """
        with self._run.lock:
            self._run.fitted()
            _refine.check_refiner(self.config, self._run.kernel)
            data = fit_views(views, self.x_shape, self.y_shape, "refine")
            if data is not None and data[0].shape[0] == 0:
                raise DataError("views must hold at least one row (pair of views), got 0 rows")
            notify = self._notify(callback)
            _refine.refine(self._run, data, notify)
            return self

    # ------------------------------------------------------------------ streams
    def fit_stream(
        self,
        frames: StreamFrames,
        *,
        trace: float = 0.0,
        iterations: int | None = None,
        callback: Callback | None = None,
    ) -> SigmaPiSOM:
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
        with self._run.lock:
            x, y = check_frames(frames, self.x_shape, self.y_shape, least=2)
            lam = check_trace(trace)
            total = self.config.iterations if iterations is None else iterations
            total = _validate.integer("iterations", total, 0)
            notify = self._notify(callback)
            _stream.fit_stream(self._run, x, y, lam, total, notify)
            return self

    def partial_fit_stream(
        self,
        frames: StreamFrames,
        *,
        trace: float = 0.0,
        callback: Callback | None = None,
    ) -> SigmaPiSOM:
        """Continue learning from the next frames of a stream; returns ``self``.

        ``frames`` ``(x, y)``: codes ``(T, n_x)``, ``(T, n_y)`` that follow the frames of
        the calls before (the trace carries over, so a stream cut anywhere into several
        calls learns what one call learns). Each frame is one iteration, but the very first
        frame of a model, which only starts the trace; an unfitted model starts from the
        initial weights of its config (the ordered start from this call's consecutive
        frames, which must then be at least 2). ``trace``: as in :meth:`fit_stream`. No
        refinement (:meth:`refine` runs it on pairs).
        """
        with self._run.lock:
            least = 2 if self._run.state is None else 1
            x, y = check_frames(frames, self.x_shape, self.y_shape, least=least)
            lam = check_trace(trace)
            notify = self._notify(callback)
            _stream.partial_fit_stream(self._run, x, y, lam, notify)
            return self


def load_model(path: str | Path, backend: str | None = None) -> SigmaPiSOM:
    """Read a model file (``sigmapi.load``); see :meth:`SigmaPiSOM.load`."""
    return SigmaPiSOM.load(path, backend=backend)
