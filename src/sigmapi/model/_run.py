"""The estimator's run: one private :class:`RunState` with one reset, its random streams, its
schedule and its start.

:class:`~sigmapi.model.som.SigmaPiSOM` holds one :class:`RunState`: its config, the entropy
of its random streams, the kernel and its state (the weights), the counters (iterations
``t``, refinement pairs ``refined``), the refinement in progress (its rows, the sums of its
round), a stream's trace, the caches and the lock. The training modes are functions of it
alone (:mod:`~sigmapi.model._train`: pairs and reward-gated iterations;
:mod:`~sigmapi.model._refine`: the refinement; :mod:`~sigmapi.model._stream`: streams);
nothing else writes it.

Random streams: one :class:`numpy.random.SeedSequence` per run, of the entropy ``entropy``
(:func:`rng`). The initial weights come from its child ``spawn_key=(0,)``; the training data
of iterations ``[b * BLOCK, (b + 1) * BLOCK)`` from child ``(1, b)``; the ordered start's
pairs of the built-in task from child ``(2,)``; the order of pass ``p`` over your own rows
from child ``(3, p)``; the refinement's pairs of round ``r``, block ``b`` from child
``(4, r, b)``. The data of any iteration is therefore a pure function of the seed and the
iteration number: stopping, saving, loading and continuing gives the same run, bit for bit,
wherever the run was cut.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory
from sigmapi.codes import grid_coordinates
from sigmapi.config import SOMConfig
from sigmapi.errors import NotFittedError, NumericalError
from sigmapi.kernels import Kernel, KernelState, get_backend
from sigmapi.kernels.base import MAX_WEIGHT
from sigmapi.model._grids import sampler_of
from sigmapi.rules import WinnerRule, ordering, winner_rule
from sigmapi.rules.refinement import Sums
from sigmapi.tasks import Batch

__all__ = [
    "BLOCK",
    "Notify",
    "RunState",
    "check_memory",
    "eps_at",
    "initial_weights",
    "memory_estimate",
    "rng",
    "sigma_at",
    "training_rule",
]

BLOCK = 1000
"""The run's unit of work: iterations per block of training data (one random child stream
per block), pairs per block of a refinement round (one stream each), frames per call of the
kernel in stream learning; a training callback is called at least once per block."""

Array = NDArray[np.float64]
Notify = Callable[[], None] | None
"""What a training mode calls after each block: the caller's ``callback(model)``, or None."""

_GRIDS = ("map_shape", "x_shape", "y_shape")


def rng(entropy: int, *key: int) -> np.random.Generator:
    """The run's random stream of child ``spawn_key=key`` (a PCG64 generator)."""
    ss = np.random.SeedSequence(entropy, spawn_key=key)
    return np.random.Generator(np.random.PCG64(ss))


def sigma_at(c: SOMConfig, t: int | NDArray[np.int64]) -> Array:
    """Neighbourhood width at iteration(s) t of the schedule, as the ordering procedure caps
    it (``crossview``: at ``ordering_sigma``)."""
    return ordering(c.ordering).cap_sigma(c.sigma_schedule.at(t, c.iterations), c.ordering_sigma)


def eps_at(c: SOMConfig, t: int | NDArray[np.int64]) -> Array:
    """Learning rate at iteration(s) t of the schedule."""
    return c.eps_schedule.at(t, c.iterations)


def training_rule(c: SOMConfig) -> WinnerRule:
    """The winner rule training uses: ``config.winner_rule`` as the ordering procedure trains
    it (``crossview``: the soft rule border-normalised)."""
    return ordering(c.ordering).training_rule(winner_rule(c.winner_rule))


def memory_estimate(c: SOMConfig, kernel: Kernel[Any]) -> int:
    """Bytes a model of ``c`` on ``kernel`` needs at its peak: the float64 start and the
    ordered start's working memory, the backend's state (``kernel.memory_bytes``), the
    refinement's sums and the float64 ``weights_``."""
    shape = (int(np.prod(c.map_shape)), int(np.prod(c.x_shape)), int(np.prod(c.y_shape)))
    n = shape[0] * shape[1] * shape[2]
    sums = 8 * n if c.refine_rounds > 0 else 0  # the refinement's accumulators
    start = ordering(c.ordering).start_bytes(c.map_shape)
    return 16 * n + sums + start + kernel.memory_bytes(shape, c.kernel_tol)


def check_memory(c: SOMConfig, kernel: Kernel[Any]) -> None:
    """A :class:`~sigmapi.errors.ResourceError` if the machine cannot hold
    :func:`memory_estimate`."""
    units, nx, ny = (int(np.prod(s)) for s in (c.map_shape, c.x_shape, c.y_shape))
    _memory.check(
        memory_estimate(c, kernel),
        f"a model of {units} units x {nx} x {ny} inputs ({units * nx * ny:,} weights)",
        "use a smaller map_shape, x_shape or y_shape",
    )


def initial_weights(run: RunState, views: tuple[Array, ...] | None = None) -> Array:
    """The run's initial weights from the ordering procedure (:mod:`sigmapi.rules.ordering`):
    child stream ``(0,)``, and for an ordered start without ``views`` the built-in task's
    pairs from child ``(2,)``."""
    c, entropy = run.config, run.entropy
    procedure = ordering(c.ordering)
    check_memory(c, run.kernel)
    if views is None and procedure.init_pairs:
        b = sampler_of(c).sample(procedure.init_pairs, rng(entropy, 2))
        views = (b.x0, b.y0, b.x1, b.y1)
    return procedure.initial_weights(c, rng(entropy, 0), views)


@dataclass(eq=False)
class RunState:
    """Everything a run changes and what it runs on: the config, the entropy of its random
    streams, the kernel and its state, the counters, the refinement in progress, a stream's
    trace, the caches and the lock (one per model: calls from several threads run one after
    the other). The training modes take it alone."""

    config: SOMConfig
    """The hyperparameters (the estimator's ``config``)."""
    entropy: int
    """The entropy of the random streams (the estimator's ``seed_entropy``)."""
    kernel: Kernel[Any]
    state: KernelState | None = None
    t: int = 0
    """Learning iterations done (pairs, rows or frames)."""
    refined: int = 0
    """Refinement pairs done, all rounds."""
    refine_rows: int | None = None
    """Rows a round of the refinement in progress runs on (None: the built-in task)."""
    refine_acc: tuple[int, Sums] | None = None
    """The round in progress and its sums so far (in memory only: a loaded model replays)."""
    trace: Array | None = None
    """A stream's trace (in memory only: a loaded model starts a fresh one)."""
    weights: Array | None = None
    """The float64 copy of the state (``weights_``), until the state changes."""
    block: tuple[int, Batch] | None = None
    """The last block of training data of the built-in task: (block, its batch)."""
    sigma: tuple[int, float] | None = None
    """(t, the width at t), for ``sigma_``."""
    positions: Array | None = None
    """``transform``'s table: every unit's map position as fractions of the axes."""
    lock: threading.RLock = field(default_factory=threading.RLock)
    calling_back: bool = False
    """Whether a training call's callback runs now (``set_params`` is refused meanwhile: the
    run in progress keeps the config it started with)."""

    def notifier(self, callback: Callable[[], object] | None) -> Notify:
        """What a training mode calls after each block: ``callback()``, marked as running
        (:attr:`calling_back`) while it runs; None without one."""
        if callback is None:
            return None

        def notify() -> None:
            self.calling_back = True
            try:
                callback()
            finally:
                self.calling_back = False

        return notify

    def reset(self, state: KernelState | None) -> None:
        """The one reset: a fresh run from ``state`` (None: not fitted), with no iteration, no
        refinement, no trace and no cached weights."""
        self.state = state
        self.t = 0
        self.refined = 0
        self.refine_rows = None
        self.refine_acc = None
        self.trace = None
        self.weights = None

    def restore(self, state: KernelState, t: int, refined: int, rows: int | None) -> None:
        """A run read back from a model file: its state and counters, nothing in memory."""
        self.reset(state)
        self.t, self.refined, self.refine_rows = int(t), int(refined), rows

    def changed(self, state: Any) -> None:
        """The kernel returned a new state (or changed it in place): the cached weights go."""
        self.state = state
        self.weights = None

    def prepared(self, weights: Array, tol: float) -> KernelState:
        """``weights`` as this kernel's state, refused if not finite and at most
        ``MAX_WEIGHT`` in magnitude."""
        top = float(np.abs(weights).max(initial=0.0))
        if not top <= MAX_WEIGHT:  # also NaN
            raise NumericalError(
                f"weights must be finite and at most {MAX_WEIGHT:g} in magnitude (a backend "
                f"may store float32 and scale lazily), got {top:.3g}; rescale them"
            )
        return self.kernel.prepare(weights, tol=tol)

    def fitted(self) -> KernelState:
        """The kernel state; a :class:`NotFittedError` before fitting."""
        if self.state is None:
            raise NotFittedError(
                "this SigmaPiSOM is not fitted yet; call fit() or partial_fit() first, "
                "or load a trained model with sigmapi.load(path)"
            )
        return self.state

    def exported(self) -> Array:
        """The weights as a read-only float64 array (cached until the state changes)."""
        state = self.fitted()
        if self.weights is None:
            w = np.array(self.kernel.export(state), dtype=np.float64)
            w.flags.writeable = False
            self.weights = w
        return self.weights

    def sigma_now(self) -> float:
        """The neighbourhood width at the current iteration (cached per ``t``)."""
        t = self.t
        self.fitted()
        if self.sigma is None or self.sigma[0] != t:
            self.sigma = (t, float(sigma_at(self.config, t)))
        return self.sigma[1]

    def unit_positions(self) -> Array:
        """Map positions of the units as fractions of each axis in [0, 1] (periodic: of the
        turn, unit ``k`` of ``n`` at ``k / n``), cached until the config changes."""
        c = self.config
        if self.positions is None:
            n = np.asarray(c.map_shape, dtype=np.float64)
            scale = n if c.map_periodic else np.maximum(n - 1.0, 1.0)
            self.positions = grid_coordinates(c.map_shape) / scale
        return self.positions

    def reseed(self, entropy: int) -> None:
        """Draw the random streams from ``entropy`` from now on (the cached data goes)."""
        self.entropy = int(entropy)
        self.block = None

    def reconfigure(self, new: SOMConfig) -> None:
        """Change the hyperparameters to ``new``: what follows the config is forgotten; a new
        grid discards the weights (a fresh run, not fitted); a new backend takes the weights
        over (the counters stay; a round in progress is replayed)."""
        old, self.config = self.config, new
        moved = new.backend != old.backend
        grid = any(getattr(new, k) != getattr(old, k) for k in _GRIDS)
        weights = self.exported() if moved and not grid and self.state is not None else None
        self.block = self.sigma = self.positions = None
        if moved:
            self.kernel = get_backend(new.backend)
        if grid:
            self.reset(None)
        elif weights is not None:
            self.changed(self.prepared(np.array(weights), new.kernel_tol))
            self.refine_acc = None  # the old kernel's sums: the round is replayed
