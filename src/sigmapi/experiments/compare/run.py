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

Values over seeds are medians; every seed's value is kept. Each seed is one job of the
executor (:func:`compare_seed`); the experiment ``compare`` (:class:`Compare`) is
:func:`run_compare` on the command line.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.util
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sigmapi import _memory
from sigmapi.baselines.kohonen import KohonenSOM, MiniSomMap
from sigmapi.baselines.readout import GainFieldNetwork, RBMFeatures
from sigmapi.baselines.scoring import score_readout, score_units
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, install_hint
from sigmapi.executor import Executor, job_memory
from sigmapi.experiments.base import Experiment, check_seeds, register, run_all
from sigmapi.experiments.compare.config import (
    LABELS,
    METHODS,
    QUICK,
    QUICK_SEEDS,
    SEEDS,
    CompareConfig,
)
from sigmapi.experiments.compare.result import (
    FIGURE,
    CompareResult,
    MethodScore,
)
from sigmapi.experiments.kit.jobs import Tick, counted
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.metrics import evaluation_sets, grid_spacing
from sigmapi.model.som import SigmaPiSOM
from sigmapi.progress import Progress
from sigmapi.tasks import Batch

__all__ = [
    "COMPARE",
    "LABELS",
    "METHODS",
    "QUICK",
    "QUICK_SEEDS",
    "SEEDS",
    "Compare",
    "CompareConfig",
    "CompareJob",
    "CompareResult",
    "MethodScore",
    "compare_seed",
    "run_compare",
]

Array = NDArray[np.float64]
Views = tuple[Array, Array, Array, Array]


SIGMA_PI_CHANGES: dict[str, dict[str, Any]] = {
    "sigma-pi": {"ordering": "crossview"},
    "sigma-pi same view": {"ordering": "crossview", "same_view": True},
    "sigma-pi ordering none": {"ordering": "none"},
}
"""The Sigma-Pi map (sigmapi's ordering procedure, whatever the preset says) and its two
ablations: learning from the view it saw, and the paper's random start."""


NEEDS = {"minisom": "minisom", "basis functions": "sklearn", "rbm": "sklearn"}
"""Methods that need an optional module (the extra ``sigmapi[baselines]``)."""

PACKAGES = {"minisom": "minisom", "sklearn": "scikit-learn"}
"""The package that installs each optional module."""


# ------------------------------------------------------------------ the run


def _train(name: str, cfg: CompareConfig, som_cfg: SOMConfig, views: Views, seed: int) -> Any:
    """Train method ``name`` on ``views``; returns the trained object."""
    if name.startswith("sigma-pi"):
        return SigmaPiSOM(som_cfg, seed=seed, **SIGMA_PI_CHANGES[name]).fit(views)
    shape, its = som_cfg.map_shape, cfg.baseline_iterations
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


@dataclass(frozen=True)
class CompareJob:
    """One seed of the comparison (a job of the executor): every method on that seed's data."""

    seed: int
    cfg: CompareConfig
    cal: Batch
    test: Batch
    progress: bool = False
    """Write a line per method on stderr (when the jobs run one by one in this process)."""


Scores = dict[str, tuple[float, float, dict[int, float], float]]
"""Per method: view consistency, unit consistency, z error per labels, seconds."""


PLAN = SeedPlan({"data": 13})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): the recorded
views, apart from the streams a model of the same seed draws."""


def compare_seed(job: CompareJob) -> Scores:
    """Train and score every method of ``job.cfg`` on seed ``job.seed``'s recording (with
    ``job.progress``, a bar or lines of its methods)."""
    work = functools.partial(_compare_seed, job)
    show = Progress() if job.progress else None
    return counted(show, len(job.cfg.methods), f"compare seed {job.seed}", work, "method")


def _compare_seed(job: CompareJob, tick: Tick | None) -> Scores:
    cfg, seed, cal, test = job.cfg, job.seed, job.cal, job.test
    som_cfg = cfg.som_config
    base = SigmaPiSOM(som_cfg)
    spacing = grid_spacing(som_cfg.x_shape, som_cfg.periodic)
    cells = (base.sampler.relation.z_range, som_cfg.map_shape)
    rng = PLAN.rng(seed, "data")
    b = base.sampler.sample(cfg.train_pairs, rng)
    views = (b.x0, b.y0, b.x1, b.y1)
    out: Scores = {}
    for name in cfg.methods:
        if tick is not None:
            tick(0, name)
        t0 = time.perf_counter()
        model = _train(name, cfg, som_cfg, views, seed)
        if hasattr(model, "winner"):
            unit = _hard_winner(model) if isinstance(model, SigmaPiSOM) else model.winner
            vc, uc, curve = score_units(unit, base.map_coords, cal, test, cfg.labels, spacing)
        else:
            vc, uc, curve = score_readout(model.features, cal, test, cfg.labels, spacing, cells)
        out[name] = (vc, uc, curve, time.perf_counter() - t0)
        if tick is not None:
            tick(1, name)
    return out


def check_installed(methods: Sequence[str]) -> None:
    """Refuse, before anything trains, methods whose optional module is not installed."""
    missing = sorted({NEEDS[m] for m in methods if m in NEEDS} - installed())
    if missing:
        names = " and ".join(PACKAGES[m] for m in missing)
        raise ConfigError(
            f"the baselines need {names} (not installed here); "
            f"{install_hint('baselines')}, or leave those methods out"
        )


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
    start = time.perf_counter()
    seeds = check_seeds(seeds)
    check_installed(cfg.methods)
    som = SigmaPiSOM(cfg.som_config)
    width = 8 * (int(np.prod(som.x_shape)) + int(np.prod(som.y_shape)))  # a view pair, float64
    _memory.check_count("train_pairs", cfg.train_pairs, 2 * width, "e.g. --train-pairs 20000")
    _memory.check_count("n_test", cfg.n_test, 4 * width + 32 * som.n_units, "e.g. --n-test 10000")
    cal, test = evaluation_sets(som, cfg.n_test)
    jobs = [(f"seed {seed}", CompareJob(seed, cfg, cal, test)) for seed in seeds]
    done = run_all(
        compare_seed,
        jobs,
        executor=executor,
        per_job=job_memory(cfg.som_config, cfg.n_test),
        progress=progress,
        desc="compare",
        verbose=_verbose,
    )
    scores = {name: MethodScore(name) for name in cfg.methods}
    for per_method in done.values():
        for name, (vc, uc, curve, seconds) in per_method.items():
            s = scores[name]
            s.view_consistency.append(vc)
            s.unit_consistency.append(uc)
            s.z_error_by_labels.append(curve)
            s.seconds.append(seconds)
    return CompareResult(cfg, scores, time.perf_counter() - start, seeds)


def _verbose(job: CompareJob) -> CompareJob:
    return dataclasses.replace(job, progress=True)


def _hard_winner(model: SigmaPiSOM) -> Callable[[Array, Array], NDArray[np.int64]]:
    return lambda x, y: model.winner(x, y, hard=True)


class Compare(Experiment[CompareConfig]):
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
    writes = (FIGURE, Path(FIGURE).with_suffix(".txt").name)
    """The files written into --out besides result.json (checked before the work)."""

    def run(
        self,
        config: CompareConfig,
        *,
        seeds: Sequence[int],
        out: Path | None = None,
        executor: Executor | None = None,
        progress: Progress | None = None,
    ) -> CompareResult:
        return run_compare(config, progress, seeds=seeds, executor=executor)


COMPARE = register(Compare())
