# Over 400 lines: one estimator class (state, training, use, arrays and files) reads as one.
"""SigmaPiSOM: a self-organizing map of Sigma-Pi units (Weber & Wermter 2007).

The estimator holds the state (weights, iteration count, random streams) and delegates the
arithmetic to a kernel module (:mod:`sigmapi.kernels`), so backends are swappable.

Random streams: one :class:`numpy.random.SeedSequence` per run. The initial weights come from
its child ``spawn_key=(0,)``; the training data of iterations ``[b * BLOCK, (b + 1) * BLOCK)``
from child ``(1, b)``. The data of any iteration is therefore a pure function of the seed and
the iteration number: stopping, saving, loading and continuing gives the same run, bit for
bit, wherever the run was cut.
"""

from __future__ import annotations

import copy
import dataclasses
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _memory, _validate
from sigmapi.codes import PopulationCode, grid_coordinates
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, DataError, NotFittedError, NumericalError
from sigmapi.kernels import KernelState, get_backend
from sigmapi.kernels.base import MAX_WEIGHT
from sigmapi.model_file import read_parts, write_parts
from sigmapi.rules import WinnerRule, ordering, winner_rule
from sigmapi.tasks import Batch, TwoViewSampler
from sigmapi.views import CodeViews, Views, check_pairs, check_views, encode_views

__all__ = ["BLOCK", "SigmaPiSOM", "load_model"]

BLOCK = 1000
"""Iterations per block of training data (one random child stream per block)."""

Callback = Callable[["SigmaPiSOM"], None]

_FIELDS = tuple(f.name for f in dataclasses.fields(SOMConfig) if f.name != "extra")
"""The hyperparameters :meth:`SigmaPiSOM.get_params` lists (``extra`` holds notes, no parameter)."""

_SHAPE_FIELDS = ("map_shape", "x_shape", "y_shape")


class SigmaPiSOM:
    """Self-organizing map of Sigma-Pi units, ``h_k = sum_ij w_kij x_i y_j``.

    Trained without a teacher on two views of the same body-centred position z: the winner is
    found from view 0 and the weights learn view 1, so units come to respond to z alone, in a
    topographic map.

    Parameters
    ----------
    config : SOMConfig, optional
        All hyperparameters (default: the authors' 1-D run).
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
        if overrides:
            cfg = cfg.replace(**overrides)
            for k, v in overrides.items():
                # store the caller's object where validation only rebuilt an identical value:
                # scikit-learn's ``clone`` checks that ``__init__`` kept every parameter as given
                if k in _FIELDS and _identical(v, getattr(cfg, k)):
                    object.__setattr__(cfg, k, v)
        self.config = cfg
        self._t = 0
        self._state: KernelState | None = None
        self._kernel = get_backend(self.config.backend)
        self.seed_entropy = _entropy(self.config.seed)
        self._block_cache: tuple[int, Batch] | None = None
        self._weights_cache: NDArray[np.float64] | None = None
        self._lock = threading.RLock()
        self._unit_positions: NDArray[np.float64] | None = None  # transform()'s table
        self._sigma_cache: tuple[int, float] | None = None  # (t_, sigma at t_)

    @property
    def t_(self) -> int:
        """Learning iterations done so far; raises :class:`NotFittedError` before fitting."""
        self._check_fitted()
        return self._t

    @t_.setter
    def t_(self, value: int) -> None:
        self._t = int(value)

    def __sklearn_is_fitted__(self) -> bool:
        """What ``sklearn.utils.validation.check_is_fitted`` asks: whether there are weights."""
        return self.is_fitted

    def __sklearn_tags__(self) -> Any:
        """scikit-learn's tags (asked by its checks from 1.6 on): unsupervised, needs fitting."""
        from sklearn.utils import Tags, TargetTags

        return Tags(estimator_type=None, target_tags=TargetTags(required=False))

    # ------------------------------------------------------------------ shapes and codes
    @property
    def map_shape(self) -> tuple[int, ...]:
        return self.config.map_shape

    @property
    def x_shape(self) -> tuple[int, ...]:
        return self.config.x_shape

    @property
    def y_shape(self) -> tuple[int, ...]:
        return self.config.y_shape

    @property
    def n_units(self) -> int:
        return int(np.prod(self.map_shape))

    @property
    def backend(self) -> str:
        """Name of the kernel in use (one of :data:`sigmapi.kernels.BACKENDS`)."""
        return str(self._kernel.NAME)

    def _code(self, shape: tuple[int, ...]) -> PopulationCode:
        c = self.config
        return PopulationCode(shape, c.code_width, c.code_height, c.code_normalize, c.periodic)

    @property
    def x_code(self) -> PopulationCode:
        """The code of x the model was trained with: ``x_code.encode(p)`` for positions p."""
        return self._code(self.x_shape)

    @property
    def y_code(self) -> PopulationCode:
        """The code of y the model was trained with."""
        return self._code(self.y_shape)

    @property
    def sampler(self) -> TwoViewSampler:
        """The two-view sampler of the model's relation and codes."""
        return TwoViewSampler(self.config.relation, self.x_code, self.y_code)

    @property
    def map_coords(self) -> NDArray[np.float64]:
        """Grid coordinates of the map units, ``(n_units, map_ndim)``, C order."""
        return grid_coordinates(self.map_shape)

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
        """Bytes this model needs at its peak: the float64 start, the backend's state (its
        own estimate, ``kernel.memory_bytes``) and the float64 ``weights_``."""
        shape = (self.n_units, int(np.prod(self.x_shape)), int(np.prod(self.y_shape)))
        n = shape[0] * shape[1] * shape[2]
        return 16 * n + self._kernel.memory_bytes(shape, self.config.kernel_tol)

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
            data = self._check_views(views, "fit")
            total = _count(self.config.iterations if iterations is None else iterations)
            rows = 0 if data is None else data[0].shape[0]
            if data is not None and rows == 0:
                raise DataError("views must hold at least one row (pair of views), got 0 rows")
            self._set_weights(self.initial_weights(data))
            self._t = 0
            if data is None:
                return self._partial_fit(None, total, callback)
            npass = 0
            while self._t < total:
                order = self._seq(3, npass).permutation(rows)[: total - self._t]
                self._train_rows(data, order, callback)
                npass += 1
            return self

    def encode_views(
        self, px0: ArrayLike, py0: ArrayLike, px1: ArrayLike, py1: ArrayLike
    ) -> CodeViews:
        """Two views given as positions, as the codes :meth:`fit` takes: ``(x0, y0, x1, y1)``.

        ``px0``, ``px1`` are retinal positions and ``py0``, ``py1`` gaze directions, each of
        shape ``(B, d)`` (``(B,)`` in 1-D) in [0, 1], fractions of the axis (rescale your
        units first); row b of the four arrays shows the same body-centred position twice.
        The codes are the model's own (:attr:`x_code`, :attr:`y_code`).
        """
        return encode_views(self.x_code, self.y_code, px0, py0, px1, py1)

    # ------------------------------------------------------------------ scikit-learn parameters
    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """The hyperparameters, as scikit-learn's ``get_params``: every field of the config.

        ``SigmaPiSOM(**model.get_params())`` is an unfitted model with the same
        hyperparameters (what ``sklearn.base.clone`` builds; ``extra``, the preset's notes, is
        left out). ``deep`` is there for scikit-learn's signature: nothing is nested.

        Examples
        --------
        >>> som = SigmaPiSOM(map_shape=(6,), seed=0)
        >>> som.get_params()["map_shape"], som.set_params(iterations=2000).config.iterations
        ((6,), 2000)
        """
        return {k: getattr(self.config, k) for k in _FIELDS}

    def set_params(self, **params: Any) -> SigmaPiSOM:
        """Change hyperparameters (``config`` and/or fields of :class:`SOMConfig`); returns self.

        A fitted model keeps its weights and iteration count (so ``set_params(eps=0.001)``
        followed by :meth:`partial_fit` continues with the new value), except when a grid
        changes (``map_shape``, ``x_shape``, ``y_shape``): the weights no longer fit and are
        discarded (call :meth:`fit`). A new ``seed`` re-seeds the random streams; a new
        ``backend`` moves the weights onto that kernel.
        """
        cfg = params.pop("config", self.config)
        if not isinstance(cfg, SOMConfig):
            raise ConfigError(
                f"config must be a sigmapi.SOMConfig, got {type(cfg).__name__}; "
                "or pass single hyperparameters, e.g. set_params(iterations=50000)"
            )
        old, new = self.config, cfg.replace(**params) if params else cfg
        weights = self.weights_ if self.is_fitted else None
        self.config = new
        self._block_cache = None
        self._unit_positions = None  # transform()'s table follows map_shape and map_periodic
        if new.seed != old.seed:
            self.seed_entropy = _entropy(new.seed)
        if new.backend != old.backend:
            self._kernel = get_backend(new.backend)
        if any(getattr(new, k) != getattr(old, k) for k in _SHAPE_FIELDS):
            self._state, self._weights_cache, self._t = None, None, 0
        elif new.backend != old.backend and weights is not None:
            self._set_weights(np.array(weights))
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
            Iterations to run on the built-in task (default: the rest of the configured run).
            Not with ``views``, whose rows are the iterations.
        callback : callable, optional
            ``callback(model)``, called after every chunk of at most ``BLOCK`` iterations.

        Calls from several threads on one model run one after the other (a lock), so no
        iteration is lost; the order in which they run is the threads'.
        """
        with self._lock:
            data = self._check_views(views, "partial_fit")
            if data is not None and iterations is not None:
                raise ConfigError(
                    f"iterations must be None when partial_fit is given views (one iteration "
                    f"per row), got {iterations!r}; pass the first rows, views[i][:n], or "
                    "fit(views, iterations=n) for passes over them"
                )
            n = None if iterations is None else _count(iterations)
            return self._partial_fit(data, n, callback)

    def _partial_fit(
        self, data: CodeViews | None, iterations: int | None, callback: Callback | None
    ) -> SigmaPiSOM:
        if self._state is None:
            self._set_weights(self.initial_weights(data))
        if data is not None:
            self._train_rows(data, None, callback)
            return self
        if iterations is None:
            iterations = self.config.iterations - self._t
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
        if self.config.same_view:
            self._run(x0, y0, x0, y0)
        else:
            self._run(x0, y0, x1, y1)

    def _run(self, x0: NDArray[Any], y0: NDArray[Any], x1: NDArray[Any], y1: NDArray[Any]) -> None:
        t = np.arange(self.t_, self.t_ + x0.shape[0])
        c = self.config
        self._kernel.train_block(
            self._state, x0, y0, x1, y1, self.sigma_at(t), self.eps_at(t),
            map_shape=self.map_shape, winner_rule=self.winner_rule_, soft_cut=c.soft_cut,
            threads=c.threads, map_periodic=c.map_periodic,
        )  # fmt: skip
        self.t_ += x0.shape[0]
        self._weights_cache = None

    def _check_views(self, views: Any, method: str) -> CodeViews | None:
        """``views`` checked against the model's grids (:func:`sigmapi.views.check_views`)."""
        if views is None:
            return None
        if _validate.is_int(views):
            raise ConfigError(
                f"views must be a tuple (x0, y0, x1, y1) of code arrays or None, got the int "
                f"{views}; pass an iteration count by name: {method}(iterations={views})"
            )
        return check_views(views, self.x_shape, self.y_shape)

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
        return np.asarray(
            self._kernel.winners_of(
                self._state,
                xa,
                ya,
                self.map_shape,
                chosen,
                self.sigma_,
                self.config.soft_cut,
                self.config.map_periodic,
            ),
            dtype=np.int64,
        )

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

    def cost_terms(
        self, batch: Batch, sigma: float | None = None
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """Winners of view 0 ``(B,)``, ``|x1 y1^T - w_k|^2`` for every unit ``(B, n_units)``
        and the neighbourhood of each winner at width ``sigma`` (default: the current sigma)
        ``(B, n_units)``, from the model's kernel.

        The distances use ``|x y^T|^2 = |x|^2 |y|^2`` and ``<x y^T, w_k> = h_k``, so no outer
        product is formed.
        """
        k = self.winner(batch.x0, batch.y0)
        h1 = self.respond(batch.x1, batch.y1)
        wn = self.unit_sqnorms()
        dn = (batch.x1**2).sum(1) * (batch.y1**2).sum(1)
        s = self.sigma_ if sigma is None else float(sigma)
        a = self._kernel.neighbourhood(k, self.map_shape, s, self.config.map_periodic)
        return k, dn[:, None] - 2.0 * h1 + wn[None, :], a

    def cost(self, batch: Batch, sigma: float | None = None) -> float:
        """Approximate cost of section 6.3 (after Kaski 1997), mean per sample.

        ``E = mean_mu sum_k a_k^mu |x1^mu y1^mu^T - w_k|^2``, with the neighbourhood a^mu of
        the winner of view 0 at width ``sigma`` (default: the current sigma) and the data
        outer product of view 1.
        """
        _, dist, a = self.cost_terms(batch, sigma)
        return float(np.mean(np.sum(a * dist, axis=1)))

    def replay_twin(self) -> SigmaPiSOM:
        """An unfitted model with this one's config and random streams (its seed entropy).

        ``model.replay_twin().fit(iterations=model.t_)`` replays the run that made ``model``
        (the training data of every iteration is a pure function of the seed entropy and the
        iteration number). ``sklearn.base.clone(model)`` instead builds a model from the
        hyperparameters alone: with ``seed=None``, other random streams.
        """
        twin = SigmaPiSOM(self.config)
        twin.seed_entropy = self.seed_entropy
        return twin

    # ------------------------------------------------------------------ state as arrays, files
    def to_arrays(self) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
        """The model as a JSON-able header and arrays (what a model file holds).

        The header holds the resolved ``config``, the iteration count ``t``, the
        ``seed_entropy`` of the random streams (a decimal string) and the ``backend``; the
        arrays are the backend's own, in its precision, with which the model continues bit
        for bit on that backend (:mod:`sigmapi.model_file`).

        Raises :class:`~sigmapi.errors.NumericalError` if the weights hold NaN or inf, so
        that no file is written that :func:`sigmapi.load` would refuse.
        """
        self._check_fitted()
        return write_parts(self.config, self.t_, self.seed_entropy, self._kernel, self._state)

    @classmethod
    def from_arrays(
        cls,
        header: dict[str, Any],
        arrays: dict[str, NDArray[Any]],
        backend: str | None = None,
        source: str = "arrays",
    ) -> SigmaPiSOM:
        """Rebuild a model from :meth:`to_arrays`'s header and arrays (also of older files).

        ``backend`` runs the model on another kernel (which starts from the weights; the
        kernel state is used only by the backend that wrote it). Raises
        :class:`~sigmapi.errors.ModelFileError`, its message starting with ``source``, if
        the header and arrays do not make a model (:func:`sigmapi.model_file.read_parts`).
        """
        parts = read_parts(header, arrays, backend, source)
        model = cls(parts.config)
        model.seed_entropy = parts.seed_entropy
        if parts.state is not None:
            model._state = parts.state
        else:
            model._set_weights(np.asarray(parts.weights))
        model.t_ = parts.t
        return model

    def save(self, path: str | Path, *, compress: bool = False) -> Path:
        """Write the model atomically to ``path`` (``.npz``, no pickle); returns the path.

        ``compress=True`` deflates the arrays (for archives: smaller, slower). The ``.npz``
        file is the format to keep models in; ``pickle`` works (it stores the same arrays)
        but ties a file to Python and is never safe to load from others.
        """
        from sigmapi.io import write_model

        return write_model(path, *self.to_arrays(), compress=compress)

    @classmethod
    def load(cls, path: str | Path, backend: str | None = None) -> SigmaPiSOM:
        """Read a model written by :meth:`save` (optionally onto another ``backend``)."""
        from sigmapi.io import read_model

        header, arrays = read_model(path)
        return cls.from_arrays(header, arrays, backend=backend, source=str(path))

    # ------------------------------------------------------------------ copies and pickles
    def __getstate__(self) -> dict[str, Any]:
        """State arrays and the config, never modules or compiled kernels (see :meth:`save`)."""
        if self.is_fitted:
            header, arrays = self.to_arrays()
            return {"header": header, "arrays": arrays}
        header = {"config": self.config.to_dict(), "seed_entropy": str(self.seed_entropy)}
        return {"header": header, "arrays": None}

    def __setstate__(self, state: dict[str, Any]) -> None:
        header, arrays = state["header"], state["arrays"]
        if arrays is None:
            twin = SigmaPiSOM(SOMConfig.from_dict(header["config"]))
            twin.seed_entropy = int(header["seed_entropy"])
        else:
            twin = SigmaPiSOM.from_arrays(header, arrays, source="pickle")
        self.__dict__.update(twin.__dict__)

    def __copy__(self) -> SigmaPiSOM:
        """A full copy: a shallow one would share the weights while ``t_`` diverges."""
        return copy.deepcopy(self)

    def __repr__(self) -> str:
        fitted = f"t_={self.t_}" if self.is_fitted else "not fitted"
        return (
            f"SigmaPiSOM(map_shape={self.map_shape}, x_shape={self.x_shape}, "
            f"y_shape={self.y_shape}, backend={self.backend!r}, {fitted})"
        )


def _entropy(seed: int | None) -> int:
    """The entropy of the random streams of ``seed``: ``seed`` itself, or fresh for None."""
    return int(np.random.SeedSequence(seed).entropy)  # type: ignore[arg-type]


def _count(iterations: Any) -> int:
    """An iteration count to run, checked: an int >= 0."""
    return _validate.integer("iterations", iterations, 0)


def _identical(given: Any, stored: Any) -> bool:
    """Whether ``given`` equals ``stored`` with the same types all the way down."""
    if type(given) is not type(stored):
        return False
    if isinstance(given, tuple):
        return len(given) == len(stored) and all(map(_identical, given, stored))
    return bool(given == stored)


def load_model(path: str | Path, backend: str | None = None) -> SigmaPiSOM:
    """Read a model file (``sigmapi.load``); see :meth:`SigmaPiSOM.load`."""
    return SigmaPiSOM.load(path, backend=backend)
