"""The kernel contract and the base every backend builds on.

A kernel satisfies :class:`Kernel`. It owns its state (the weights in its own layout): it
builds it from dense weights, says how much memory it needs, writes it into a model file and
reads it back, and computes the activations, scores, winners, neighbourhood and learning
iterations (plain and gated) on it. The estimator only passes the state back to the kernel.
The reference kernel's state is the dense weight array itself; the fast kernel's is a
:class:`~sigmapi.kernels.fast.FastState`. Both satisfy :class:`KernelState`.

:class:`KernelBase` holds what is the same for every backend (the winner rules' scores and
winners from the activations, the neighbourhood, dense model file arrays, norms and the
largest weight from the dense weights), so a backend implements only its arithmetic:
:meth:`~KernelBase.prepare`, :meth:`~KernelBase.export`, :meth:`~KernelBase.activation` and
:meth:`~KernelBase.train_block`, and overrides a default where its layout does better.
:class:`BackendOptions` are a backend's settings (the device, the storage dtype), checked
against what it declares (``DEVICES``, ``DTYPES``). The map reaches a kernel as one value,
:class:`~sigmapi.rules.geometry.MapGeometry` (grid, periodic axes, the soft winner's window).

Model file arrays: a kernel writes either ``weights`` (dense, ``(K, n_x, n_y)``; every kernel
reads those, :func:`dense_file_weights`) or arrays of its own named ``state_<name>``
(lower-case letters, digits and ``_``), float32 or float64 (what the file format stores).
Another backend reads such a file through :meth:`Kernel.file_weights` of the one that wrote
it.
"""

from __future__ import annotations

import copy
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar, Protocol, Self, TypeVar, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.rules import WINNER_RULES, WinnerRule, winner_rule
from sigmapi.rules.geometry import MapGeometry
from sigmapi.rules.neighbourhood import neighbourhood
from sigmapi.rules.refinement import Sums
from sigmapi.rules.winners import Scoring

__all__ = [
    "CONTRACT",
    "MAX_WEIGHT",
    "REFINER",
    "STREAMER",
    "BackendOptions",
    "FileArrays",
    "Kernel",
    "KernelBase",
    "KernelState",
    "Refiner",
    "Streamer",
    "check_codes",
    "check_map",
    "check_steps",
    "dense_file_weights",
]

MAX_WEIGHT = 1e30
"""Largest weight magnitude a model holds (starts from, saves, loads): far inside every
backend's storage, also the fast kernel's float32 ``raw = W / scale`` with ``scale >= 2**-50``
(about 2e30 at most, against float32's 3.4e38)."""

FileArrays = dict[str, NDArray[np.floating]]
"""Model file arrays by member name (``weights`` or ``state_<name>``)."""
Shape = tuple[int, int, int]
Array = NDArray[np.floating]


@dataclass(frozen=True)
class BackendOptions:
    """A backend's settings: where it computes and in what precision it stores the weights.

    Attributes
    ----------
    device : str
        Where the arithmetic runs: ``"cpu"`` for sigmapi's own backends; a GPU backend
        declares its devices (e.g. ``"cuda"``, ``"cuda:1"``) in ``DEVICES``.
    dtype : str or None
        The storage dtype of the weights (``"float32"``, ``"float64"``); None: the
        backend's own choice (the reference kernel: float64; the fast kernel: float32, float64
        in its exact mode ``kernel_tol = 0``).

    A backend checks its options (:meth:`KernelBase.with_options`): a value it does not
    declare is a :class:`~sigmapi.errors.ConfigError` naming the backend and what it takes.
    """

    device: str = "cpu"
    dtype: str | None = None


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


def check_codes(shape: tuple[int, ...], **codes: Array) -> int:
    """The common number of rows of the codes ``codes`` for weights of ``shape``
    ``(K, n_x, n_y)``: those named ``x...`` are ``(B, n_x)``, the others ``(B, n_y)``. A
    ``ValueError`` names the first that does not fit."""
    _, nx, ny = shape
    rows = [np.shape(a)[0] if np.ndim(a) == 2 else -1 for a in codes.values()]
    for (name, a), n in zip(codes.items(), rows, strict=True):
        width = nx if name.startswith("x") else ny
        if n < 0 or np.shape(a)[1] != width:
            raise ValueError(f"{name} must have shape (B, {width}), got {np.shape(a)}")
    if len(set(rows)) > 1:
        raise ValueError(f"{', '.join(codes)} must have the same number of rows, got {rows}")
    return rows[0] if rows else 0


def check_map(geometry: MapGeometry, units: int) -> None:
    """``ValueError`` unless the map ``geometry`` holds the state's ``units``."""
    if geometry.units != units:
        raise ValueError(
            f"the map {geometry.shape} holds {geometry.units} units, the state {units}"
        )


def check_steps(steps: int, units: int, **per_step: Array | None) -> None:
    """``ValueError`` unless every array of ``per_step`` (None: absent) has one entry per step:
    ``(steps,)``, or ``(steps, units)`` for ``gates``."""
    for name, a in per_step.items():
        want = (steps, units) if name == "gates" else (steps,)
        if a is not None and np.shape(a) != want:
            raise ValueError(f"{name} must have shape {want}, got {np.shape(a)}")


class KernelState(Protocol):
    """The weights of a map in a kernel's own layout; ``shape`` is ``(K, n_x, n_y)``."""

    @property
    def shape(self) -> tuple[int, ...]: ...


S = TypeVar("S", bound=KernelState)


class Kernel(Protocol[S]):
    """What a kernel offers (``S``: the type of its state); :class:`KernelBase` implements
    all but the arithmetic.

    Shapes: weights ``(K, n_x, n_y)``; codes ``x`` ``(B, n_x)``, ``y`` ``(B, n_y)``;
    activations ``h`` ``(B, K)``; ``K`` map units on ``geometry.shape``, flattened in C
    order. ``geometry``: the map (:class:`~sigmapi.rules.geometry.MapGeometry`: its grid,
    whether its axes wrap around, the soft winner's window ``soft_cut``). Winner rules are
    :class:`~sigmapi.rules.WinnerRule` objects or their names
    (:data:`sigmapi.rules.WINNER_RULES`). ``tol``: the kernel's truncation tolerance
    (``SOMConfig.kernel_tol``; 0 = exact), which an exact kernel ignores.
    """

    NAME: ClassVar[str]
    """The backend's name (its key in :data:`sigmapi.kernels.REGISTRY`)."""
    COMPILES: ClassVar[bool]
    """Whether the kernel compiles its code on first use (a first call of each of its
    steps takes the compile's time, which a measurement leaves out)."""
    options: BackendOptions
    """Its settings (device, dtype)."""

    def with_options(self, options: BackendOptions) -> Self:
        """The kernel with ``options``, checked (a ConfigError names what it takes)."""
        ...

    def supports(self, rule: WinnerRule | str) -> bool:
        """Whether the kernel trains and finds winners with ``rule``."""
        ...

    def memory_bytes(self, shape: Shape, tol: float) -> int:
        """Bytes of the state of weights of ``shape`` ``(K, n_x, n_y)`` at ``tol``."""
        ...

    def pair_cutoff(self, tol: float) -> float:
        """The share of ``max|x| max|y|`` below which the kernel at ``tol`` skips a pair of
        code values (0: it skips none, an exact kernel)."""
        ...

    def weight_columns(
        self, shape: Shape, arrays: FileArrays
    ) -> tuple[NDArray[np.floating], NDArray[np.float64]]:
        """The weights of a model file's ``arrays`` (written by this kernel) as columns
        ``raw`` ``(n_x n_y, K)`` and per-unit ``scale`` ``(K,)``, ``W[k] = scale[k] raw[:,
        k]``: the kernel's own layout where it keeps one, else the dense weights and ones."""
        ...

    @abstractmethod
    def prepare(self, weights: NDArray[np.float64], tol: float = ...) -> S:
        """State from dense float64 weights ``(K, n_x, n_y)``."""
        ...

    @abstractmethod
    def export(self, state: S) -> NDArray[np.float64]:
        """Dense float64 weights ``(K, n_x, n_y)`` of ``state``."""
        ...

    def max_abs(self, state: S) -> float:
        """Largest ``|w_kij|`` of ``state`` (NaN or inf if it holds them)."""
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

    @abstractmethod
    def activation(self, state: S, x: Array, y: Array) -> NDArray[np.float64]:
        """``h[b, k] = x_b^T W_k y_b``; ``(B, K)``."""
        ...

    def scores(
        self, state: S, h: Array, geometry: MapGeometry, rule: WinnerRule | str, sigma: float
    ) -> NDArray[np.float64]:
        """Per-unit scores ``(B, K)`` of ``h`` under ``rule``; the winners are their argmax."""
        ...

    def winners(
        self, state: S, h: Array, geometry: MapGeometry, rule: WinnerRule | str, sigma: float
    ) -> NDArray[np.int64]:
        """Winning unit per row of ``h`` under ``rule``, ``(B,)``; ties to the lowest index."""
        ...

    def winners_of(
        self,
        state: S,
        x: Array,
        y: Array,
        geometry: MapGeometry,
        rule: WinnerRule | str,
        sigma: float,
    ) -> NDArray[np.int64]:
        """Winning unit of each pair ``(x_b, y_b)``, ``(B,)``: the same as ``winners`` of
        ``activation``, for one pair as fast as the kernel allows (no per-call preparation).
        This default (which :class:`KernelBase` inherits) is that definition."""
        return self.winners(state, self.activation(state, x, y), geometry, rule, sigma)

    def neighbourhood(
        self, winner: NDArray[np.int64], geometry: MapGeometry, sigma: float
    ) -> NDArray[np.float64]:
        """The L2-normalised Gaussian neighbourhood ``(B, K)`` around each winner ``(B,)``."""
        ...

    @abstractmethod
    def train_block(
        self,
        state: S,
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
        """``len(x0)`` learning iterations in place: winner of view 0 at ``sigmas[t]``,
        Kohonen update towards view 1 at rate ``eps[t]``. Returns the winners ``(T,)``.

        ``gates`` ``(T, K)`` in ``[0, 1]`` (reward-gated plasticity,
        :mod:`sigmapi.rules.gating`): iteration ``t`` learns with the neighbourhood
        ``a_k * gates[t, k]`` (0 leaves unit ``k`` as it was); None is the ungated rule.
        ``threads``: the kernel may use several threads (the result must not change)."""
        ...


CONTRACT: tuple[str, ...] = (
    *Kernel.__annotations__,
    *(n for n, v in vars(Kernel).items() if callable(v) and not n.startswith("_")),
)
"""The names every kernel defines (what :func:`sigmapi.kernels.register_backend` checks)."""


@runtime_checkable
class Refiner(Protocol[S]):
    """What a kernel offers for the refinement (:mod:`sigmapi.rules.refinement`); optional.

    A kernel without these methods trains but does not refine: a config with
    ``refine_rounds > 0`` on it is a :class:`~sigmapi.errors.ConfigError` naming the
    backends that refine (no silent fallback to another kernel).
    """

    def refine_start(self, state: S, *, tol: float = 0.0) -> Sums:
        """Empty accumulators of one round, in the kernel's layout; ``tol``: the config's
        ``refine_tol`` (0: the kernel's own arithmetic, bit for bit; a kernel without a fast
        path ignores it)."""
        ...

    def refine_block(
        self,
        state: S,
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


@runtime_checkable
class Streamer(Protocol[S_in]):
    """What a kernel offers for learning from a stream (:mod:`sigmapi.rules.trace`); optional.

    A kernel without it trains on view pairs but not on streams:
    :meth:`sigmapi.SigmaPiSOM.fit_stream` on it is a :class:`~sigmapi.errors.ConfigError`
    naming the backends that do.
    """

    def train_stream(
        self,
        state: S_in,
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
        """The frames ``(x[t], y[t])`` in order, in place: the Kohonen update towards frame
        ``t`` with rate ``eps[t]`` under the trace (if one exists), then frame ``t``'s winner
        at ``sigmas[t]`` and the trace ``lam * trace + (1 - lam) * a`` of its neighbourhood
        ``a``. Returns the winners ``(T,)`` and the trace ``(K,)`` (None while there is
        none). The result must not depend on how the stream is cut, nor on threads."""
        ...


STREAMER: tuple[str, ...] = ("train_stream",)
"""The methods a kernel that learns from streams defines (:class:`Streamer`)."""


class KernelBase(Kernel[S], ABC):
    """A kernel's generic part: a backend subclasses it and implements its arithmetic
    (:meth:`prepare`, :meth:`export`, :meth:`activation`, :meth:`train_block`: the abstract
    methods of :class:`Kernel`, which it subclasses), and may override a default where its
    layout does better (the fast kernel: its norms, its file arrays, its winners in one pass).
    Instances are registered (:func:`sigmapi.kernels.register_backend`); :meth:`with_options`
    gives a configured copy.

    The defaults are the definition (dense float64 weights, the rule objects' arithmetic),
    so a backend that keeps them agrees with the reference kernel by construction.
    """

    NAME: ClassVar[str]
    """The backend's name (its key in :data:`sigmapi.kernels.REGISTRY`, recorded in files)."""
    DEVICES: ClassVar[tuple[str, ...]] = ("cpu",)
    """The devices :attr:`BackendOptions.device` may name on this backend."""
    DTYPES: ClassVar[tuple[str, ...]] = ("float64",)
    """The storage dtypes :attr:`BackendOptions.dtype` may name (None: the backend's own)."""
    COMPILES: ClassVar[bool] = False

    def __init__(self, options: BackendOptions | None = None) -> None:
        self.options = self.check_options(BackendOptions() if options is None else options)

    def check_options(self, options: BackendOptions) -> BackendOptions:
        """``options`` if this backend takes them, else a ConfigError naming what it takes."""
        if not isinstance(options, BackendOptions):
            raise _validate.fail(
                "options", "a sigmapi.kernels.BackendOptions", options, "e.g. BackendOptions()"
            )
        fix = f"backend {self.NAME!r} takes these"
        _validate.choice("device", options.device, self.DEVICES, fix=fix)
        _validate.choice("dtype", options.dtype, (None, *self.DTYPES), fix=fix)
        return options

    def with_options(self, options: BackendOptions) -> Self:
        """A copy of this kernel with ``options`` (checked); this one if they are its own."""
        checked = self.check_options(options)
        if checked == self.options:
            return self
        out = copy.copy(self)
        out.options = checked
        return out

    def __repr__(self) -> str:
        return f"<kernel {self.NAME!r} {self.options}>"

    def pair_cutoff(self, tol: float) -> float:
        """None skipped: the definition is exact."""
        return 0.0

    def weight_columns(
        self, shape: Shape, arrays: FileArrays
    ) -> tuple[NDArray[np.floating], NDArray[np.float64]]:
        """The dense weights (:meth:`file_weights`) as columns, each scale 1."""
        w = self.file_weights(shape, arrays)
        return np.ascontiguousarray(w.reshape(w.shape[0], -1).T), np.ones(w.shape[0])

    # ------------------------------------------------------------------ generic defaults

    def supports(self, rule: WinnerRule | str) -> bool:
        """Every winner rule: the default :meth:`scores` runs the rule objects' arithmetic."""
        return isinstance(rule, WinnerRule) or rule in WINNER_RULES

    def memory_bytes(self, shape: Shape, tol: float = 0.0) -> int:
        """Bytes of the state of weights of ``shape``: dense float64 weights."""
        return 8 * int(np.prod(shape, dtype=np.int64))

    def max_abs(self, state: S) -> float:
        """Largest ``|w_kij|`` of the dense weights (NaN if they hold NaN)."""
        return float(np.abs(self.export(state)).max(initial=0.0))

    def file_arrays(self, state: S) -> FileArrays:
        """What a model file stores: the dense float64 ``weights`` (a copy)."""
        return {"weights": np.array(self.export(state), dtype=np.float64)}

    def file_weights(self, shape: Shape, arrays: FileArrays) -> NDArray[np.float64]:
        """The dense weights :meth:`file_arrays` wrote (checked against ``shape``)."""
        return dense_file_weights(shape, arrays)

    def from_file_arrays(self, shape: Shape, arrays: FileArrays, tol: float = 0.0) -> S:
        """The state of the weights :meth:`file_arrays` wrote."""
        return self.prepare(self.file_weights(shape, arrays), tol)

    def sqnorms(self, state: S) -> NDArray[np.float64]:
        """``|w_k|^2 = sum_ij W[k, i, j]^2`` of every unit; ``(K,)``."""
        w = self.export(state)
        return np.einsum("kij,kij->k", w, w)

    def scores(
        self, state: S, h: Array, geometry: MapGeometry, rule: WinnerRule | str, sigma: float
    ) -> NDArray[np.float64]:
        """Per-unit scores ``(B, K)`` of activations ``h`` by the rule object's own
        arithmetic (:mod:`sigmapi.rules.winners`), with :meth:`sqnorms` where it needs them."""
        r = winner_rule(rule, "rule")
        k = state.shape[0]
        check_map(geometry, k)
        if np.ndim(h) != 2 or np.shape(h)[1] != k:
            raise ValueError(f"h must have shape (B, {k}), got {np.shape(h)}")
        norms = self.sqnorms(state) if r.needs_norms else None
        return r.scores(h, Scoring(geometry, sigma, norms))

    def winners(
        self, state: S, h: Array, geometry: MapGeometry, rule: WinnerRule | str, sigma: float
    ) -> NDArray[np.int64]:
        """The row-wise argmax of :meth:`scores`, ``(B,)``; ties to the lowest index."""
        s = self.scores(state, h, geometry, rule, sigma)
        return np.asarray(np.argmax(s, axis=1), dtype=np.int64)

    def neighbourhood(
        self, winner: NDArray[np.int64], geometry: MapGeometry, sigma: float
    ) -> NDArray[np.float64]:
        """The rules' Gaussian neighbourhood (:func:`sigmapi.rules.neighbourhood.neighbourhood`)."""
        return neighbourhood(winner, geometry, sigma)
