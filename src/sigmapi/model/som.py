# Over 500 lines: the estimator's public surface (fit, partial_fit, respond, winner, transform,
# save and load) in one place; its parts live in the _grids, _cost, _params, _persist, _refine
# and _stream mixins.
"""SigmaPiSOM: a self-organizing map of Sigma-Pi units (Weber & Wermter 2007).

The estimator holds the state (weights, iteration count, random streams) and delegates the
arithmetic to a kernel (:mod:`sigmapi.kernels`) and its rules (:mod:`sigmapi.rules`). Its
other jobs live beside it: grids and codes (:mod:`sigmapi.model._grids`), the cost
(:mod:`sigmapi.model._cost`), scikit-learn's parameters (:mod:`sigmapi.model._params`),
arrays, files and pickles (:mod:`sigmapi.model._persist`), view checks
(:mod:`sigmapi.model.views`), learning from a stream of frames (:mod:`sigmapi.model._stream`).

Random streams: one :class:`numpy.random.SeedSequence` per run. The initial weights come from
its child ``spawn_key=(0,)``; the training data of iterations ``[b * BLOCK, (b + 1) * BLOCK)``
from child ``(1, b)``; the refinement's pairs of round ``r``, block ``b`` from child
``(4, r, b)`` (:mod:`sigmapi.model._refine`). The data of any iteration is therefore a pure
function of the seed and the iteration number: stopping, saving, loading and continuing gives
the same run, bit for bit, wherever the run was cut.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _memory, _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, DataError, NotFittedError, NumericalError
from sigmapi.kernels import KernelState, get_backend
from sigmapi.kernels.base import MAX_WEIGHT
from sigmapi.model._cost import CostMixin
from sigmapi.model._grids import GridsMixin
from sigmapi.model._params import ParamsMixin, entropy_of, stored_overrides
from sigmapi.model._persist import PersistMixin
from sigmapi.model._refine import RefineMixin
from sigmapi.model._stream import StreamMixin
from sigmapi.model.views import CodeViews, Views, check_gates, check_pairs, fit_views
from sigmapi.rules import WinnerRule, ordering, winner_rule
from sigmapi.tasks import Batch

__all__ = ["BLOCK", "SigmaPiSOM", "load_model"]

BLOCK = 1000
"""Iterations per block of training data (one random child stream per block)."""

Callback = Callable[["SigmaPiSOM"], None]


class SigmaPiSOM(GridsMixin, CostMixin, ParamsMixin, PersistMixin, RefineMixin, StreamMixin):
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

    def __init__(self, config: SOMConfig | None = None, **overrides: Any) -> None:
        if config is not None and not isinstance(config, SOMConfig):
            raise ConfigError(
                f"config must be a sigmapi.SOMConfig or None, got {type(config).__name__}; "
                "pass hyperparameters as keywords instead"
            )
        cfg = config or SOMConfig()
        self.config = stored_overrides(cfg, overrides) if overrides else cfg
        self._t = 0
        self._state: KernelState | None = None
        self._kernel = get_backend(self.config.backend)
        self.seed_entropy = entropy_of(self.config.seed)
        self._block_cache: tuple[int, Batch] | None = None
        self._weights_cache: NDArray[np.float64] | None = None
        self._lock = threading.RLock()
        self._unit_positions: NDArray[np.float64] | None = None  # transform()'s table
        self._sigma_cache: tuple[int, float] | None = None  # (t_, sigma at t_)
        self._refined = 0  # refinement pairs done (all rounds)
        self._refine_rows: int | None = None  # rows a round of it (None: the built-in task)
        self._refine_acc = None  # (round, its sums so far)
        self._trace: NDArray[np.float64] | None = None  # a stream's trace (_stream.py)

    @property
    def t_(self) -> int:
        """Learning iterations done so far; raises :class:`NotFittedError` before fitting."""
        self._check_fitted()
        return self._t

    @t_.setter
    def t_(self, value: int) -> None:
        self._t = int(value)

    @property
    def backend(self) -> str:
        """Name of the kernel in use (one of :data:`sigmapi.kernels.BACKENDS`)."""
        return str(self._kernel.NAME)

    # ------------------------------------------------------------------ state
    def _seq(self, *key: int) -> np.random.Generator:
        ss = np.random.SeedSequence(self.seed_entropy, spawn_key=key)
        return np.random.Generator(np.random.PCG64(ss))

    def initial_weights(
        self, views: tuple[NDArray[np.float64], ...] | None = None
    ) -> NDArray[np.float64]:
        """The run's initial weights ``(n_units, n_x, n_y)``, from the ordering procedure
        (:mod:`sigmapi.rules.ordering`).

        ``ordering="none"``: uniform in ``[-init_scale, init_scale]`` (the paper), from the
        run's child stream ``spawn_key=(0,)``. ``ordering="crossview"``: an ordered start
        computed from view pairs alone: the first pairs of ``views`` when given (your own
        data), else as many pairs of the built-in task from the run's own random stream
        (child ``spawn_key=(2,)``).
        """
        procedure = ordering(self.config.ordering)
        self.check_memory()
        if views is None and procedure.init_pairs:
            b = self.sampler.sample(procedure.init_pairs, self._seq(2))
            views = (b.x0, b.y0, b.x1, b.y1)
        return procedure.initial_weights(self.config, self._seq(0), views)

    def memory_estimate(self) -> int:
        """Bytes this model needs at its peak: the float64 start and the ordered start's
        working memory, the backend's state (its own estimate, ``kernel.memory_bytes``) and
        the float64 ``weights_``."""
        shape = (self.n_units, int(np.prod(self.x_shape)), int(np.prod(self.y_shape)))
        n = shape[0] * shape[1] * shape[2]
        sums = 8 * n if self.config.refine_rounds > 0 else 0  # the refinement's accumulators
        start = ordering(self.config.ordering).start_bytes(self.config.map_shape)
        return 16 * n + sums + start + self._kernel.memory_bytes(shape, self.config.kernel_tol)

    def check_memory(self) -> None:
        """Raise :class:`~sigmapi.errors.ResourceError` (a MemoryError) before allocating if
        the machine's available memory cannot hold :meth:`memory_estimate`."""
        n = self.n_units * int(np.prod(self.x_shape)) * int(np.prod(self.y_shape))
        _memory.check(
            self.memory_estimate(),
            f"a model of {self.n_units} units x {int(np.prod(self.x_shape))} x "
            f"{int(np.prod(self.y_shape))} inputs ({n:,} weights)",
            "use a smaller map_shape, x_shape or y_shape",
        )

    def _set_weights(self, weights: NDArray[np.float64]) -> None:
        top = float(np.abs(weights).max(initial=0.0))
        if not top <= MAX_WEIGHT:  # also NaN
            raise NumericalError(
                f"weights must be finite and at most {MAX_WEIGHT:g} in magnitude (a backend "
                f"may store float32 and scale lazily), got {top:.3g}; rescale them"
            )
        self._state = self._kernel.prepare(weights, tol=self.config.kernel_tol)
        self._weights_cache = None

    @property
    def is_fitted(self) -> bool:
        return self._state is not None

    def _check_fitted(self) -> None:
        if self._state is None:
            raise NotFittedError(
                "this SigmaPiSOM is not fitted yet; call fit() or partial_fit() first, "
                "or load a trained model with sigmapi.load(path)"
            )

    @property
    def weights_(self) -> NDArray[np.float64]:
        self._check_fitted()
        if self._weights_cache is None:
            w = np.array(self._kernel.export(self._state), dtype=np.float64)
            w.flags.writeable = False
            self._weights_cache = w
        return self._weights_cache

    def sigma_at(self, t: int | NDArray[np.int64]) -> NDArray[np.float64]:
        """Neighbourhood width at iteration(s) t of this run's schedule, as the ordering
        procedure caps it (``crossview``: at ``ordering_sigma``)."""
        c = self.config
        return ordering(c.ordering).cap_sigma(
            c.sigma_schedule.at(t, c.iterations), c.ordering_sigma
        )

    def eps_at(self, t: int | NDArray[np.int64]) -> NDArray[np.float64]:
        """Learning rate at iteration(s) t."""
        return self.config.eps_schedule.at(t, self.config.iterations)

    @property
    def sigma_(self) -> float:
        """Neighbourhood width at the current iteration (used by the soft winner)."""
        if self._sigma_cache is None or self._sigma_cache[0] != self.t_:
            self._sigma_cache = (self.t_, float(self.sigma_at(self.t_)))
        return self._sigma_cache[1]

    # ------------------------------------------------------------------ training
    def training_block(self, b: int) -> Batch:
        """The training data of block ``b`` (iterations ``b*BLOCK`` to ``(b+1)*BLOCK - 1``)."""
        if self._block_cache is not None and self._block_cache[0] == b:
            return self._block_cache[1]
        batch = self.sampler.sample(BLOCK, self._seq(1, b))
        self._block_cache = (b, batch)
        return batch

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
        with self._lock:
            data = fit_views(views, self.x_shape, self.y_shape, "fit")
            total = self.config.iterations if iterations is None else iterations
            total = _validate.integer("iterations", total, 0)
            rows = 0 if data is None else data[0].shape[0]
            if data is not None and rows == 0:
                raise DataError("views must hold at least one row (pair of views), got 0 rows")
            if rows:  # each pass permutes every row: the int64 order, before any work
                fix = "pass fewer rows (a random subset), or partial_fit(views): each row once"
                _memory.check_count("views rows", rows, 8, fix)
            self._check_refiner()
            self._set_weights(self.initial_weights(data))
            self._t = 0
            self._refined = 0
            self._refine_acc = None
            self._trace = None
            if data is None:
                self._partial_fit(None, total, callback)
            else:
                npass = 0
                while self._t < total:
                    order = self._seq(3, npass).permutation(rows)[: total - self._t]
                    self._train_rows(data, order, callback)
                    npass += 1
            if self._t >= self.config.iterations:
                self._refine(data, callback)
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
        with self._lock:
            data = fit_views(views, self.x_shape, self.y_shape, "partial_fit")
            if data is not None and iterations is not None:
                raise ConfigError(
                    f"iterations must be None when partial_fit is given views (one iteration "
                    f"per row), got {iterations!r}; pass the first rows, views[i][:n], or "
                    "fit(views, iterations=n) for passes over them"
                )
            n = None if iterations is None else _validate.integer("iterations", iterations, 0)
            return self._partial_fit(data, n, callback)

    def _partial_fit(
        self, data: CodeViews | None, iterations: int | None, callback: Callback | None
    ) -> SigmaPiSOM:
        if self._state is None:
            self._set_weights(self.initial_weights(data))
        if data is not None:
            self._train_rows(data, None, callback)
            return self
        rest = iterations is None  # the rest of the configured run, refinement included
        if iterations is None:
            iterations = self.config.iterations - self._t
            if iterations <= 0 and self._refined < self.refine_total:
                self._check_refiner()
                self._refine(None, callback)  # the configured run continues
                return self
            if iterations <= 0:
                raise ConfigError(
                    f"the configured run of {self.config.iterations} iterations is complete "
                    f"(t_ = {self._t}); pass iterations to train further, e.g. "
                    "partial_fit(iterations=1000)"
                )
        end = self._t + iterations
        while self._t < end:
            b, off = divmod(self._t, BLOCK)
            stop = min(BLOCK, off + end - self._t)
            batch = self.training_block(b)
            sl = slice(off, stop)
            self._run_views(batch.x0[sl], batch.y0[sl], batch.x1[sl], batch.y1[sl])
            if callback is not None:
                callback(self)
        if rest and self._refined < self.refine_total:
            self._check_refiner()
            self._refine(None, callback)
        return self

    def _train_rows(
        self, data: CodeViews, order: NDArray[np.intp] | None, callback: Callback | None
    ) -> None:
        """Iterations on the rows ``order`` of ``data`` (None: all, as given), in chunks of at
        most ``BLOCK`` rows, calling ``callback`` after each."""
        n = data[0].shape[0] if order is None else order.size
        for s in range(0, n, BLOCK):
            rows = slice(s, s + BLOCK) if order is None else order[s : s + BLOCK]
            x0, y0, x1, y1 = (v[rows] for v in data)
            self._run_views(x0, y0, x1, y1)
            if callback is not None:
                callback(self)

    def _run_views(
        self, x0: NDArray[Any], y0: NDArray[Any], x1: NDArray[Any], y1: NDArray[Any]
    ) -> None:
        """One stretch of iterations on view pairs; the ablation ``same_view`` learns view 0."""
        c = self.config
        x1, y1 = (x0, y0) if c.same_view else (x1, y1)
        t = np.arange(self.t_, self.t_ + x0.shape[0])
        self._kernel.train_block(
            self._state,
            x0,
            y0,
            x1,
            y1,
            self.sigma_at(t),
            self.eps_at(t),
            geometry=c.geometry,
            winner_rule=self.winner_rule_,
            threads=c.threads,
        )
        self.t_ += x0.shape[0]
        self._weights_cache = None

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
        self._check_fitted()
        with self._lock:
            data = fit_views(views, self.x_shape, self.y_shape, "learn_gated")
            if data is None:
                raise DataError(
                    "learn_gated needs views (x0, y0, x1, y1), one row per "
                    "iteration, got None; pass the views the gates belong to"
                )
            n = data[0].shape[0]
            g = check_gates(gates, n, self.n_units)
            s = (
                self.sigma_
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
                float(self.eps_at(self.t_))
                if eps is None
                else _validate.number("eps", eps, 0.0, 1.0, fix="a learning rate, e.g. 0.01")
            )
            c = self.config
            self._kernel.train_block(
                self._state,
                *data,
                np.full(n, s),
                np.full(n, e),
                geometry=c.geometry,
                winner_rule=self.winner_rule_,
                gates=g,
            )
            self._weights_cache = None
        return self

    # ------------------------------------------------------------------ using the map
    def respond(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Activations ``h[b, k] = x_b^T W_k y_b`` of every unit; ``(B, n_units)``.

        ``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)`` are codes (``x_code.encode``), flattened in
        C order. Computed by the model's kernel on its own state
        (:meth:`sigmapi.kernels.base.Kernel.activation`).
        """
        xa, ya = self._pairs_of(x, y)
        return np.asarray(self._kernel.activation(self._state, xa, ya), dtype=np.float64)

    def _pairs_of(self, x: ArrayLike, y: ArrayLike) -> tuple[NDArray[np.float64], ...]:
        """Checked codes ``(B, n_x)`` and ``(B, n_y)`` of a fitted model's input pairs."""
        self._check_fitted()
        return check_pairs(x, y, self.x_shape, self.y_shape)

    @property
    def winner_rule_(self) -> WinnerRule:
        """The rule training uses (a :class:`~sigmapi.rules.WinnerRule`): the one named by
        ``config.winner_rule``, as the ordering procedure trains it (``crossview``: the soft
        rule border-normalised)."""
        c = self.config
        return ordering(c.ordering).training_rule(winner_rule(c.winner_rule))

    def winner(
        self,
        x: ArrayLike,
        y: ArrayLike,
        rule: WinnerRule | str | None = None,
        *,
        hard: bool = False,
    ) -> NDArray[np.int64]:
        """Flat index of the winning unit per pair; ``(B,)``.

        Uses the model's winner rule (default: :attr:`winner_rule_`) or ``rule`` (a rule or
        its name), at the current sigma. ``hard=True`` takes the rule's limit at sigma -> 0
        (:attr:`~sigmapi.rules.WinnerRule.hard`): the soft winner becomes the argmax of the
        response (the metrics use this, so that mid-run maps are not smoothed).
        """
        xa, ya = self._pairs_of(x, y)
        chosen = self.winner_rule_ if rule is None else winner_rule(rule, "rule")
        if hard:
            chosen = chosen.hard
        geometry = self.config.geometry
        k = self._kernel.winners_of(self._state, xa, ya, geometry, chosen, self.sigma_)
        return np.asarray(k, dtype=np.int64)

    def transform(self, x: ArrayLike, y: ArrayLike) -> NDArray[np.float64]:
        """Map coordinates of the winner as fractions of each map axis, ``(B, d_map)`` in [0, 1]
        (on a periodic map, fractions of the turn in [0, 1): unit ``k`` of ``n`` at ``k / n``)."""
        k = self.winner(x, y)
        if self._unit_positions is None:
            n = np.asarray(self.map_shape, dtype=np.float64)
            scale = n if self.config.map_periodic else np.maximum(n - 1.0, 1.0)
            self._unit_positions = self.map_coords / scale
        return self._unit_positions[k]

    def unit_sqnorms(self) -> NDArray[np.float64]:
        """``|w_k|^2``, the squared length of every unit's weights; ``(n_units,)``.

        From the kernel's state (a kernel may track them), without forming ``weights_``.
        """
        self._check_fitted()
        return np.asarray(self._kernel.sqnorms(self._state), dtype=np.float64)

    def __repr__(self) -> str:
        fitted = f"t_={self.t_}" if self.is_fitted else "not fitted"
        return (
            f"SigmaPiSOM(map_shape={self.map_shape}, x_shape={self.x_shape}, "
            f"y_shape={self.y_shape}, backend={self.backend!r}, {fitted})"
        )


def load_model(path: str | Path, backend: str | None = None) -> SigmaPiSOM:
    """Read a model file (``sigmapi.load``); see :meth:`SigmaPiSOM.load`."""
    return SigmaPiSOM.load(path, backend=backend)
