"""The kernel contract: what every backend offers, from its state to its model file arrays.

A kernel (a module or an object) satisfies :class:`Kernel`. It owns its state (the weights in
its own layout): it builds it from dense weights, says how much memory it needs, writes it
into a model file and reads it back, and computes the activations, scores, winners,
neighbourhood and learning iterations on it. The estimator only passes the state back to the
kernel. The reference kernel's state is the dense weight array itself; the fast kernel's is a
:class:`~sigmapi.kernels.fast.FastState`. Both satisfy :class:`KernelState`.

Model file arrays: a kernel writes either ``weights`` (dense, ``(K, n_x, n_y)``; every kernel
reads those, :func:`dense_file_weights`) or arrays of its own named ``state_<name>``
(lower-case letters, digits and ``_``), float32 or float64 (what the file format stores).
Another backend reads such a file through :meth:`Kernel.file_weights` of the one that wrote
it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from sigmapi.rules import WinnerRule, winner_rule
from sigmapi.rules.refinement import Sums
from sigmapi.rules.winners import Scoring

__all__ = [
    "CONTRACT",
    "MAX_WEIGHT",
    "REFINER",
    "STREAMER",
    "FileArrays",
    "Kernel",
    "KernelState",
    "Refiner",
    "Streamer",
    "dense_file_weights",
    "rule_scores",
]

MAX_WEIGHT = 1e30
"""Largest weight magnitude a model holds (starts from, saves, loads): far inside every
backend's storage, also the fast kernel's float32 ``raw = W / scale`` with ``scale >= 2**-50``
(about 2e30 at most, against float32's 3.4e38)."""

FileArrays = dict[str, NDArray[np.floating]]
"""Model file arrays by member name (``weights`` or ``state_<name>``)."""
Shape = tuple[int, int, int]


def rule_scores(
    rule: WinnerRule | str,
    h: NDArray[np.floating],
    map_shape: tuple[int, ...],
    sigma: float,
    cut: int,
    map_periodic: bool,
    norms: Callable[[], NDArray[np.float64]],
) -> NDArray[np.float64]:
    """Scores ``(B, K)`` of activations ``h`` under ``rule`` (an object or its name) by the
    rule's own arithmetic; ``norms()`` gives the units' ``|w_k|^2``, called only for a rule
    that needs them. A kernel's winners of ``h`` are the row-wise argmax."""
    r = winner_rule(rule, "rule")
    at = Scoring(map_shape, sigma, cut, map_periodic, norms() if r.needs_norms else None)
    return r.scores(h, at)


def dense_file_weights(shape: Shape, arrays: FileArrays) -> NDArray[np.float64]:
    """Dense float64 weights of model file arrays that hold just ``weights`` ``(K, n_x, n_y)``
    (the layout every kernel reads); ``ValueError`` if they do not."""
    if set(arrays) != {"weights"}:
        raise ValueError(f"dense weights are the one array 'weights', got {sorted(arrays)}")
    w = np.asarray(arrays["weights"])
    if tuple(w.shape) != tuple(shape):
        raise ValueError(f"weights have shape {tuple(w.shape)}, the config needs {tuple(shape)}")
    if w.dtype.kind != "f":
        raise ValueError(f"weights must be floats, got {w.dtype}")
    return np.asarray(w, dtype=np.float64)


class KernelState(Protocol):
    """The weights of a map in a kernel's own layout; ``shape`` is ``(K, n_x, n_y)``."""

    @property
    def shape(self) -> tuple[int, ...]: ...


S = TypeVar("S", bound=KernelState)


class Kernel(Protocol[S]):
    """What a kernel offers (``S``: the type of its state).

    Shapes: weights ``(K, n_x, n_y)``; codes ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``;
    activations ``h`` ``(B, K)``; ``K`` map units on ``map_shape``, flattened in C order.
    ``map_periodic``: the map's axes wrap around (grid distances the shorter way round).
    Winner rules are :class:`~sigmapi.rules.WinnerRule` objects or their names
    (:data:`sigmapi.rules.WINNER_RULES`). ``tol``: the kernel's truncation tolerance
    (``SOMConfig.kernel_tol``; 0 = exact), which an exact kernel ignores.
    """

    NAME: str
    """The backend's name (its key in :data:`sigmapi.kernels.REGISTRY`)."""

    def supports(self, rule: WinnerRule | str) -> bool:
        """Whether the kernel trains and finds winners with ``rule``."""
        ...

    def memory_bytes(self, shape: Shape, tol: float) -> int:
        """Bytes of the state of weights of ``shape`` ``(K, n_x, n_y)`` at ``tol``."""
        ...

    def prepare(self, weights: NDArray[np.float64], tol: float = ...) -> S:
        """State from dense float64 weights ``(K, n_x, n_y)``."""
        ...

    def export(self, state: S) -> NDArray[np.float64]:
        """Dense float64 weights ``(K, n_x, n_y)`` of ``state``."""
        ...

    def max_abs(self, state: S) -> float:
        """Largest ``|w_kij|`` of ``state`` (NaN or inf if it holds them), without forming
        the dense weights where the layout allows."""
        ...

    def file_arrays(self, state: S) -> FileArrays:
        """What a model file stores of ``state``: arrays that restore it exactly (copies)."""
        ...

    def from_file_arrays(self, shape: Shape, arrays: FileArrays, tol: float = ...) -> S:
        """The state :meth:`file_arrays` wrote, for weights of ``shape``, bit for bit (also
        from the files of earlier format versions); ``ValueError`` if the arrays do not fit."""
        ...

    def file_weights(self, shape: Shape, arrays: FileArrays) -> NDArray[np.float64]:
        """Dense float64 weights of what :meth:`file_arrays` wrote (for another backend)."""
        ...

    def sqnorms(self, state: S) -> NDArray[np.float64]:
        """``|w_k|^2`` of every unit, ``(K,)`` (the ``min_distance`` rule's norms)."""
        ...

    def activation(
        self, state: S, x: NDArray[np.floating], y: NDArray[np.floating]
    ) -> NDArray[np.float64]:
        """``h[b, k] = x_b^T W_k y_b``; ``(B, K)``."""
        ...

    def scores(
        self,
        state: S,
        h: NDArray[np.floating],
        map_shape: tuple[int, ...],
        rule: WinnerRule | str,
        sigma: float,
        cut: int,
        map_periodic: bool = ...,
    ) -> NDArray[np.float64]:
        """Per-unit scores ``(B, K)`` of ``h`` under ``rule``; the winners are their argmax."""
        ...

    def winners(
        self,
        state: S,
        h: NDArray[np.floating],
        map_shape: tuple[int, ...],
        rule: WinnerRule | str,
        sigma: float,
        cut: int,
        map_periodic: bool = ...,
    ) -> NDArray[np.int64]:
        """Winning unit per row of ``h`` under ``rule``, ``(B,)``; ties to the lowest index."""
        ...

    def winners_of(
        self,
        state: S,
        x: NDArray[np.floating],
        y: NDArray[np.floating],
        map_shape: tuple[int, ...],
        rule: WinnerRule | str,
        sigma: float,
        cut: int,
        map_periodic: bool = ...,
    ) -> NDArray[np.int64]:
        """Winning unit of each pair ``(x_b, y_b)``, ``(B,)``: the same as ``winners`` of
        ``activation``, for one pair as fast as the kernel allows (no per-call preparation)."""
        ...

    def neighbourhood(
        self,
        winner: NDArray[np.int64],
        map_shape: tuple[int, ...],
        sigma: float,
        map_periodic: bool = ...,
    ) -> NDArray[np.float64]:
        """The L2-normalised Gaussian neighbourhood ``(B, K)`` around each winner ``(B,)``."""
        ...

    def train_block(
        self,
        state: S,
        x0: NDArray[np.floating],
        y0: NDArray[np.floating],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
        sigmas: NDArray[np.floating],
        eps: NDArray[np.floating],
        *,
        map_shape: tuple[int, ...],
        winner_rule: WinnerRule | str,
        soft_cut: int,
        threads: bool = False,
        map_periodic: bool = False,
    ) -> NDArray[np.int64]:
        """``len(x0)`` learning iterations in place: winner of view 0 at ``sigmas[t]``,
        Kohonen update towards view 1 at rate ``eps[t]``. Returns the winners ``(T,)``.
        ``threads``: the kernel may use several threads (the result must not change).
        ``map_periodic``: every map axis wraps around (a ring in 1-D, a torus in 2-D)."""
        ...


CONTRACT: tuple[str, ...] = (
    *Kernel.__annotations__,
    *(n for n, v in vars(Kernel).items() if callable(v) and not n.startswith("_")),
)
"""The names every kernel defines (what :func:`sigmapi.kernels.register_backend` checks)."""


class Refiner(Protocol[S]):
    """What a kernel offers for the refinement (:mod:`sigmapi.rules.refinement`); optional.

    A kernel without these methods trains but does not refine: a config with
    ``refine_rounds > 0`` on it is a :class:`~sigmapi.errors.ConfigError` naming the
    backends that refine (no silent fallback to another kernel).
    """

    def refine_start(self, state: S) -> Sums:
        """Empty float64 accumulators of one round, in the kernel's layout."""
        ...

    def refine_block(
        self,
        state: S,
        acc: Sums,
        x0: NDArray[np.floating],
        y0: NDArray[np.floating],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
        *,
        map_shape: tuple[int, ...],
        winner_rule: WinnerRule | str,
        soft_cut: int,
        sigma: float,
        map_periodic: bool = False,
    ) -> NDArray[np.int64]:
        """Add ``len(x0)`` pairs to ``acc`` in order: the winner of view 0 on the fixed
        ``state`` under ``winner_rule`` (a hard rule), view 1's outer product weighted by the
        assignment at width ``sigma`` (0: the winner alone). Returns the winners. The sums
        must not depend on how the stream is cut into blocks, nor on threads."""
        ...

    def refine_finish(self, state: S, acc: Sums) -> S:
        """The state of the new weights: ``sums / mass`` per unit, unchanged where the mass
        is 0 (:meth:`sigmapi.rules.refinement.BatchMean.finish`)."""
        ...


REFINER: tuple[str, ...] = ("refine_start", "refine_block", "refine_finish")
"""The methods a kernel that refines defines (:class:`Refiner`)."""


S_in = TypeVar("S_in", bound=KernelState, contravariant=True)


class Streamer(Protocol[S_in]):
    """What a kernel offers for learning from a stream (:mod:`sigmapi.rules.trace`); optional.

    A kernel without it trains on view pairs but not on streams:
    :meth:`sigmapi.SigmaPiSOM.fit_stream` on it is a :class:`~sigmapi.errors.ConfigError`
    naming the backends that do.
    """

    def train_stream(
        self,
        state: S_in,
        x: NDArray[np.floating],
        y: NDArray[np.floating],
        trace: NDArray[np.floating] | None,
        sigmas: NDArray[np.floating],
        eps: NDArray[np.floating],
        *,
        lam: float,
        map_shape: tuple[int, ...],
        winner_rule: WinnerRule | str,
        soft_cut: int,
        threads: bool = False,
        map_periodic: bool = False,
    ) -> tuple[NDArray[np.int64], NDArray[np.float64] | None]:
        """The frames ``(x[t], y[t])`` in order, in place: the Kohonen update towards frame
        ``t`` with rate ``eps[t]`` under the trace (if one exists), then frame ``t``'s winner
        at ``sigmas[t]`` and the trace ``lam * trace + (1 - lam) * a`` of its neighbourhood
        ``a``. Returns the winners ``(T,)`` and the trace ``(K,)`` (None while there is
        none). The result must not depend on how the stream is cut, nor on threads."""
        ...


STREAMER: tuple[str, ...] = ("train_stream",)
"""The methods a kernel that learns from streams defines (:class:`Streamer`)."""
