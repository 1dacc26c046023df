"""The trace rule: learning from a stream of frames without pair labels (docs/algorithm.md,
"Learning from a stream").

A stream shows one view ``(x_t, y_t)`` per frame, in time order; the object stays put for a
few frames and moves at moments nobody marks. The trace rule (after Foldiak 1991) keeps a
decaying trace of the neighbourhoods of recent winners,

    ``abar_t = lam abar_{t-1} + (1 - lam) a_t``    (``abar_0 = a_0``),

and learns frame ``t + 1`` under the trace of frames ``0 .. t``: the Kohonen update
``w_kij += eps abar_t,k (x_{t+1,i} y_{t+1,j} - w_kij)``. The trace constant ``lam`` in
[0, 1) is the share of the trace carried from one frame to the next. At ``lam = 0`` the trace
is the last winner's neighbourhood alone, ``abar_t = a_t``, exactly (``0 * abar + 1 * a``):
the two-view rule on consecutive frames, frame ``t`` as view 0 and frame ``t + 1`` as view 1.

:func:`trace_step` is the reference arithmetic; the fast kernel compiles the same function
(:mod:`sigmapi.kernels.fast`), so both evaluate one expression.

References
----------
P. Foldiak, "Learning invariance from transformation sequences", Neural Computation 3 (1991)
194-200.
"""

from __future__ import annotations

from typing import Any

from sigmapi import _validate

__all__ = ["check_trace", "trace_step"]


def trace_step(trace: Any, a: Any, lam: float) -> Any:
    """The next trace ``lam * trace + (1 - lam) * a`` (scalars or arrays of one shape).

    At ``lam = 0`` this is ``a`` bit for bit (for finite ``trace``).
    """
    return lam * trace + (1.0 - lam) * a


def check_trace(lam: Any) -> float:
    """``lam`` as a float in [0, 1), else a ConfigError naming ``trace``."""
    return _validate.number(
        "trace",
        lam,
        0.0,
        1.0,
        hi_open=True,
        fix="0 is the two-view rule on consecutive frames; the share of the trace kept per frame",
    )
