"""``sigmapi compare``: the Sigma-Pi map beside the methods a user would pick instead.

Every method is trained on the same two-view data (``train_pairs`` view pairs of the preset's
task per seed, the recording a user would make) and scored on the same evaluation sets as
:func:`sigmapi.evaluate` (fixed seed ``EVAL_SEED``), by one definition for all:

- every method ends in a linear read-out of z from its output. For a map the output is the
  winning unit (one-hot) and the read-out the mean z of each unit's labelled wins (the
  per-unit table of :func:`sigmapi.metrics.z_decoder`, least squares on the one-hot code);
  for the gain-field and RBM baselines it is a ridge regression on the middle layer;
- **z error**: RMSE of the read-out of view 0 on the test set, in input grid spacings, given
  ``L`` labelled samples (the first ``L`` of the calibration set), for each ``L`` of
  ``labels``; the table reports it at ``labels_used`` = all of them (the Sigma-Pi map's
  figure is then :func:`sigmapi.evaluate`'s ``z_error``);
- **view consistency**: the fraction of test z's whose two views land on the same *place*:
  the same winning unit for a map; for a read-out, the same cell when the read-out z is
  binned into as many cells per axis as the map has units (what a map of that size
  resolves);
- **same unit** (no label used): the same winner for a map; for a read-out method the same
  most active middle-layer unit (gain-field unit, RBM hidden unit);
- **quantisation floor**: the z error of the best decoder that sees only which of the map's
  units won (z cut into as many equal cells as the map has units); a continuous read-out can
  go below it;
- **labels needed**: the fewest ``L`` whose z error is within 10 % of the method's error with
  all labels (what its read-out needs); **labels to match**: the fewest ``L`` whose z error
  is within 10 % of the Sigma-Pi map's with all labels (None: not within ``labels``).

Values over seeds are medians; every seed's value is kept.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _validate
from sigmapi.baselines.kohonen import KohonenSOM, MiniSomMap
from sigmapi.baselines.readout import GainFieldNetwork, RBMFeatures, fit_readout
from sigmapi.config import SOMConfig, apply_overrides, load_preset
from sigmapi.errors import ConfigError
from sigmapi.metrics import evaluation_sets, grid_spacing, z_decoder
from sigmapi.som import SigmaPiSOM
from sigmapi.tasks import Batch

__all__ = [
    "LABELS",
    "METHODS",
    "QUICK",
    "CompareConfig",
    "CompareResult",
    "MethodScore",
    "run_compare",
]

Array = NDArray[np.float64]
Views = tuple[Array, Array, Array, Array]

LABELS = (10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10_000)
"""Numbers of labelled samples the read-outs are scored with (those <= ``n_test``)."""

METHODS: dict[str, str] = {
    "sigma-pi": "Sigma-Pi map (sigmapi's ordering procedure, crossview)",
    "sigma-pi same view": "Sigma-Pi map, learns the view it saw (ablation)",
    "sigma-pi ordering none": "Sigma-Pi map, the paper's random start (ordering none)",
    "kohonen": "first-order SOM on [x; y] (sigmapi's)",
    "kohonen two-view": "first-order SOM, the two-view rule",
    "minisom": "MiniSom on [x; y] (reference)",
    "basis functions": "gain-field products + linear read-out",
    "rbm": "RBM on [x; y] + linear read-out",
}
"""Method names (the JSON's ``name``) and what each is."""

SIGMA_PI_CHANGES: dict[str, dict[str, Any]] = {
    "sigma-pi": {"ordering": "crossview"},
    "sigma-pi same view": {"ordering": "crossview", "same_view": True},
    "sigma-pi ordering none": {"ordering": "none"},
}
"""The Sigma-Pi map (sigmapi's ordering procedure, whatever the preset says) and its two
ablations: learning from the view it saw, and the paper's random start."""

MATCH_SHARE = 1.1
"""labels needed: the z error within this factor of the error with all labels."""


@dataclass(frozen=True)
class CompareConfig:
    """What ``sigmapi compare`` trains and scores."""

    preset: str = "paper-1d"
    """The task and the Sigma-Pi map's settings (a preset name; ``sigmapi presets``)."""
    overrides: tuple[str, ...] = ()
    """``key=value`` changes to the preset (as ``--set``), e.g. ``("iterations=50000",)``."""
    seeds: tuple[int, ...] = (0, 1, 2, 3, 4)
    """Seeds: each draws its own training data and trains every method on it."""
    train_pairs: int = 20_000
    """View pairs recorded per seed (every method trains on these rows)."""
    som_iterations: int = 100_000
    """Online updates of the first-order maps (sigmapi's and MiniSom)."""
    rbm_epochs: int = 10
    """Training passes of the RBM over the data."""
    n_test: int = 10_000
    """Test z's (and calibration z's, the pool the labels are drawn from)."""
    methods: tuple[str, ...] = tuple(METHODS)
    """Methods to run, a subset of :data:`METHODS`; "sigma-pi" always runs."""

    def __post_init__(self) -> None:
        seeds = tuple(_validate.integer("seeds", s, 0) for s in self.seeds)
        if not seeds:
            raise ConfigError("seeds must name at least one seed, got none; e.g. 0 1 2 3 4")
        object.__setattr__(self, "seeds", seeds)
        _validate.integer("train_pairs", self.train_pairs, 100, fix="e.g. 20000")
        _validate.integer("som_iterations", self.som_iterations, 1, fix="e.g. 100000")
        _validate.integer("rbm_epochs", self.rbm_epochs, 1, fix="e.g. 10")
        _validate.integer("n_test", self.n_test, LABELS[0], fix="e.g. 10000")
        for m in self.methods:
            _validate.choice("methods", m, tuple(METHODS))
        object.__setattr__(
            self, "methods", tuple(m for m in METHODS if m in self.methods or m == "sigma-pi")
        )
        object.__setattr__(self, "overrides", tuple(self.overrides))
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def labels(self) -> tuple[int, ...]:
        return tuple(n for n in LABELS if n <= self.n_test)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with the overrides: the task and the Sigma-Pi map's settings."""
        return apply_overrides(load_preset(self.preset), list(self.overrides))


QUICK = CompareConfig(seeds=(0, 1), train_pairs=10_000, som_iterations=20_000, rbm_epochs=5,
                      n_test=5000)  # fmt: skip
"""``--quick``: two seeds, less data, shorter baselines (about a minute)."""


@dataclass
class MethodScore:
    """One method's scores over seeds (lists in the order of the seeds)."""

    name: str
    view_consistency: list[float] = field(default_factory=list)
    unit_consistency: list[float] = field(default_factory=list)
    z_error_by_labels: list[dict[int, float]] = field(default_factory=list)
    seconds: list[float] = field(default_factory=list)

    def median_curve(self) -> dict[int, float]:
        """Median z error over seeds per number of labels."""
        keys = self.z_error_by_labels[0]
        return {n: float(np.median([c[n] for c in self.z_error_by_labels])) for n in keys}

    @property
    def z_error(self) -> float:
        curve = self.median_curve()
        return curve[max(curve)]

    def labels_needed(self) -> int:
        curve = self.median_curve()
        return min(n for n, e in curve.items() if e <= MATCH_SHARE * self.z_error)

    def labels_to_match(self, target: float) -> int | None:
        hits = [n for n, e in self.median_curve().items() if e <= MATCH_SHARE * target]
        return min(hits) if hits else None


@dataclass
class CompareResult:
    """Scores of every method (:class:`MethodScore`) and the run's settings."""

    config: CompareConfig
    scores: dict[str, MethodScore]
    seconds: float = 0.0

    @property
    def reference(self) -> MethodScore:
        return self.scores["sigma-pi"]

    @property
    def floor(self) -> float:
        """z error of the best decoder that sees only the winner of a map of this size.

        z uniform over the relation's range, cut into ``map_shape`` equal cells per axis: the
        error of the cell's centre is ``cell width / sqrt(12)`` per axis (in grid spacings).
        """
        som_cfg = self.config.som_config
        lo, hi = SigmaPiSOM(som_cfg).sampler.relation.z_range
        spacing = grid_spacing(som_cfg.x_shape, som_cfg.periodic)
        width = (hi - lo) / np.asarray(som_cfg.map_shape, dtype=np.float64)
        return float(np.sqrt(np.sum((width * spacing) ** 2 / 12.0)))

    def to_dict(self) -> dict[str, Any]:
        """``{"methods": [{name, view_consistency, z_error, labels_used, ...}], ...}``."""
        target = self.reference.z_error
        labels_used = max(self.config.labels)
        methods = []
        for name, s in self.scores.items():
            curve = s.median_curve()
            methods.append({
                "name": name,
                "description": METHODS[name],
                "view_consistency": float(np.median(s.view_consistency)),
                "unit_consistency": float(np.median(s.unit_consistency)),
                "z_error": s.z_error,
                "labels_used": labels_used,
                "labels_needed": s.labels_needed(),
                "labels_to_match_sigma_pi": s.labels_to_match(target),
                "z_error_by_labels": {str(n): e for n, e in curve.items()},
                "per_seed": {
                    "view_consistency": s.view_consistency,
                    "unit_consistency": s.unit_consistency,
                    "z_error": [c[labels_used] for c in s.z_error_by_labels],
                    "seconds": s.seconds,
                },
            })  # fmt: skip
        cfg = dataclasses.asdict(self.config)
        return {
            "methods": methods,
            "config": {**cfg, "seeds": list(self.config.seeds), "labels": list(self.config.labels)},
            "z_error_unit": "input grid spacings",
            "quantisation_floor": self.floor,
            "seconds": self.seconds,
        }

    def table(self) -> str:
        """The comparison as a plain-text table (medians over seeds)."""
        d = self.to_dict()
        rows = [
            f"{'method':24s} {'same place':>10s} {'same unit':>9s} {'z error':>8s} "
            f"{'labels':>7s} {'needed':>7s} {'to match':>8s}"
        ]
        for m in d["methods"]:
            match = m["labels_to_match_sigma_pi"]
            rows.append(
                f"{m['name']:24s} {m['view_consistency']:10.3f} {m['unit_consistency']:9.3f} "
                f"{m['z_error']:8.3f} {m['labels_used']:7d} {m['labels_needed']:7d} "
                f"{'-' if match is None else str(match):>8s}"
            )
        rows.append(
            f"z error in grid spacings; a map's winner alone cannot beat {self.floor:.3f} "
            f"(z cut into {'x'.join(map(str, self.config.som_config.map_shape))} cells)"
        )
        return "\n".join(rows)

    def caption(self) -> str:
        """A caption computed from the result."""
        cfg, ref = self.config, self.reference
        n = len(cfg.seeds)
        parts = [
            f"{cfg.preset} task, {cfg.train_pairs:,} recorded view pairs per seed, median of {n} "
            f"seed{'s' * (n > 1)}. The Sigma-Pi map puts both views of one z on the same unit "
            f"in {np.median(ref.view_consistency):.2f} of test cases, z error "
            f"{ref.z_error:.2f} grid spacings (a winner alone cannot beat {self.floor:.2f}) with "
            f"its units named by {ref.labels_needed()} labels (within 10 % of its error with "
            "all of them)."
        ]
        for name, s in self.scores.items():
            if name == "sigma-pi":
                continue
            match = s.labels_to_match(ref.z_error)
            reach = (
                f"comes within 10 % of the map's z error with {match:,} labels"
                if match is not None
                else f"not within 10 % of the map's z error with {max(cfg.labels):,} labels"
            )
            parts.append(
                f"{name}: same place {np.median(s.view_consistency):.2f}, z error "
                f"{s.z_error:.2f}, {reach}."
            )
        return " ".join(parts)


# ------------------------------------------------------------------ scoring


def _bins(z: Array, lo: float, hi: float, shape: tuple[int, ...]) -> NDArray[np.int64]:
    """Flat cell of each read-out ``z`` ``(B, d)`` on a grid of ``shape`` cells over [lo, hi]."""
    n = np.asarray(shape)
    cell = np.clip(np.floor((z - lo) / (hi - lo) * n), 0, n - 1).astype(np.int64)
    return np.asarray(np.ravel_multi_index(tuple(cell.T), shape), dtype=np.int64)


def score_units(
    unit: Callable[[Array, Array], NDArray[np.int64]],
    coords: Array,
    cal: Batch,
    test: Batch,
    labels: Sequence[int],
    spacing: Array,
) -> tuple[float, float, dict[int, float]]:
    """View consistency and z error per number of labels of a map whose output is a unit.

    Returns ``(view consistency, the same again (a map's unit needs no label), curve)``.
    """
    w0, w1, wc = unit(test.x0, test.y0), unit(test.x1, test.y1), unit(cal.x0, cal.y0)
    curve = {}
    for n in labels:
        table = z_decoder(wc[:n], cal.z[:n], coords)
        curve[n] = _rmse(table[w0] - test.z, spacing)
    same = float(np.mean(w0 == w1))
    return same, same, curve


def score_readout(
    features: Callable[[Array, Array], Array],
    cal: Batch,
    test: Batch,
    labels: Sequence[int],
    spacing: Array,
    cells: tuple[tuple[float, float], tuple[int, ...]],
) -> tuple[float, float, dict[int, float]]:
    """View consistency and z error per number of labels of a read-out.

    Returns ``(same cell of the binned read-out, same most active middle-layer unit (no
    label used), curve)``.
    """
    fc, f0, f1 = features(cal.x0, cal.y0), features(test.x0, test.y0), features(test.x1, test.y1)
    curve = {}
    for n in labels:
        readout = fit_readout(fc[:n], cal.z[:n])
        curve[n] = _rmse(readout(f0) - test.z, spacing)
    (lo, hi), shape = cells
    b0, b1 = _bins(readout(f0), lo, hi, shape), _bins(readout(f1), lo, hi, shape)
    unit = float(np.mean(np.argmax(f0, axis=1) == np.argmax(f1, axis=1)))
    return float(np.mean(b0 == b1)), unit, curve


def _rmse(err: Array, spacing: Array) -> float:
    return float(np.sqrt(np.mean(np.sum((err * spacing) ** 2, axis=1))))


# ------------------------------------------------------------------ the run


def _train(name: str, cfg: CompareConfig, som_cfg: SOMConfig, views: Views, seed: int) -> Any:
    """Train method ``name`` on ``views``; returns the trained object."""
    if name.startswith("sigma-pi"):
        return SigmaPiSOM(som_cfg, seed=seed, **SIGMA_PI_CHANGES[name]).fit(views)
    shape, its = som_cfg.map_shape, cfg.som_iterations
    if name == "kohonen":
        return KohonenSOM(shape, its, seed=seed).fit(views)
    if name == "kohonen two-view":
        return KohonenSOM(shape, its, two_view=True, seed=seed).fit(views)
    if name == "minisom":
        return MiniSomMap(shape, its, seed=seed).fit(views)
    if name == "basis functions":
        return GainFieldNetwork().fit(views)
    n_hidden = int(np.prod(som_cfg.x_shape) * np.prod(som_cfg.y_shape))
    return RBMFeatures(n_hidden, cfg.rbm_epochs, seed=seed).fit(views)


def run_compare(cfg: CompareConfig, progress: Callable[[str], None] | None = None) -> CompareResult:
    """Train and score every method of ``cfg`` on every seed; see the module docstring."""
    start = time.perf_counter()
    som_cfg = cfg.som_config
    base = SigmaPiSOM(som_cfg)
    cal, test = evaluation_sets(base, cfg.n_test)
    spacing = grid_spacing(som_cfg.x_shape, som_cfg.periodic)
    cells = (base.sampler.relation.z_range, som_cfg.map_shape)
    scores = {name: MethodScore(name) for name in cfg.methods}
    for seed in cfg.seeds:
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(13,)))
        b = base.sampler.sample(cfg.train_pairs, rng)
        views = (b.x0, b.y0, b.x1, b.y1)
        for name in cfg.methods:
            if progress is not None:
                progress(f"seed {seed}: {name}")
            t0 = time.perf_counter()
            model = _train(name, cfg, som_cfg, views, seed)
            if hasattr(model, "winner"):
                if isinstance(model, SigmaPiSOM):
                    unit = _hard_winner(model)
                else:
                    unit = model.winner
                vc, uc, curve = score_units(unit, base.map_coords, cal, test, cfg.labels, spacing)
            else:
                vc, uc, curve = score_readout(model.features, cal, test, cfg.labels, spacing, cells)
            s = scores[name]
            s.view_consistency.append(vc)
            s.unit_consistency.append(uc)
            s.z_error_by_labels.append(curve)
            s.seconds.append(time.perf_counter() - t0)
    return CompareResult(cfg, scores, time.perf_counter() - start)


def _hard_winner(model: SigmaPiSOM) -> Callable[[Array, Array], NDArray[np.int64]]:
    return lambda x, y: model.winner(x, y, hard=True)
