"""``sigmapi compare``: the Sigma-Pi map beside the methods a user would pick instead.

Every method is trained on the same two-view data (``train_pairs`` view pairs of the preset's
task per seed, the recording a user would make) and scored on the same evaluation sets as
:func:`sigmapi.evaluate` (fixed seed ``EVAL_SEED``), by one definition for all: a linear
read-out of z from the method's output, given the first ``L`` labels of the calibration set
for each ``L`` of ``labels`` (:mod:`sigmapi.baselines.scoring`). The scores (**z error**,
**view consistency** or same place, **same unit**, the **quantisation floor**, **labels
needed** and **labels to match**) are defined in docs/algorithm.md, "Your own data and the
baselines". Values over seeds are medians; every seed's value is kept.

Read top to bottom: the settings (:class:`CompareConfig`), the result (:class:`CompareResult`,
its figure drawn by :mod:`.figures`) and the run (:class:`Compare`, one job per seed;
:func:`run_compare` from Python).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.util
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory, _validate
from sigmapi.baselines.kohonen import KohonenSOM, MiniSomMap
from sigmapi.baselines.readout import GainFieldNetwork, RBMFeatures
from sigmapi.baselines.scoring import score_readout, score_units
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, install_hint
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import KEY_VALUES, Run, check_seeds, register
from sigmapi.experiments.kit.jobs import SeedJob, SeedRuns, Tick
from sigmapi.experiments.kit.maps import MapSpec
from sigmapi.experiments.kit.results import Result, columns, render
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.metrics import evaluation_sets, grid_spacing
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress
from sigmapi.tasks import Batch

# -- the settings ----------------------------------------------------------------------------------


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


@dataclass(frozen=True)
class CompareConfig:
    """What ``sigmapi compare`` trains and scores."""

    preset: str = "paper-1d"
    """The task and the Sigma-Pi map's settings (a preset name; ``sigmapi presets``)."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` changes to the preset, e.g. ``iterations=50000`` (one per change)."""
    train_pairs: int = field(
        default=20_000, metadata=_validate.bounded("int", 100, 10_000_000, fix="e.g. 20000")
    )
    """View pairs recorded per seed (every method trains on these rows)."""
    baseline_iterations: int = field(
        default=100_000, metadata=_validate.bounded("int", 1, 100_000_000, fix="e.g. 100000")
    )
    """Online updates of the first-order maps (sigmapi's and MiniSom)."""
    rbm_epochs: int = field(default=10, metadata=_validate.bounded("int", 1, 10_000, fix="e.g. 10"))
    """Training passes of the RBM over the data."""
    n_test: int = field(
        default=10_000, metadata=_validate.bounded("int", LABELS[0], 1_000_000, fix="e.g. 10000")
    )
    """Test z's (and calibration z's, the pool the labels are drawn from)."""
    methods: tuple[str, ...] = tuple(METHODS)
    """Methods to run (default: all of them); "sigma-pi" always runs."""

    def __post_init__(self) -> None:
        _validate.check_fields(self)
        for m in self.methods:
            _validate.choice("methods", m, tuple(METHODS))
        chosen = {*self.methods, "sigma-pi"}
        object.__setattr__(self, "methods", tuple(m for m in METHODS if m in chosen))
        object.__setattr__(self, "overrides", tuple(self.overrides))
        self.som_config  # noqa: B018 (an unknown preset or a bad override fails here, not later)

    @property
    def labels(self) -> tuple[int, ...]:
        return tuple(n for n in LABELS if n <= self.n_test)

    @property
    def som_config(self) -> SOMConfig:
        """The preset with the overrides: the task and the Sigma-Pi map's settings."""
        return MapSpec(self.preset, self.overrides).config()


QUICK = CompareConfig(train_pairs=10_000, baseline_iterations=20_000, rbm_epochs=5, n_test=5000)
"""The quick comparison: less data, shorter baselines (with :data:`QUICK_SEEDS`)."""


SEEDS = (0, 1, 2, 3, 4)
"""The default seeds: each draws its own training data and trains every method on it."""


QUICK_SEEDS = (0, 1)
"""The seeds of the quick comparison."""


# -- the result: its JSON form, table and figure ---------------------------------------------------


MATCH_SHARE = 1.1
"""labels needed: the z error within this factor of the error with all labels."""

COLUMNS = columns(
    "name:24s view_consistency:10.3f unit_consistency:9.3f z_error:8.3f labels_used:7d",
    "labels_needed:7d labels_to_match_sigma_pi:>8",
    view_consistency="same place",
    unit_consistency="same unit",
    labels_used="labels",
    labels_needed="needed",
    labels_to_match_sigma_pi="to match",
)
"""The table's columns: one row per method (medians over seeds)."""


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
        return min(n for n, e in self.median_curve().items() if e <= MATCH_SHARE * self.z_error)

    def labels_to_match(self, target: float) -> int | None:
        hits = [n for n, e in self.median_curve().items() if e <= MATCH_SHARE * target]
        return min(hits) if hits else None


@dataclass
class CompareResult(Result):
    """Scores of every method (:class:`MethodScore`) and the run's settings. A result read
    back from its JSON form (:meth:`from_dict`) holds no scores per seed and number of
    labels: its summaries are ``written``, as the file has them."""

    config: CompareConfig
    scores: dict[str, MethodScore] = field(default_factory=dict)
    seconds: float = 0.0
    seeds: tuple[int, ...] = SEEDS
    """The seeds, in the order of the scores' lists."""

    KEYS = (
        "methods",
        "config: config_json",
        "z_error_unit",
        "quantisation_floor: floor",
        "seconds",
    )
    """The JSON form: ``methods`` (name, view consistency, z error, labels used, ...), the
    config with its seeds and labels, the z error's unit and its quantisation floor."""
    COMPUTED = ("methods", "z_error_unit", "quantisation_floor")
    SEEDS_IN_CONFIG = True
    FIGURE = "compare.png"
    DRAWN_BY = "sigmapi.experiments.compare.figures:compare_figure"
    z_error_unit = "input grid spacings"

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

    def config_json(self) -> dict[str, object]:
        """The config's fields, the seeds after its preset and overrides, and its labels."""
        cfg = dataclasses.asdict(self.config)
        head = {"preset": cfg.pop("preset"), "overrides": cfg.pop("overrides")}
        return {**head, "seeds": list(self.seeds), **cfg, "labels": list(self.config.labels)}

    def methods(self) -> list[dict[str, object]]:
        """Per method its medians over seeds, the labels it used and needed (and to match
        the Sigma-Pi map's z error), its z error by labels and its values per seed."""
        target = self.reference.z_error
        labels_used = max(self.config.labels)
        methods = []
        for name, s in self.scores.items():
            curve = s.median_curve()
            entry = {
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
            }
            methods.append(entry)
        return methods

    def table(self) -> str:
        """The comparison as a plain-text table (medians over seeds)."""
        shape = "x".join(map(str, self.config.som_config.map_shape))
        floor = f"a map's winner alone cannot beat {self.floor:.3f} (z cut into {shape} cells)"
        rows = render(COLUMNS, self.to_dict()["methods"])
        return "\n".join([*rows, f"z error in grid spacings; {floor}"])

    def caption(self) -> str:
        """A caption computed from the result's JSON form (so that a result read back from
        its file draws its figure with the same caption)."""
        data = self.to_dict()
        cfg, methods = self.config, {m["name"]: m for m in data["methods"]}
        ref = methods["sigma-pi"]
        n = len(self.seeds)
        parts = [
            f"{cfg.preset} task, {cfg.train_pairs:,} recorded view pairs per seed, median of {n} "
            f"seed{'s' * (n > 1)}. The Sigma-Pi map puts both views of one z on the same unit "
            f"in {ref['view_consistency']:.2f} of test cases, z error "
            f"{ref['z_error']:.2f} grid spacings (a winner alone cannot beat "
            f"{data['quantisation_floor']:.2f}) with its units named by {ref['labels_needed']} "
            "labels (within 10 % of its error with all of them)."
        ]
        for name, m in methods.items():
            if name == "sigma-pi":
                continue
            match = m["labels_to_match_sigma_pi"]
            n = max(cfg.labels) if match is None else match
            within = "not within" if match is None else "comes within"
            reach = f"{within} 10 % of the map's z error with {n:,} labels"
            vc, z = m["view_consistency"], m["z_error"]
            parts.append(f"{name}: same place {vc:.2f}, z error {z:.2f}, {reach}.")
        return " ".join(parts)


Array = NDArray[np.float64]
Views = tuple[Array, Array, Array, Array]


SIGMA_PI_CHANGES: dict[str, dict[str, object]] = {
    "sigma-pi": {"ordering": "crossview"},
    "sigma-pi same view": {"ordering": "crossview", "same_view": True},
    "sigma-pi ordering none": {"ordering": "none"},
}
"""The Sigma-Pi map (sigmapi's ordering procedure, whatever the preset says) and its two
ablations: learning from the view it saw, and the paper's random start."""


# -- the run: every method per seed, the experiment ------------------------------------------------


NEEDS = {"minisom": "minisom", "basis functions": "sklearn", "rbm": "sklearn"}
"""Methods that need an optional module (the extra ``sigmapi[baselines]``)."""

PACKAGES = {"minisom": "minisom", "sklearn": "scikit-learn"}
"""The package that installs each optional module."""


Method = SigmaPiSOM | KohonenSOM | GainFieldNetwork | RBMFeatures
"""A trained method: a map (its winner) or a read-out method (its middle layer)."""


def _train(name: str, cfg: CompareConfig, som_cfg: SOMConfig, views: Views, seed: int) -> Method:
    """Train method ``name`` on ``views``; returns the trained object."""
    if name.startswith("sigma-pi"):
        return SigmaPiSOM(som_cfg, seed=seed, **SIGMA_PI_CHANGES[name]).fit(views)
    shape, its = som_cfg.map_shape, cfg.baseline_iterations
    if name.startswith("kohonen"):  # the two-view rule, or each view on its own
        return KohonenSOM(shape, its, two_view=name == "kohonen two-view", seed=seed).fit(views)
    if name == "minisom":
        return MiniSomMap(shape, its, seed=seed).fit(views)
    if name == "basis functions":
        return GainFieldNetwork().fit(views)
    n_hidden = int(np.prod(som_cfg.x_shape) * np.prod(som_cfg.y_shape))
    return RBMFeatures(n_hidden, cfg.rbm_epochs, seed=seed).fit(views)


Scores = dict[str, tuple[float, float, dict[int, float], float]]
"""Per method: view consistency, unit consistency, z error per labels, seconds."""


PLAN = SeedPlan({"data": 13})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): the recorded
views, apart from the streams a model of the same seed draws."""


def installed() -> set[str]:
    """The optional modules of the baselines that are installed here."""
    return {name for name in PACKAGES if importlib.util.find_spec(name)}


def run_compare(
    cfg: CompareConfig,
    progress: Progress | None = None,
    *,
    seeds: Sequence[int] = SEEDS,
    executor: Executor | None = None,
) -> CompareResult:
    """Train and score every method of ``cfg`` on every seed; see the module docstring.

    Each seed (its recording, every method trained on it) is one job of ``executor`` (None:
    one after another in this process); ``progress`` writes a line per method, or per seed
    where the seeds run in parallel.
    """
    return COMPARE.execute(cfg, Run(check_seeds(seeds), executor=executor, progress=progress))


class Compare(SeedRuns[CompareConfig]):
    """Train the Sigma-Pi map, its ablations, first-order SOMs (sigmapi's and MiniSom), a
    basis-function network and an RBM + read-out on the same two-view data and score them by
    the same metrics."""

    name = "compare"
    summary = "the Sigma-Pi map beside the baselines a user would pick instead"
    config_type = CompareConfig
    quick = QUICK
    seeds = SEEDS
    quick_seeds = QUICK_SEEDS
    quick_time = "about 1 min on two cores"
    extra = "baselines"
    default_out = "compare"
    writes = CompareResult.figure_names()
    unit = "method"

    def check(self, config: CompareConfig) -> int:
        """Refuse, before anything trains, methods whose optional module is not installed
        (:func:`installed`) and data that does not fit; one job's memory."""
        missing = sorted({NEEDS[m] for m in config.methods if m in NEEDS} - installed())
        if missing:
            names = " and ".join(PACKAGES[m] for m in missing)
            raise ConfigError(
                f"the baselines need {names} (not installed here); "
                f"{install_hint('baselines')}, or leave those methods out"
            )
        som, pairs, n_test = SigmaPiSOM(config.som_config), config.train_pairs, config.n_test
        width = 8 * (int(np.prod(som.x_shape)) + int(np.prod(som.y_shape)))  # a view pair
        _memory.check_count("train_pairs", pairs, 2 * width, "e.g. --train-pairs 20000")
        _memory.check_count("n_test", n_test, 4 * width + 32 * som.n_units, "e.g. --n-test 10000")
        return job_memory(config.som_config, n_test)

    def prepare(self, config: CompareConfig, progress: object) -> tuple[Batch, Batch]:
        """The calibration and test sets every seed is scored on."""
        return evaluation_sets(SigmaPiSOM(config.som_config), config.n_test)

    def steps(self, job: SeedJob) -> int:
        return len(job.config.methods)

    def describe(self, key: str, value: Scores) -> str:
        return f"seed {key} ({sum(v[3] for v in value.values()):.0f} s)"

    def seed_run(self, job: SeedJob, tick: Tick | None) -> Scores:
        """Train and score every method of ``job.config`` on seed ``job.seed``'s recording."""
        cfg, seed, (cal, test) = job.config, job.seed, job.shared
        som_cfg = cfg.som_config
        base = SigmaPiSOM(som_cfg)
        spacing = grid_spacing(som_cfg.x_shape, som_cfg.periodic)
        cells = (base.sampler.relation.z_range, som_cfg.map_shape)
        b = base.sampler.sample(cfg.train_pairs, PLAN.rng(seed, "data"))
        views = (b.x0, b.y0, b.x1, b.y1)
        out: Scores = {}
        for name in cfg.methods:
            if tick is not None:
                tick(0, name)
            t0 = time.perf_counter()
            model = _train(name, cfg, som_cfg, views, seed)
            if isinstance(model, (GainFieldNetwork, RBMFeatures)):
                vc, uc, curve = score_readout(model.features, cal, test, cfg.labels, spacing, cells)
            else:
                unit = (
                    functools.partial(model.winner, hard=True)
                    if isinstance(model, SigmaPiSOM)
                    else model.winner
                )
                vc, uc, curve = score_units(unit, base.map_coords, cal, test, cfg.labels, spacing)
            out[name] = (vc, uc, curve, time.perf_counter() - t0)
            if tick is not None:
                tick(1, name)
        return out

    def collect(
        self, config: CompareConfig, seeds: tuple[int, ...], values: list[Any]
    ) -> CompareResult:
        """Each method's scores over the seeds, in their order."""
        scores = {}
        for name in config.methods:
            vc, uc, curves, seconds = zip(*(per_seed[name] for per_seed in values), strict=True)
            scores[name] = MethodScore(name, list(vc), list(uc), list(curves), list(seconds))
        return CompareResult(config, scores, 0.0, seeds)


COMPARE = Compare()
register(COMPARE)
