"""A map of dendritic neurons: each unit a two-layer neuron with first-order synapses.

Unit ``k`` has ``D`` dendritic branches. Branch ``d`` carries ordinary synapses from the
retina, ``u_kd`` (``n_x``), and from the gaze, ``v_kd`` (``n_y``); its local drive is

    s_kd = u_kd . x + v_kd . y - (|u_kd|^2 + |v_kd|^2) / 2

(the last term a threshold set by the branch's own synaptic weight), and its output a
saturating, NMDA-like sigmoid ``b_kd = 1 / (1 + exp(-g (s_kd - theta)))``. The soma sums
its branches: ``h_k = sum_d b_kd``. Below ``theta`` the sigmoid is about ``exp(g (s -
theta))`` = ``exp(g u.x) exp(g v.y)`` times a constant: the expansive part of the branch
nonlinearity multiplies the retinal and the gaze drive, so that one branch is a conjunction
of a retinal and a gaze region, and the soma a sum of such conjunctions: a Sigma-Pi unit with
``D`` terms instead of ``n_x n_y`` (Poirazi et al. 2003; Mel 2006). For codes of length 1,
``s_kd = 1 - (|x - u_kd|^2 + |y - v_kd|^2) / 2``: the drive is largest for the input the
branch's synapses match.

The learning rule
-----------------
Cost (the approximate cost of the chapter's section 6.3 with a branch assignment inside each
unit, as k-means inside each neuron):

    E = sum_pairs sum_k a_k sum_d r_kd (|x1 - u_kd|^2 + |y1 - v_kd|^2)

with ``a_k`` the neighbourhood of the winner of **view 0** and ``r_kd`` = 1 for the branch
of unit k with the largest drive ``s_kd`` for **view 1**, else 0 (the assignment that
minimises E over ``r`` with the weights fixed, since ``s_kd = 1 - |.|^2 / 2``). Its gradient
in the weights with the assignments fixed gives the rule

    du_kd = eps a_k r_kd (x1 - u_kd),    dv_kd = eps a_k r_kd (y1 - v_kd),

and its fixed point ``u_kd`` = the mean of ``x1`` over the pairs assigned to branch d of
unit k (:meth:`DendriticMap.refine`). Each factor is local to the synapse: ``x1_i`` the
presynaptic activity; ``r_kd`` an event of the branch (the one branch in a plateau, a
dendritic spike that wins over the neuron's other branches); ``a_k`` a signal the whole
neuron shares (a back-propagating action potential, graded by the map's neighbourhood). The
decay ``-u_kd`` acts only when both the branch and the soma are active. Winner from one view,
learning from the other, is the chapter's rule unchanged; for ``D = 1`` and a linear branch
it is a Kohonen map of first-order units, which cannot learn the transformation.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.neurons.training import CHUNK, FirstOrderMap, TrainingConfig, train

__all__ = ["DendriticMap", "branch_summary"]

Array = NDArray[np.float64]

START_MIX = 0.1
"""Share of one drawn pair in a branch's start (the rest: its unit's neighbourhood mean)."""


class DendriticMap(FirstOrderMap):
    """A map of two-layer dendritic neurons (module docstring) on the task of ``config``.

    Parameters
    ----------
    config : SOMConfig
        The task: codes, relation, map grid (e.g. ``load_preset("paper-1d")``).
    branches : int
        Dendritic branches ``D`` per unit.
    gain, threshold : float
        Slope ``g`` and threshold ``theta`` of the branch sigmoid.

    Examples
    --------
    >>> from sigmapi.config import load_preset
    >>> from sigmapi.neurons.training import TrainingConfig
    >>> cfg = load_preset("tiny-1d")
    >>> short = TrainingConfig(pairs=2000, refine_pairs=2000)
    >>> m = DendriticMap(cfg, branches=3).fit(short, seed=0)
    >>> m.u_.shape == (m.n_units, 3, 9), m.synapses == 3 * (9 + 9)
    (True, True)
    """

    def __init__(
        self, config: SOMConfig, branches: int = 8, gain: float = 8.0, threshold: float = 0.5
    ) -> None:
        self.config = config
        self.branches = _validate.integer("branches", branches, 1, 1024, fix="e.g. 8")
        self.gain = _validate.number("gain", gain, 0.0, lo_open=True, fix="e.g. 8")
        self.threshold = _validate.number("threshold", threshold, -10.0, 10.0, fix="e.g. 0.5")
        k, d = self.n_units, self.branches
        self.u_ = np.zeros((k, d, self.x_code.size))
        self.v_ = np.zeros((k, d, self.y_code.size))

    def fit(
        self, training: TrainingConfig | None = None, seed: int | np.random.SeedSequence = 0
    ) -> DendriticMap:
        """Train with the two-view rule (:func:`sigmapi.neurons.training.train`; ``seed``: of
        its pairs and start, an int or a ``SeedSequence``); returns self."""
        train(self, training or TrainingConfig(), np.random.default_rng(seed))
        return self

    # ---------------------------------------------------------------- the neuron
    def drive(self, x: Array, y: Array) -> Array:
        """Each branch's local drive ``s`` ``(B, K, D)`` (module docstring)."""
        k, d = self.n_units, self.branches
        u = self.u_.reshape(k * d, -1)
        v = self.v_.reshape(k * d, -1)
        bias = 0.5 * ((u**2).sum(axis=1) + (v**2).sum(axis=1))
        return np.asarray((x @ u.T + y @ v.T - bias).reshape(-1, k, d))

    def branch_output(self, x: Array, y: Array) -> Array:
        """Each branch's output ``b`` ``(B, K, D)``: the sigmoid of its drive."""
        z = np.clip(self.gain * (self.drive(x, y) - self.threshold), -60.0, 60.0)
        return np.asarray(1.0 / (1.0 + np.exp(-z)))

    def respond(self, x: Array, y: Array) -> Array:
        """Somatic activations ``h_k = sum_d b_kd`` ``(B, K)``."""
        return np.asarray(self.branch_output(np.asarray(x), np.asarray(y)).sum(axis=2))

    @property
    def synapses(self) -> int:
        """``D (n_x + n_y)``: every branch synapses with every input unit."""
        return self.branches * (self.x_code.size + self.y_code.size)

    def active_synapses(self, fraction: float = 0.01) -> float:
        """Synapses per unit whose weight is at least ``fraction`` of the largest weight of
        its branch on its input (the rest could be pruned: :meth:`pruned`)."""
        return float(
            sum(np.sum(w >= fraction * w.max(axis=2, keepdims=True)) for w in (self.u_, self.v_))
            / self.n_units
        )

    def pruned(self, fraction: float = 0.01) -> DendriticMap:
        """A copy without the synapses below ``fraction`` of their branch's largest weight."""
        out = DendriticMap(self.config, self.branches, self.gain, self.threshold)
        for name in ("u_", "v_"):
            w = getattr(self, name)
            setattr(out, name, np.where(w >= fraction * w.max(axis=2, keepdims=True), w, 0.0))
        return out

    # ---------------------------------------------------------------- learning
    def start(self, a: Array, x1: Array, y1: Array, rng: np.random.Generator) -> None:
        """Each branch half the unit's neighbourhood mean and half one pair drawn from the
        pairs placed near the unit (so that the branches of one unit start apart)."""
        mean_x, mean_y = a @ x1, a @ y1
        for k in range(self.n_units):
            pick = rng.choice(a.shape[1], size=self.branches, p=a[k])
            self.u_[k] = (1.0 - START_MIX) * mean_x[k] + START_MIX * x1[pick]
            self.v_[k] = (1.0 - START_MIX) * mean_y[k] + START_MIX * y1[pick]

    def _assign(self, x1: Array, y1: Array) -> NDArray[np.int64]:
        """The branch of each unit with the largest drive for view 1: ``(B, K)``."""
        return np.asarray(np.argmax(self.drive(x1, y1), axis=2))

    def learn(self, a: Array, x1: Array, y1: Array, eps: float) -> None:
        """``du_kd = eps a_k r_kd (x1 - u_kd)`` and likewise for ``v`` (module docstring)."""
        k, d = self.n_units, self.branches
        r = np.eye(d)[self._assign(x1, y1)]  # (B, K, D) one-hot
        coef = (eps * a[:, :, None] * r).reshape(-1, k * d)
        total = coef.sum(axis=0)[:, None]
        for name, inp in (("u_", x1), ("v_", y1)):
            w = getattr(self, name).reshape(k * d, -1)
            w += coef.T @ inp - total * w

    def refine(self, winners: NDArray[np.int64], x1: Array, y1: Array) -> None:
        """Every branch to the mean of view 1 over the pairs its unit won and it was assigned."""
        k, d = self.n_units, self.branches
        sx = np.zeros((k * d, self.u_.shape[2]))
        sy = np.zeros((k * d, self.v_.shape[2]))
        n = np.zeros(k * d)
        for s in range(0, winners.shape[0], CHUNK):
            w, xs, ys = winners[s : s + CHUNK], x1[s : s + CHUNK], y1[s : s + CHUNK]
            drive = np.take_along_axis(self.drive(xs, ys), w[:, None, None], axis=1)[:, 0]
            slot = w * d + np.argmax(drive, axis=1)
            np.add.at(sx, slot, xs)
            np.add.at(sy, slot, ys)
            n += np.bincount(slot, minlength=k * d)
        seen = n > 0
        u, v = self.u_.reshape(k * d, -1), self.v_.reshape(k * d, -1)
        u[seen] = sx[seen] / n[seen, None]
        v[seen] = sy[seen] / n[seen, None]


def _centre_spread(w: Array, coords: Array) -> tuple[Array, Array, Array]:
    """Centre of mass ``(M, c)``, spread (RMS distance from it, grid units) ``(M,)`` and the
    share of weight within 1.5 grid units of the strongest synapse ``(M,)`` of weights ``w``."""
    p = np.maximum(w, 0.0)
    p = p / np.maximum(p.sum(axis=1, keepdims=True), 1e-300)
    centre = p @ coords
    spread = np.sqrt(np.sum(p * ((coords[None] - centre[:, None]) ** 2).sum(-1), axis=1))
    peak = coords[np.argmax(w, axis=1)]
    near = ((coords[None] - peak[:, None]) ** 2).sum(-1) <= 1.5**2
    return centre, spread, np.sum(p * near, axis=1)


def branch_summary(
    model: DendriticMap, z_of_unit: Array, min_use: float = 0.0
) -> dict[str, object]:
    """What the branches learned: per branch the centre of its retinal and its gaze synapses
    (grid units), their spread, the share of its weight in one region (within 1.5 grid units
    of its strongest synapse, per input), and the body-centred position ``z`` of the
    conjunction its centres make, against ``z_of_unit`` ``(K, d)`` (each unit's decoded z);
    the ``conjunction_share``: branches whose retinal and gaze weights each hold >= 80 % of
    their weight in one region. Positions are in grid units of x."""
    k, d = model.n_units, model.branches
    cx, sx, one_x = _centre_spread(model.u_.reshape(k * d, -1), model.x_code.coords)
    cy, sy, one_y = _centre_spread(model.v_.reshape(k * d, -1), model.y_code.coords)
    px = cx / model.x_code.scale
    py = cy / model.y_code.scale
    zb = model.sampler.relation.forward(px, py)
    unit = np.repeat(np.arange(k), d)
    z_gap = np.sqrt(np.sum(((zb - z_of_unit[unit]) * model.x_code.scale) ** 2, axis=1))
    conj = (one_x >= 0.8) & (one_y >= 0.8)
    return {
        "unit": unit.tolist(),
        "x_centre": cx.tolist(),
        "y_centre": cy.tolist(),
        "x_spread": sx.tolist(),
        "y_spread": sy.tolist(),
        "x_one_region": one_x.tolist(),
        "y_one_region": one_y.tolist(),
        "z_gap": z_gap.tolist(),
        "conjunction_share": float(np.mean(conj)),
        "z_gap_median": float(np.median(z_gap)),
        "spread_median": float(np.median(np.concatenate([sx, sy]))),
    }
