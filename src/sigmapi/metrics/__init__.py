"""How well a Sigma-Pi SOM learned the transformation (definitions: docs/algorithm.md).

- **view consistency**: over test z's, the fraction whose two independent views give the same
  winner, and the fraction whose winners are within one map unit (Chebyshev distance <= 1).
- **z error**: decode z from the winner as the mean z of that unit's wins on a calibration set
  (units that never win there: the affine prediction below); RMSE on a separate test set, in
  input grid spacings (Euclidean over the z dimensions).
- **order**: R^2 of an affine fit from winner grid coordinates to z (fit on the calibration
  set, scored on the test set); a rotated or mirrored map is not penalised, a twisted one is.
- **usage**: fraction of units that win for some test z.
- **fold score** (never reads z, only the two views of each test pair): the larger of

  * the number of *starved* units: units that win fewer than ``STARVED_SHARE`` (10 %) of a
    uniform share of the test views (both views of every pair). A 1-D map folded onto itself
    leaves the unit at the fold almost without wins;
  * for maps of two or more dimensions, ``S / TWIST_S`` with
    ``S = (1 - view_within_one) + topographic_error`` (the topographic error is the fraction
    of view-0 test pairs whose best and second-best units are not grid neighbours). A twist
    sends the two views of one z, and the best and second-best units of one view, to far-apart
    units along its seam. In 1-D this term is left out: the paper's soft winner swaps the two
    end units of many well-ordered maps, which raises the topographic error without a fold
    (measured in docs/algorithm.md, "Ordering procedures");
  * for 1-D maps, ``F / FAR_SHARE`` with ``F`` the fraction of test pairs whose two views win
    units ``FAR_UNITS`` (3) or more apart. A fold lays two branches of the map over the same
    z's, and the two views of one z then land on different branches; in an ordered map they
    land at most two units apart. This catches the folds of small maps that starve no unit.

  ``folded`` is ``fold_score >= FOLD_THRESHOLD`` (1.0). The thresholds were chosen on every map
  trained while building the ordering procedure (docs/algorithm.md, "Ordering procedures").

Winners are the **hard winners** (``model.winner(..., hard=True)``): the rule's limit at
sigma -> 0, the argmax of the response for the soft rule. The soft winner at a mid-run sigma
would smooth the map's differences away and inflate mid-run scores.

All metrics draw their data from a fixed evaluation seed, independent of the training seed,
so that two models are measured on the same test set.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.metrics.circular import circular_metrics, map_distance
from sigmapi.rules import Scoring

if TYPE_CHECKING:
    from sigmapi.model.som import SigmaPiSOM
    from sigmapi.tasks import Batch

__all__ = [
    "EVAL_SEED",
    "FOLD_THRESHOLD",
    "ORDERED_R2",
    "Metrics",
    "affine_fit",
    "evaluate",
    "fold_indicators",
    "grid_spacing",
    "hard_scores",
    "starved_mask",
    "winner_metrics",
    "z_decoder",
]

EVAL_SEED = 20070601
"""Seed of the evaluation data (calibration and test sets)."""

STARVED_SHARE = 0.1
"""A unit is starved when it wins fewer than this fraction of a uniform share of the views."""

TWIST_S = 0.065
"""Maps of 2+ dimensions: ``(1 - within one) + topographic error`` that counts as one fold sign."""

FAR_UNITS = 3.0
"""1-D maps: two views whose winners are this many units apart (or more) count as far apart."""

FAR_SHARE = 0.002
"""1-D maps: the fraction of far-apart view pairs that counts as one fold sign."""

FOLD_THRESHOLD = 1.0
"""``folded`` is ``fold_score >= FOLD_THRESHOLD``."""

ORDERED_R2 = 0.95
"""A map counts as ordered when its order R^2 (or the affine R^2 of its receptive-field
centres, in figure captions) is at least this; below it, captions call the map twisted."""


@dataclass(frozen=True)
class Metrics:
    """Metrics of one model on one test set (see the module docstring)."""

    view_consistency: float
    view_within_one: float
    z_error: float
    order_r2: float
    usage: float
    n_test: int
    fold_score: float = 0.0
    fold_threshold: float = FOLD_THRESHOLD
    folded: bool = False
    starved_units: int = 0
    topographic_error: float = 0.0
    circular: dict[str, float | bool] | None = None
    """Maps of angles only (a relation with circular z): ``order_circular``, ``seam_jump``,
    ``seam_gap``, ``seam_units_win`` and ``seamless`` (:mod:`sigmapi.metrics.circular`); their
    ``z_error`` is then the circular one. None for every other relation."""

    def to_dict(self) -> dict[str, float | int | bool]:
        """The metrics as one flat table (the circular ones beside the rest, when present)."""
        out = asdict(self)
        out.update(out.pop("circular") or {})
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Metrics:
        """The metrics a :meth:`to_dict` wrote (keys that are no field are the circular ones)."""
        names = {f.name for f in fields(cls)} - {"circular"}
        circular = {k: v for k, v in data.items() if k not in names}
        return cls(**{k: v for k, v in data.items() if k in names}, circular=circular or None)


def affine_fit(coords: NDArray[np.float64], z: NDArray[np.float64]) -> NDArray[np.float64]:
    """Least-squares affine map from coordinates ``(N, c)`` to z ``(N, d)``: ``(c + 1, d)``."""
    a = np.hstack([coords, np.ones((coords.shape[0], 1))])
    beta, *_ = np.linalg.lstsq(a, z, rcond=None)
    return np.asarray(beta)


def _affine_predict(beta: NDArray[np.float64], coords: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.hstack([coords, np.ones((coords.shape[0], 1))]) @ beta


def z_decoder(
    winners: NDArray[np.int64], z: NDArray[np.float64], map_coords: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Per-unit decoded z ``(n_units, d)``: mean z of each unit's wins; the affine fit elsewhere."""
    n_units, d = map_coords.shape[0], z.shape[1]
    counts = np.bincount(winners, minlength=n_units).astype(np.float64)
    sums = np.zeros((n_units, d))
    np.add.at(sums, winners, z)
    beta = affine_fit(map_coords[winners], z)
    table = _affine_predict(beta, map_coords)
    seen = counts > 0
    table[seen] = sums[seen] / counts[seen, None]
    return table


def grid_spacing(x_shape: tuple[int, ...], periodic: bool = False) -> NDArray[np.float64]:
    """Grid spacings per unit of position along each axis of x: z errors are reported in them."""
    n = np.asarray(x_shape, dtype=np.float64)
    return n if periodic else n - 1.0


def chebyshev(
    map_coords: NDArray[np.float64],
    a: NDArray[np.int64],
    b: NDArray[np.int64],
    periodic_shape: tuple[int, ...] | None = None,
) -> NDArray[np.float64]:
    """Chebyshev distance on the map grid between units ``a`` and ``b``; ``periodic_shape``:
    the shape of a periodic map, whose distances go the shorter way round."""
    if periodic_shape is not None:
        return map_distance(map_coords, a, b, periodic_shape, True)
    return np.max(np.abs(map_coords[a] - map_coords[b]), axis=1)


def _periodic_shape(model: SigmaPiSOM) -> tuple[int, ...] | None:
    """The map's shape if it wraps around (for :func:`chebyshev`), else None."""
    return model.map_shape if model.config.map_periodic else None


def evaluate(
    model: SigmaPiSOM,
    n_test: int = 10_000,
    seed: int = EVAL_SEED,
    test: Batch | None = None,
    calibration: Batch | None = None,
) -> Metrics:
    """All metrics of ``model`` on ``n_test`` test z's (and as many calibration z's).

    Parameters
    ----------
    model : SigmaPiSOM
        A fitted model.
    n_test : int
        Test (and calibration) set size.
    seed : int
        Seed of the evaluation data; the default is fixed so that models are comparable.
    test, calibration : Batch, optional
        Precomputed evaluation data (e.g. reused across learning-curve checkpoints).
    """
    _validate.integer("n_test", n_test, 2)
    n_x, n_y = int(np.prod(model.x_shape)), int(np.prod(model.y_shape))
    _memory.check(  # two batches of codes, the responses (B, K) and their scores
        n_test * 8 * (4 * (n_x + n_y) + 3 * model.n_units + 16),
        f"evaluating on n_test={n_test} test pairs",
        "use a smaller n_test (the default is 10000)",
    )
    if test is None or calibration is None:
        calibration, test = evaluation_sets(model, n_test, seed)
    coords = model.map_coords
    scores = hard_scores(model, test.x0, test.y0)  # one pass: view 0's winners and fold score
    w0 = np.argmax(scores, axis=1)
    w1 = model.winner(test.x1, test.y1, hard=True)
    wc = model.winner(calibration.x0, calibration.y0, hard=True)

    spacing = grid_spacing(model.x_shape, model.config.periodic)
    m = winner_metrics(wc, calibration.z, w0, w1, test.z, coords, spacing, _periodic_shape(model))
    z_error = m["z_error"]
    starved, te, score = fold_indicators(model, test, w0, w1, scores)
    circ = None
    if model.sampler.relation.circular:  # angles: z error the shorter way round, seam
        circ = circular_metrics(
            wc,
            calibration.z,
            w0,
            test.z,
            coords,
            model.map_shape,
            model.config.map_periodic,
            spacing,
            starved_mask(w0, w1, model.n_units),
        )
        z_error = float(circ.pop("z_error"))
    return Metrics(
        m["view_consistency"],
        m["view_within_one"],
        z_error,
        m["order_r2"],
        m["usage"],
        int(test.z.shape[0]),
        fold_score=score,
        folded=score >= FOLD_THRESHOLD,
        starved_units=starved,
        topographic_error=te,
        circular=circ,
    )


def winner_metrics(
    wc: NDArray[np.int64],
    z_cal: NDArray[np.float64],
    w0: NDArray[np.int64],
    w1: NDArray[np.int64],
    z_test: NDArray[np.float64],
    coords: NDArray[np.float64],
    spacing: float | NDArray[np.float64],
    periodic_shape: tuple[int, ...] | None = None,
) -> dict[str, float]:
    """View consistency, within one, z error, order R^2 and usage from hard winners alone.

    ``wc``: winners of the calibration views (positions ``z_cal`` ``(N, d)``); ``w0``, ``w1``:
    of the two test views (positions ``z_test``); ``coords``: the map's unit coordinates
    ``(K, d_map)``; ``spacing``: input grid spacings per unit of z; ``periodic_shape``: the
    shape of a periodic map. The definitions of the module docstring, for :func:`evaluate`
    and for maps scored on data of their own (e.g. ``sigmapi.experiments.chain.run``).
    """
    table = z_decoder(wc, z_cal, coords)
    err = (table[w0] - z_test) * spacing
    beta = affine_fit(coords[wc], z_cal)
    sse = float(np.sum((_affine_predict(beta, coords[w0]) - z_test) ** 2))
    sst = float(np.sum((z_test - z_test.mean(axis=0)) ** 2))
    return {
        "view_consistency": float(np.mean(w0 == w1)),
        "view_within_one": float(np.mean(chebyshev(coords, w0, w1, periodic_shape) <= 1.0)),
        "z_error": float(np.sqrt(np.mean(np.sum(err**2, axis=1)))),
        "order_r2": 1.0 - sse / sst if sst > 0 else float("nan"),
        "usage": float(np.unique(w0).size / coords.shape[0]),
    }


def fold_indicators(
    model: SigmaPiSOM,
    test: Batch,
    w0: NDArray[np.int64] | None = None,
    w1: NDArray[np.int64] | None = None,
    scores: NDArray[np.float64] | None = None,
) -> tuple[int, float, float]:
    """``(starved units, topographic error, fold score)`` from view pairs alone (never z).

    ``w0``, ``w1``: the hard winners of the two views, and ``scores``: :func:`hard_scores` of
    view 0, when already known. Definitions in the module docstring.
    """
    if w0 is None:
        w0 = model.winner(test.x0, test.y0, hard=True)
    if w1 is None:
        w1 = model.winner(test.x1, test.y1, hard=True)
    starved = int(np.sum(starved_mask(w0, w1, model.n_units)))
    if scores is None:
        scores = hard_scores(model, test.x0, test.y0)
    top2 = np.argpartition(-scores, 1, axis=1)[:, :2]
    coords = model.map_coords
    te = float(np.mean(chebyshev(coords, top2[:, 0], top2[:, 1], _periodic_shape(model)) > 1.0))
    score = float(starved)
    apart = chebyshev(coords, w0, w1, _periodic_shape(model))
    if len(model.map_shape) >= 2:
        within = float(np.mean(apart <= 1.0))
        score = max(score, ((1.0 - within) + te) / TWIST_S)
    else:
        score = max(score, float(np.mean(apart >= FAR_UNITS)) / FAR_SHARE)
    return starved, te, score


def starved_mask(w0: NDArray[np.int64], w1: NDArray[np.int64], n_units: int) -> NDArray[np.bool_]:
    """The starved units ``(K,)``: those winning fewer than ``STARVED_SHARE`` of a uniform
    share of the views (both views of every test pair), for the fold score and the seam."""
    wins = np.bincount(np.concatenate([w0, w1]), minlength=n_units)
    return np.asarray(wins < STARVED_SHARE * wins.sum() / n_units)


def hard_scores(
    model: SigmaPiSOM, x: NDArray[np.float64], y: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Per-unit scores ``(B, K)`` whose row-wise argmax is the hard winner
    (``model.winner(x, y, hard=True)``, the same units, ties to the lowest index): the scores
    of the model's rule at sigma -> 0 (the response ``h`` for the soft rules, ``2 h - |w_k|^2``
    under ``min_distance``) on the model's response."""
    rule, c = model.winner_rule_.hard, model.config
    norms = model.unit_sqnorms() if rule.needs_norms else None
    at = Scoring(c.geometry, model.sigma_, norms)
    return rule.scores(model.respond(x, y), at)


def evaluation_sets(model: SigmaPiSOM, n: int, seed: int = EVAL_SEED) -> tuple[Batch, Batch]:
    """(calibration, test) batches of ``n`` two-view samples each, from ``seed``."""
    cal_rng, test_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
    sampler = model.sampler
    return sampler.sample(n, cal_rng), sampler.sample(n, test_rng)
