"""The batch refinement after the training (section 6.3; :mod:`sigmapi.rules.refinement`):
:class:`RefineMixin`.

Round ``r`` on the built-in task draws ``config.refine_pairs`` pairs from the run's child
streams ``(4, r, block)``; with ``fit(views)`` a round is one pass over the rows. A round's
winners use the weights of its start, which stay unchanged until the round ends, so a model
saved within a round (``refined_`` is in the model file) replays that round's pairs so far
and continues to the same weights, bit for bit. A refinement in progress continues only on
what it started on (the built-in task, or the same rows: ``refine_rows`` is in the model file
too); other views, or none where it ran on rows, raise a DataError naming what to pass.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, DataError
from sigmapi.kernels.base import REFINER
from sigmapi.model.views import CodeViews, Views, fit_views
from sigmapi.rules.refinement import Sums

if TYPE_CHECKING:
    from sigmapi.rules import WinnerRule
    from sigmapi.tasks import TwoViewSampler

__all__ = ["RefineMixin"]

BLOCK = 1000
"""Pairs per block of a refinement round (one random child stream per block)."""

GROUP = 10
"""Blocks per call of the kernel (at most ``GROUP * BLOCK`` pairs): the fast kernel sorts a
call's pairs by the units they need, so larger calls read the same weights and sums more
often from cache (the sums do not depend on how the stream is cut)."""


class RefineMixin:
    """``refine`` and its progress, for a model with a kernel, random streams and a lock."""

    config: SOMConfig
    _kernel: Any
    _state: Any
    _lock: threading.RLock
    _refined: int
    _refine_rows: int | None
    _refine_acc: tuple[int, Sums] | None
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
        def sampler(self) -> TwoViewSampler: ...
        @property
        def winner_rule_(self) -> WinnerRule: ...
        def _check_fitted(self) -> None: ...
        def _seq(self, *key: int) -> np.random.Generator: ...

    @property
    def refined_(self) -> int:
        """Refinement pairs done so far, all rounds (:meth:`refine`); 0 before or without."""
        self._check_fitted()
        return self._refined

    @property
    def refine_total(self) -> int:
        """Refinement pairs of the configured run: rounds x pairs a round (the built-in
        task's ``refine_pairs``, or the rows the refinement in progress runs on)."""
        return self.config.refine_rounds * self._refine_per()

    @property
    def refine_rounds_done_(self) -> int:
        """Refinement rounds complete (:attr:`refined_` // pairs a round)."""
        return self.refined_ // self._refine_per()

    def _refine_per(self) -> int:
        rows = getattr(self, "_refine_rows", None)
        return self.config.refine_pairs if rows is None else rows

    def refine(
        self, views: Views | None = None, *, callback: Callable[[Any], None] | None = None
    ) -> Any:
        """Run the rest of the configured refinement (``config.refine_rounds`` rounds,
        :mod:`sigmapi.rules.refinement`) on the trained map; returns ``self``.

        Without ``views`` round ``r`` draws ``config.refine_pairs`` fresh pairs of the
        built-in task from the run's child streams ``(4, r, b)``, so a model saved during the
        refinement (:attr:`refined_` is in the model file) continues to the same weights,
        bit for bit. With ``views`` each round is one pass over the rows in the given order
        (give the same rows to continue). ``fit`` calls this after the training.
        ``callback(model)`` is called after every block of at most ``BLOCK`` pairs.
        """
        with self._lock:
            self._check_fitted()
            self._check_refiner()
            data = fit_views(views, self.x_shape, self.y_shape, "refine")
            if data is not None and data[0].shape[0] == 0:
                raise DataError("views must hold at least one row (pair of views), got 0 rows")
            return self._refine(data, callback)

    def _check_refiner(self) -> None:
        """A ConfigError if the config refines and the backend lacks the methods."""
        missing = [m for m in REFINER if not hasattr(self._kernel, m)]
        if self.config.refine_rounds > 0 and missing:
            from sigmapi.kernels import REGISTRY

            able = sorted(n for n, k in REGISTRY.items() if all(hasattr(k, m) for m in REFINER))
            raise ConfigError(
                f"backend {self.backend!r} does not refine (it lacks {', '.join(missing)}), "
                f"got refine_rounds = {self.config.refine_rounds}; set refine_rounds = 0 or "
                f"use a backend that refines: {', '.join(able)}"
            )

    def _check_same_rows(self, data: CodeViews | None) -> None:
        """A refinement in progress continues only on what it started on (its pairs so far
        count rounds of that many rows): a DataError naming what to pass otherwise."""
        rows = None if data is None else int(data[0].shape[0])
        was = getattr(self, "_refine_rows", None)
        if self._refined == 0 or rows == was:
            return
        done = f"its refinement ran {self._refined:,} pairs on"
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

    def _refine(self, data: CodeViews | None, callback: Callable[[Any], None] | None) -> Any:
        c = self.config
        self._check_same_rows(data)
        self._refine_rows = None if data is None else int(data[0].shape[0])
        per = c.refine_pairs if data is None else data[0].shape[0]
        kernel = self._kernel
        rule = self.winner_rule_.hard
        drawn: list[np.ndarray] = []  # the groups' codes, drawn into the same memory
        while self._refined < c.refine_rounds * per:
            r, done = divmod(self._refined, per)
            if self._refine_acc is None or self._refine_acc[0] != r:
                # a round's winners use the weights of its start: replay its pairs so far
                self._refine_acc = (r, kernel.refine_start(self._state))
                self._refine_acc[1].code_shapes = (self.x_shape, self.y_shape)
            acc = self._refine_acc[1]
            while acc.pairs < per:
                lo = acc.pairs
                if data is None:
                    b = lo // BLOCK
                    last = min(b + GROUP, -(-per // BLOCK))  # blocks b .. last - 1
                    hi = min(per, last * BLOCK)
                    views = self._draw(r, b, last, lo - b * BLOCK, hi - b * BLOCK, drawn)
                    ends = [min(per, (i + 1) * BLOCK) for i in range(b, last)]
                else:
                    hi = min(per, lo + GROUP * BLOCK)
                    views = (data[0][lo:hi], data[1][lo:hi], data[2][lo:hi], data[3][lo:hi])
                    ends = [*range(lo + BLOCK, hi, BLOCK), hi]
                x0, y0, x1, y1 = views
                if c.same_view:
                    x1, y1 = x0, y0
                kernel.refine_block(
                    self._state,
                    acc,
                    x0,
                    y0,
                    x1,
                    y1,
                    map_shape=self.map_shape,
                    winner_rule=rule,
                    soft_cut=c.soft_cut,
                    sigma=c.refine_sigma,
                    map_periodic=c.map_periodic,
                )
                for end in ends[:-1]:  # the round's weights stay those of its start until its end
                    self._block_done(r * per + end, done < end, callback)
                if acc.pairs >= per:
                    self._state = kernel.refine_finish(self._state, acc)
                    self._weights_cache = None
                    self._refine_acc = None
                self._block_done(r * per + hi, done < hi, callback)
                if self._refine_acc is None:
                    break
        return self

    def _block_done(self, refined: int, new: bool, callback: Callable[[Any], None] | None) -> None:
        """A block of pairs is in the sums: if it was not before (``new``; a round replayed
        after loading repeats its first blocks), count it and call ``callback``. A model saved
        then replays the round's pairs so far, whatever the kernel already added."""
        if new:
            self._refined = refined
            if callback is not None:
                callback(self)

    def _draw(
        self, r: int, first: int, last: int, lo: int, hi: int, out: list[np.ndarray]
    ) -> CodeViews:
        """Pairs ``lo .. hi - 1`` of blocks ``first .. last - 1`` of round ``r`` (counted from
        the first block's start), each block from its own stream, drawn in place one block at
        a time into ``out`` (the four codes of a group; made on first use, then reused)."""
        n = (last - first) * BLOCK
        if not out or out[0].shape[0] < n:
            out[:] = [np.empty((n, int(np.prod(s)))) for s in (self.x_shape, self.y_shape) * 2]
        for i in range(first, last):
            at = slice((i - first) * BLOCK, (i - first + 1) * BLOCK)
            self.sampler.sample(
                BLOCK, self._seq(4, r, i), out=(out[0][at], out[1][at], out[2][at], out[3][at])
            )
        return out[0][lo:hi], out[1][lo:hi], out[2][lo:hi], out[3][lo:hi]
