"""Reference kernel: dense NumPy, written to be read. The definition the tests trust.

Shapes: ``W`` is ``(K, n_x, n_y)`` (one Sigma-Pi weight per map unit and input pair), codes
``x`` ``(B, n_x)`` and ``y`` ``(B, n_y)``, activations ``h`` ``(B, K)``; ``K`` map units on a
grid ``map_shape`` flattened in C order.

One learning iteration (Fig. 7 of the chapter; docs/algorithm.md):

1. ``h_k = x0^T W_k y0``                                    (:func:`activation`)
2. winner ``k*`` under the winner rule: the rule object's arithmetic
   (:mod:`sigmapi.rules.winners`; the paper's: argmax of h smoothed over the map)
3. ``a_k = exp(-|k - k*|^2 / (2 sigma^2))``, L2-normalised      (:func:`neighbourhood`)
4. ``w_kij += eps a_k (x1_i y1_j - w_kij)`` with the OTHER view
   (:data:`sigmapi.rules.KOHONEN`)

On a periodic map (``geometry.periodic``), grid distances in steps 2 and 3 go the shorter
way round. Steps 2-4 are the rules' reference arithmetic (:mod:`sigmapi.rules`); this module
runs them in order on dense weights, so it computes every rule there is.

:data:`KERNEL` (a :class:`ReferenceKernel`) satisfies the kernel contract
(:class:`sigmapi.kernels.base.Kernel`): its state is the dense weight array ``W`` itself, and
a model file holds it as ``weights``. It keeps the generic defaults of
:class:`~sigmapi.kernels.base.KernelBase` (the rule objects' scores, dense file arrays) and
adds its arithmetic: :func:`activation` and the learning iterations.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import rules
from sigmapi.kernels.base import KernelBase, check_codes, check_map, check_steps
from sigmapi.rules import BATCH_MEAN, KOHONEN, WinnerRule
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.refinement import Sums, assignment
from sigmapi.rules.trace import trace_step

__all__ = ["KERNEL", "NAME", "ReferenceKernel", "activation", "sqnorms"]

Array = NDArray[np.floating]
NAME = "reference"

# Activations of at most this many (sample x weight) products are formed at once.
_CHUNK_ELEMS = 2**24


def sqnorms(W: Array) -> NDArray[np.float64]:
    """``|w_k|^2 = sum_ij W[k, i, j]^2`` of every unit; ``(K,)``."""
    return np.einsum("kij,kij->k", W, W)


def activation(W: Array, x: Array, y: Array) -> NDArray[np.float64]:
    """Sigma-Pi activations ``h[b, k] = sum_ij W[k, i, j] x[b, i] y[b, j]``; ``(B, K)``."""
    k, nx, ny = W.shape
    wf = W.reshape(k, nx * ny)
    b = x.shape[0]
    rows = max(1, _CHUNK_ELEMS // (nx * ny))
    out = np.empty((b, k), dtype=np.float64)
    for s in range(0, b, rows):
        xy = np.einsum("bi,bj->bij", x[s : s + rows], y[s : s + rows]).reshape(-1, nx * ny)
        out[s : s + rows] = xy @ wf.T
    return out


class ReferenceKernel(KernelBase[NDArray[np.float64]]):
    """Dense NumPy weights ``W`` ``(K, n_x, n_y)`` (float64), one thread, every winner rule;
    ``tol`` has no meaning here (this kernel is exact)."""

    NAME = NAME

    def prepare(self, weights: NDArray[np.float64], tol: float = 0.0) -> NDArray[np.float64]:
        """Backend state from float64 weights ``(K, n_x, n_y)``: here a float64 copy."""
        return np.array(weights, dtype=np.float64, copy=True)

    def export(self, state: NDArray[np.float64]) -> NDArray[np.float64]:
        """Dense float64 weights ``(K, n_x, n_y)`` from backend state (no copy)."""
        return np.asarray(state, dtype=np.float64)

    def sqnorms(self, state: NDArray[np.float64]) -> NDArray[np.float64]:
        """``|w_k|^2`` of every unit (:func:`sqnorms`)."""
        return sqnorms(state)

    def activation(self, state: NDArray[np.float64], x: Array, y: Array) -> NDArray[np.float64]:
        """Sigma-Pi activations (:func:`activation`); ``(B, K)``."""
        check_codes(state.shape, x=x, y=y)
        return activation(state, x, y)

    def train_block(
        self,
        state: NDArray[np.float64],
        x0: Array,
        y0: Array,
        x1: Array,
        y1: Array,
        sigmas: Array,
        eps: Array,
        *,
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
        gates: Array | None = None,
        threads: bool = False,
    ) -> NDArray[np.int64]:
        """Run ``len(x0)`` learning iterations in order, updating ``state`` in place.

        Iteration ``t`` finds the winner of view ``(x0[t], y0[t])`` at width ``sigmas[t]``
        (rule ``winner_rule``, smoothing window ``geometry.soft_cut``) and learns view
        ``(x1[t], y1[t])`` with rate ``eps[t]`` (the Kohonen rule). On a periodic map every
        axis wraps around (a ring in 1-D, a torus in 2-D), in the winner's smoothing and in
        the neighbourhood. Returns the winners ``(T,)``.

        ``gates`` ``(T, K)`` in ``[0, 1]`` (reward-gated plasticity,
        :mod:`sigmapi.rules.gating`): iteration ``t`` learns with the neighbourhood
        ``a_k * gates[t, k]``, so ``w_k += eps[t] gates[t, k] a_k (x1_i y1_j - w_k)``; 0
        leaves unit ``k`` as it was, None is the ungated rule. The winner is found on the
        weights as they are before iteration ``t``. ``threads`` is ignored: this kernel is
        written to be read, on one thread.
        """
        W = state
        n = check_codes(W.shape, x0=x0, y0=y0, x1=x1, y1=y1)
        check_map(geometry, W.shape[0])
        check_steps(n, W.shape[0], sigmas=sigmas, eps=eps, gates=gates)
        g = None if gates is None else np.asarray(gates, dtype=np.float64)
        rule = rules.winner_rule(winner_rule, "winner_rule")
        out = np.empty(x0.shape[0], dtype=np.int64)
        for t in range(x0.shape[0]):
            h = activation(W, x0[t : t + 1], y0[t : t + 1])
            k = self.winners(W, h, geometry, rule, float(sigmas[t]))
            a = self.neighbourhood(k, geometry, float(sigmas[t]))[0]
            KOHONEN.update(W, a if g is None else a * g[t], x1[t], y1[t], float(eps[t]))
            out[t] = k[0]
        return out

    def train_stream(
        self,
        state: NDArray[np.float64],
        x: Array,
        y: Array,
        trace: Array | None,
        sigmas: Array,
        eps: Array,
        *,
        lam: float,
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
        threads: bool = False,
    ) -> tuple[NDArray[np.int64], NDArray[np.float64] | None]:
        """Learn the frames ``(x[t], y[t])`` of a stream in order under the trace rule
        (:mod:`sigmapi.rules.trace`), updating ``state`` in place.

        Frame ``t``: if a trace exists (``trace`` ``(K,)`` from the frames before this call,
        or the one built from frames ``0 .. t-1``), the Kohonen update with rate ``eps[t]``
        and the trace as neighbourhood towards frame ``t``; then the winner of frame ``t`` on
        the updated weights at width ``sigmas[t]``, its neighbourhood ``a`` and the next
        trace ``lam * trace + (1 - lam) * a`` (``a`` alone when there was none). ``eps[0]``
        is unused when ``trace`` is None. Returns the winners ``(T,)`` and the trace after
        the last frame (a copy of ``trace`` when there are no frames: None stays None). At
        ``lam = 0`` the iterations are those of :meth:`train_block` on the consecutive pairs
        ``(frame t, frame t + 1)``. ``threads`` is ignored (one thread).
        """
        W = state
        n = check_codes(W.shape, x=x, y=y)
        check_map(geometry, W.shape[0])
        check_steps(n, W.shape[0], sigmas=sigmas, eps=eps)
        if trace is not None and np.shape(trace) != (W.shape[0],):
            raise ValueError(f"trace must have shape ({W.shape[0]},), got {np.shape(trace)}")
        rule = rules.winner_rule(winner_rule, "winner_rule")
        out = np.empty(x.shape[0], dtype=np.int64)
        tr = None if trace is None else np.array(trace, dtype=np.float64)
        for t in range(x.shape[0]):
            if tr is not None:
                KOHONEN.update(W, tr, x[t], y[t], float(eps[t]))
            h = activation(W, x[t : t + 1], y[t : t + 1])
            k = self.winners(W, h, geometry, rule, float(sigmas[t]))
            a = self.neighbourhood(k, geometry, float(sigmas[t]))[0]
            tr = a if tr is None else trace_step(tr, a, lam)
            out[t] = k[0]
        return out, tr

    def refine_start(self, state: NDArray[np.float64], *, tol: float = 0.0) -> Sums:
        """Empty accumulators of a refinement round: sums ``(K, n_x, n_y)``, mass ``(K,)``
        (exact: ``tol``, the fast path's tolerance, is ignored)."""
        k, nx, ny = state.shape
        return BATCH_MEAN.start((k, nx, ny))

    def refine_block(
        self,
        state: NDArray[np.float64],
        acc: Sums,
        x0: Array,
        y0: Array,
        x1: Array,
        y1: Array,
        *,
        geometry: MapGeometry,
        winner_rule: WinnerRule | str,
        sigma: float,
    ) -> NDArray[np.int64]:
        """Add ``len(x0)`` pairs to ``acc`` (:meth:`sigmapi.rules.BatchMean.accumulate`):
        winners of view 0 on the fixed weights, view 1's outer products weighted by
        :func:`~sigmapi.rules.refinement.assignment` at ``sigma``. Returns the winners."""
        k = self.winners_of(state, x0, y0, geometry, winner_rule, 0.0)
        a = assignment(k, geometry, float(sigma))
        BATCH_MEAN.accumulate(acc, a, x1, y1)
        return k

    def refine_finish(self, state: NDArray[np.float64], acc: Sums) -> NDArray[np.float64]:
        """The new weights (:meth:`sigmapi.rules.BatchMean.finish`)."""
        return BATCH_MEAN.finish(state, acc)


KERNEL = ReferenceKernel()
"""The reference kernel (what :data:`sigmapi.kernels.REGISTRY` holds as ``"reference"``)."""
