"""Learning rules: how the weights move after the winner is found (docs/algorithm.md,
"Learning: one iteration", step 4).

The Kohonen rule moves every unit towards the outer product of the OTHER view, in proportion
to its neighbourhood value. :meth:`Kohonen.update` is its reference form (NumPy, dense); the
fast kernel computes the same update in compiled form with lazy decay (``W_k = s_k V_k``:
the decay ``(1 - eps a_k)`` goes into the per-unit scale ``s_k``, the sparse additive part
into ``V_k``; ``sigmapi.kernels.fast._unit_chunk``). The two agree to float64 rounding:
``tests/kernels/test_fast_kernel.py`` checks it in the fast kernel's exact mode.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["KOHONEN", "LEARNING_RULES", "Kohonen"]


class Kohonen:
    """The Kohonen update ``W_k <- W_k + eps a_k (x1 y1^T - W_k)`` of every unit ``k``."""

    name = "kohonen"

    def update(
        self,
        W: NDArray[np.floating],
        a: NDArray[np.floating],
        x1: NDArray[np.floating],
        y1: NDArray[np.floating],
        eps: float,
    ) -> None:
        """In place, for one sample: weights ``W`` ``(K, n_x, n_y)``, neighbourhood ``a``
        ``(K,)``, codes ``x1`` ``(n_x,)`` and ``y1`` ``(n_y,)``, learning rate ``eps``."""
        ea = (eps * a)[:, None, None]
        W *= 1.0 - ea
        W += ea * np.outer(x1, y1)[None, :, :]

    def __repr__(self) -> str:
        return f"<learning rule {self.name!r}>"


KOHONEN = Kohonen()
LEARNING_RULES: dict[str, Kohonen] = {KOHONEN.name: KOHONEN}
"""The learning rules by name."""
