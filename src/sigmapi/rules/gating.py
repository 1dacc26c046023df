"""Reward gating: how much each map unit may learn from one step of a task
(docs/algorithm.md, "Reward-gated plasticity").

In the spirit of attention-gated reinforcement learning (AGREL, Roelfsema & van Ooyen 2005),
the map's own Kohonen update of unit ``k`` is scaled by a gate

    g_k = f(delta) * b_k,        0 <= g_k <= 1

a global factor ``f`` of the critic's TD error ``delta`` times ``b_k``, the feedback from the
chosen action onto unit ``k``: the action's actor weight from unit ``k``, positive part,
relative to the largest (units that did not vote for the chosen action are not changed). The
gated update is then ``w_k += eps g_k a_k (x1 y1^T - w_k)`` (the ``gates`` of
:meth:`sigmapi.kernels.base.Kernel.train_block`): a gate of 0 leaves ``w_k`` as it was, a
gate of 1 is the ungated rule.

The surprise factors ``f`` (:data:`SURPRISE`), each clipped to ``[0, 1]`` after dividing by
``scale``:

- ``"positive"``: ``max(delta, 0) / scale``: learn where the outcome was better than
  expected (the default; see docs/algorithm.md for why);
- ``"absolute"``: ``|delta| / scale``: learn where the outcome was surprising either way;
- ``"constant"``: 1 whatever ``delta`` (only the action's feedback gates: an ablation).

The feedback ``b`` (:data:`FEEDBACK`): ``"action"`` (the chosen action's weights, as above)
or ``"none"`` (every unit 1: the global factor alone).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sigmapi import _validate

__all__ = ["FEEDBACK", "SURPRISE", "action_feedback", "reward_gate", "surprise"]

SURPRISE = ("positive", "absolute", "constant")
"""The global factors of the TD error (see the module's text)."""
FEEDBACK = ("action", "none")
"""The per-unit feedback terms (see the module's text)."""


def surprise(delta: ArrayLike, mode: str = "positive", scale: float = 1.0) -> NDArray[np.float64]:
    """The global factor ``f(delta)`` in ``[0, 1]`` of TD errors ``delta`` (any shape).

    Examples
    --------
    >>> surprise([-0.5, 0.0, 0.25, 2.0], "positive", scale=0.5).tolist()
    [0.0, 0.0, 0.5, 1.0]
    >>> surprise([-0.5, 0.25], "absolute", scale=0.5).tolist()
    [1.0, 0.5]
    """
    _validate.choice("surprise", mode, SURPRISE)  # the kind of surprise (mode)
    scale = _validate.positive("scale", scale, fix="a TD error of this size opens the gate")
    d = np.asarray(delta, dtype=np.float64)
    if mode == "constant":
        return np.ones_like(d)
    raw = np.maximum(d, 0.0) if mode == "positive" else np.abs(d)
    return np.asarray(np.clip(raw / scale, 0.0, 1.0), dtype=np.float64)


def action_feedback(weights: ArrayLike, mode: str = "action") -> NDArray[np.float64]:
    """Feedback ``b_k`` in ``[0, 1]`` from the chosen action's weights ``(K,)`` onto the
    units: the positive part relative to the largest (all 0 when no weight is positive);
    ``mode="none"``: every unit 1.

    Examples
    --------
    >>> action_feedback([0.2, -0.1, 0.4]).tolist()
    [0.5, 0.0, 1.0]
    """
    _validate.choice("feedback", mode, FEEDBACK)  # the kind of feedback (mode)
    w = np.asarray(weights, dtype=np.float64)
    if mode == "none":
        return np.ones_like(w)
    pos = np.maximum(w, 0.0)
    top = float(pos.max(initial=0.0))
    return pos / top if top > 0 else np.zeros_like(w)


def reward_gate(
    delta: float,
    weights: ArrayLike,
    surprise_mode: str = "positive",
    feedback_mode: str = "action",
    scale: float = 1.0,
) -> NDArray[np.float64]:
    """The gates ``g_k = f(delta) b_k`` ``(K,)`` of one step: TD error ``delta`` and the chosen
    action's actor weights ``weights`` ``(K,)`` (:func:`surprise`, :func:`action_feedback`).

    Examples
    --------
    >>> reward_gate(0.5, [0.2, -0.1, 0.4]).tolist()
    [0.25, 0.0, 0.5]
    >>> reward_gate(-0.5, [0.2, -0.1, 0.4]).tolist()
    [0.0, 0.0, 0.0]
    """
    _validate.choice("surprise_mode", surprise_mode, SURPRISE)  # named as this function's
    _validate.choice("feedback_mode", feedback_mode, FEEDBACK)
    return float(surprise(delta, surprise_mode, scale)) * action_feedback(weights, feedback_mode)
