"""A map of dendritic neurons with sparse, clustered synapses (Mel 2006; Poirazi et al. 2003).

Unit ``k`` has at most ``D`` dendritic branches. Branch ``d`` holds a cluster of two
synapses, one from retinal unit ``i_kd`` and one from gaze unit ``j_kd`` (weight 1 each), and
an NMDA-like threshold nonlinearity, ``b_kd = 1 / (1 + exp(-g (x_i + y_j - theta)))``: with
``theta`` above the height of one code's peak the branch reaches its plateau only when both
its inputs are active, an AND of a retinal and a gaze position, close to the product
``x_i y_j`` a Sigma-Pi weight multiplies. The soma sums its branches, each with its coupling
strength ``c_kd`` (the output weights of Poirazi's two-layer model):
``h_k = sum_d c_kd b_kd``. A unit thus holds ``2 D`` synapses and ``D`` couplings, against
the ``n_x n_y`` weights of a Sigma-Pi unit; a branch is one of the conjunctions a
basis-function network (:mod:`sigmapi.neurons.basis`) shares between all units, here owned by
one neuron.

The learning rule
-----------------
The couplings learn by the chapter's rule: winner from view 0, then every unit, in proportion
to its neighbourhood ``a_k``, steps towards the branch outputs for view 1,

    dc_kd = eps a_k (b_kd(x1, y1) - c_kd),

a product of the branch's own plateau (local), the soma's activity ``a_k`` (a
back-propagating signal the whole neuron shares) and the coupling itself; its fixed point is
the mean plateau of the branch over the pairs the unit wins (:meth:`SparseDendriticMap.refine`).

Which branches a unit keeps is structural plasticity (turnover of synapse clusters): every
unit starts with a branch on every candidate conjunction and, during the first
``prune_until`` share of the online phase, the branches whose coupling is below a pruning
threshold are removed (a cluster that rarely reaches its plateau when its neuron fires loses
its synapses, as in the activity-dependent stabilisation of synapse clusters). Given the
threshold, a branch's removal depends on its own coupling alone; the threshold itself is not
local. It is set by a ranking: the number of branches the map keeps falls on a geometric
schedule, from all of them to ``D`` per unit on average at ``prune_until``, and stays there,
and the threshold is the coupling of the last branch that number admits. With
``budget="map"`` (the default) that is one ranking of every branch of the map, so a unit whose
z occurs over a long stretch of the retina-gaze square keeps more branches than one at the end
of the range. With ``budget="unit"`` each neuron ranks its own branches and keeps its ``D``
strongest. This uses information from the whole neuron, not only from the branch. On the
fresh seeds of ``benchmarks/results/neurons-sparse.json`` (paper-1d, ``D = 45``) the map-wide
ranking met the 0.02 target on 5 of 5 seeds, the per-neuron ranking on 2 of 5. The refinement
after the online phase leaves the branches as they are. Below ``D`` candidate conjunctions per
unit nothing is pruned.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.config import SOMConfig
from sigmapi.neurons.basis import BasisFunctionMap
from sigmapi.neurons.training import TrainingConfig, train

__all__ = ["SparseDendriticMap", "sparse_summary"]

Array = NDArray[np.float64]


class SparseDendriticMap(BasisFunctionMap):
    """Dendritic neurons of ``D`` branches, two clustered synapses each (module docstring).

    Parameters
    ----------
    config : SOMConfig
        The task: codes, relation, map grid.
    branches : int
        Branches ``D`` each unit keeps.
    stride : int
        Candidate conjunctions: every ``stride``-th retinal and gaze unit per axis.
    gain, threshold : float
        Slope and threshold of the branch sigmoid of ``x_i + y_j``.
    prune_until : float
        Share of the online phase by which the map is down to ``D`` branches per unit.
    budget : {"map", "unit"}
        ``D`` branches per unit on average over the map (one threshold from a map-wide
        ranking of the couplings) or in every unit (each neuron ranks its own branches).

    Examples
    --------
    >>> from sigmapi.config import load_preset
    >>> from sigmapi.neurons.training import TrainingConfig
    >>> m = SparseDendriticMap(load_preset("tiny-1d"), branches=12, budget="unit")
    >>> m = m.fit(TrainingConfig(pairs=2000, refine_pairs=2000), seed=0)
    >>> int(m.mask_.sum(axis=1).max()), m.synapses, m.mean_synapses
    (12, 24, 24.0)
    """

    def __init__(
        self,
        config: SOMConfig,
        branches: int = 40,
        stride: int = 1,
        gain: float = 30.0,
        threshold: float = 1.2,
        prune_until: float = 1.0,
        budget: str = "map",
    ) -> None:
        super().__init__(config, stride=stride, gain=gain, threshold=threshold)
        self.branches = _validate.integer("branches", branches, 1, fix="e.g. 40")
        self.prune_until = _validate.number(
            "prune_until", prune_until, 0.0, 1.0, lo_open=True, fix="e.g. 0.5"
        )
        self.budget = _validate.choice("budget", budget, ("map", "unit"))
        self.mask_ = np.ones((self.n_units, self.n_hidden), dtype=bool)

    def fit(
        self, training: TrainingConfig | None = None, seed: int | np.random.SeedSequence = 0
    ) -> SparseDendriticMap:
        """Train with the two-view rule and the pruning schedule (``seed``: of its pairs and
        start, an int or a ``SeedSequence``); returns self."""
        train(self, training or TrainingConfig(), np.random.default_rng(seed))
        return self

    @property
    def synapses(self) -> int:
        """Two synapses per branch of the unit that keeps the most branches."""
        return 2 * int(self.mask_.sum(axis=1).max())

    @property
    def mean_synapses(self) -> float:
        """Two synapses per branch, mean over the units."""
        return 2.0 * float(self.mask_.sum(axis=1).mean())

    @property
    def couplings(self) -> int:
        """Branch couplings per unit (the most any unit keeps)."""
        return int(self.mask_.sum(axis=1).max())

    def respond(self, x: Array, y: Array) -> Array:
        """``h_k = sum_d c_kd b_kd`` over the branches unit ``k`` keeps ``(B, K)``."""
        return np.asarray(self.hidden(x, y) @ (self.c_ * self.mask_).T)

    def keep(self, n: int) -> None:
        """Keep the strongest branches (largest coupling): ``n`` per unit on average over
        the map (``budget="map"``: one ranking of all the map's branches, so the branches
        above one threshold) or in every unit (``budget="unit"``: a ranking per neuron)."""
        n = min(n, self.n_hidden)
        c = np.where(self.mask_, self.c_, -np.inf)
        mask = np.zeros_like(self.mask_)
        if self.budget == "unit":
            if n >= int(self.mask_.sum(axis=1).max()):
                return
            top = np.argpartition(-c, n - 1, axis=1)[:, :n]
            np.put_along_axis(mask, top, True, axis=1)
        else:
            total = n * self.n_units
            if total >= int(self.mask_.sum()):
                return
            mask.ravel()[np.argpartition(-c.ravel(), total - 1)[:total]] = True
        self.mask_ = mask
        self.c_ = np.where(mask, self.c_, 0.0)

    def set_branches(self, index: NDArray[np.int64]) -> None:
        """Give unit ``k`` the branches ``index[k]`` (candidate conjunctions ``(K, D)``)."""
        mask = np.zeros_like(self.mask_)
        np.put_along_axis(mask, np.asarray(index), True, axis=1)
        self.mask_ = mask
        self.c_ = np.where(mask, self.c_, 0.0)

    def restructure(self, progress: float) -> None:
        """The pruning schedule at ``progress`` (share of the online phase done)."""
        f = min(progress / self.prune_until, 1.0)
        n = self.n_hidden * (self.branches / self.n_hidden) ** f
        self.keep(max(self.branches, int(np.ceil(n))))

    def start(self, a: Array, x1: Array, y1: Array, rng: np.random.Generator) -> None:
        """Every candidate branch, couplings the neighbourhood mean of the plateaus."""
        self.mask_ = np.ones((self.n_units, self.n_hidden), dtype=bool)
        super().start(a, x1, y1, rng)

    def learn(self, a: Array, x1: Array, y1: Array, eps: float) -> None:
        """``dc_kd = eps sum_pairs a_k (b_kd(x1, y1) - c_kd)`` on the kept branches."""
        super().learn(a, x1, y1, eps)
        self.c_ *= self.mask_

    def refine(self, winners: NDArray[np.int64], x1: Array, y1: Array) -> None:
        """Every kept coupling to the mean plateau of its branch over the unit's wins."""
        super().refine(winners, x1, y1)
        self.c_ *= self.mask_


def sparse_summary(model: SparseDendriticMap, z_of_unit: Array) -> dict[str, object]:
    """What the kept branches are: per branch its unit, retinal and gaze position (grid units
    of each code), coupling, and the distance (grid units of x) of the body-centred position
    ``z`` of its conjunction from its unit's decoded z (``z_of_unit`` ``(K, d)``); the median
    distance and the branches per unit."""
    unit, slot = np.nonzero(model.mask_)
    px = model.x_code.coords[model.ix[slot // model.iy.size]]
    py = model.y_code.coords[model.iy[slot % model.iy.size]]
    zb = model.sampler.relation.forward(px / model.x_code.scale, py / model.y_code.scale)
    gap = np.sqrt(np.sum(((zb - z_of_unit[unit]) * model.x_code.scale) ** 2, axis=1))
    return {
        "unit": unit.tolist(),
        "x_position": px.tolist(),
        "y_position": py.tolist(),
        "coupling": model.c_[unit, slot].tolist(),
        "z_gap": gap.tolist(),
        "z_gap_median": float(np.median(gap)),
        "branches_per_unit": np.bincount(unit, minlength=model.n_units).tolist(),
    }
