"""The jobs of ``sigmapi neurons``, one per seed and task: every map of the package's docstring
trained and scored by :func:`sigmapi.evaluate`; in 1-D also each map's physiology
(:func:`sigmapi.analysis.physiology.record`) and the spiking deployments on ``spike_test`` test
z's of the evaluation set: the conjunction network at every peak rate, the dendritic ones at
100 Hz.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from sigmapi.analysis.physiology import record
from sigmapi.config import SOMConfig
from sigmapi.executor import job_memory
from sigmapi.experiments.base import register
from sigmapi.experiments.kit.jobs import SeedRuns, Tick
from sigmapi.experiments.kit.seeds import SeedPlan
from sigmapi.metrics import evaluate, evaluation_sets, grid_spacing, winner_metrics, z_decoder
from sigmapi.model.som import SigmaPiSOM
from sigmapi.neurons.basis import BasisFunctionMap
from sigmapi.neurons.dendritic import DendriticMap, branch_summary
from sigmapi.neurons.sparse import SparseDendriticMap, sparse_summary
from sigmapi.neurons.spiking import (
    SpikingConfig,
    SpikingRun,
    simulate_conjunction,
    simulate_dendritic,
)
from sigmapi.progress import Progress

from .config import METRICS, PHYSIOLOGY, QUICK, REFERENCE_RATE, NeuronsConfig
from .result import NeuronsResult, Row

M = TypeVar("M")
SPIKES = ("input_spikes", "hidden_spikes", "map_spikes")
"""The spike counts per trial of a spiking run (:class:`~sigmapi.neurons.spiking.SpikingRun`)."""
Array = NDArray[np.float64]


PLAN = SeedPlan({"spikes": 11, "neurons": 12})
"""The streams of a seed (:class:`~sigmapi.experiments.kit.seeds.SeedPlan`): the spike trains
at each peak rate (and pool, where not the config's), under key 11; the training pairs and
start of the dendritic, sparse dendritic and basis-function maps, under key 12 (each map the
same stream, as the Sigma-Pi map's are its seed's own)."""


@dataclass(frozen=True)
class NeuronsJob:
    """One seed and task of the experiment."""

    seed: int
    task: str  # "1d" or "2d"
    config: NeuronsConfig
    show: Progress | None = None
    """Where given, the job shows its steps (:func:`~sigmapi.experiments.kit.jobs.counted`)."""

    @property
    def som_config(self) -> SOMConfig:
        c = self.config
        return c.som_config if self.task == "1d" else c.som_config_2d


def _scored(model: Any, n_test: int, start: float, **extra: Any) -> Row:
    m = evaluate(model, n_test=n_test)
    row = {k: float(getattr(m, k)) for k in METRICS}
    row.update(folded=bool(m.folded), seconds=time.perf_counter() - start, **extra)
    return row


def _z_table(model: Any, n: int) -> np.ndarray:
    """Each unit's decoded z ``(K, d)`` on the calibration set (for the branch summary)."""
    cal, _ = evaluation_sets(model, n)
    return z_decoder(model.winner(cal.x0, cal.y0, hard=True), cal.z, model.map_coords)


def _spiking_rows(
    job: NeuronsJob,
    name: str,
    model: Any,
    simulate: Callable[[Array, Array, SpikingConfig, np.random.Generator], SpikingRun],
    rate_winner: Callable[[Array, Array], NDArray[np.int64]],
    rates: Sequence[tuple[float, int]],
    *,
    dendritic: bool = False,
    tick: Tick | None = None,
) -> list[dict[str, object]]:
    """One row per window and ``(peak rate, pool)`` of ``rates`` of a spiking deployment of
    ``model`` (a pool other than the config's tags the name ``-pool<n>``); ``dendritic``: the
    dendritic network's settings (:meth:`NeuronsConfig.spiking`)."""
    c = job.config
    cal, test = evaluation_sets(model, c.n_test)
    n = min(c.spike_test, test.z.shape[0])
    x = np.vstack([test.x0[:n], test.x1[:n]])
    y = np.vstack([test.y0[:n], test.y1[:n]])
    r = rate_winner(x, y)
    wc = rate_winner(cal.x0, cal.y0)
    spacing = grid_spacing(model.x_shape, model.config.periodic)
    rows = []
    for rate, pool in rates:
        more = (rate,) if pool == c.pool else (rate, pool)
        rng = PLAN.rng(job.seed, "spikes", *more)
        tag = "" if pool == c.pool else f"-pool{pool}"
        _step(tick, 0, f"{name}{tag} at {rate:g} Hz")
        start = time.perf_counter()
        run: SpikingRun = simulate(x, y, c.spiking(rate, pool, dendritic=dendritic), rng)
        secs = time.perf_counter() - start
        _step(tick, 1, f"{name}{tag} at {rate:g} Hz")
        for i, window in enumerate(run.windows_ms):
            w = run.winners[i]
            m = winner_metrics(wc, cal.z, w[:n], w[n:], test.z[:n], model.map_coords, spacing)
            spikes = run.input_spikes[i] + run.hidden_spikes[i] + run.map_spikes[i]
            rows.append(
                {
                    "name": f"{name}{tag}-{window:g}ms",
                    "window_ms": window,
                    "peak_rate": rate,
                    "pool": pool,
                    "agreement": float(np.mean(w == r)),
                    "rate_view_consistency": float(np.mean(r[:n] == r[n:])),
                    **{k: m[k] for k in METRICS[:4]},  # view consistency to order
                    **{k: float(getattr(run, k)[i].mean()) for k in SPIKES},
                    "spikes_per_decision": float(spikes.mean()),
                    "n_trials": int(x.shape[0]),
                    "seconds": secs,
                }
            )
    return rows


def _step(tick: Tick | None, n: int, phase: str) -> None:
    """``tick(n, phase)`` where the job shows its steps: 0 as a step starts, 1 when done."""
    if tick is not None:
        tick(n, phase)


def _neurons_job(job: NeuronsJob, tick: Tick | None) -> Row:
    c, cfg = job.config, job.som_config
    two_d = job.task == "2d"
    training, stride = c.training(two_d), c.basis_stride_2d if two_d else 1
    maps: list[tuple[str, Any, Row]] = []  # name, model, its row's own keys
    drawn = PLAN.sequence(job.seed, "neurons")  # the neuron maps' pairs and start

    def train(name: str, fit: Callable[..., M], *args: Any, **kwargs: Any) -> M:
        start = time.perf_counter()  # a row's seconds: from its training to its scores
        _step(tick, 0, f"train {name}")
        model = fit(*args, **kwargs)
        _step(tick, 1, f"train {name}")
        maps.append((name, model, {"start": start}))
        return model

    sp = train("sigma-pi", SigmaPiSOM(cfg, seed=job.seed).fit)
    maps[-1][2]["synapses"] = int(np.prod(cfg.x_shape)) * int(np.prod(cfg.y_shape))
    dendritic: dict[int, DendriticMap] = {}
    for d in c.branches_2d if two_d else c.branches:
        dm = dendritic[d] = train(f"dendritic-D{d}", DendriticMap(cfg, d).fit, training, seed=drawn)
        maps[-1][2].update(synapses=dm.synapses, branches=d, active_synapses=dm.active_synapses())
    sparse: dict[int, SparseDendriticMap] = {}
    for d in c.sparse_branches_2d if two_d else c.sparse_branches:
        fit = SparseDendriticMap(cfg, d, stride=stride).fit
        sm = sparse[d] = train(f"dendritic-sparse-D{d}", fit, training, seed=drawn)
        gap = sparse_summary(sm, _z_table(sm, c.n_test))["z_gap_median"]
        maps[-1][2].update(
            synapses=sm.synapses, mean_synapses=sm.mean_synapses, branches=d, branch_z_gap=gap
        )
    basis = BasisFunctionMap(cfg, stride=stride).fit
    maps[-1][2]["synapses"] = train("basis-function", basis, training, seed=drawn).synapses
    rows = []
    for name, model, extra in maps:
        begin = extra.pop("start")
        _step(tick, 0, f"score {name}")
        row = _scored(model, c.n_test, begin, name=name, task=job.task, seed=job.seed, **extra)
        if not two_d:  # the physiology's medians over the units
            phys = record(model)
            row.update({k: phys[f"median_{k}"] for k in PHYSIOLOGY})
        rows.append(row)
        _step(tick, 1, f"score {name}")
    mid = sorted(dendritic)[len(dendritic) // 2]
    summary = branch_summary(dendritic[mid], _z_table(dendritic[mid], c.n_test))
    summary.update(branches=mid, task=job.task, seed=job.seed)
    spiking = [] if two_d else _spiking(job, sp, dendritic, sparse, tick)
    for r in spiking:
        r.update(task=job.task, seed=job.seed)
    return {"maps": rows, "spiking": spiking, "branches": summary}


def _spiking(
    job: NeuronsJob,
    sp: SigmaPiSOM,
    dendritic: dict[int, DendriticMap],
    sparse: dict[int, SparseDendriticMap],
    tick: Tick | None,
) -> list[dict[str, object]]:
    """The rows of the spiking deployments of a 1-D job: the conjunction network at every
    peak rate (and the compared pools at the reference rate), the dendritic and the sparse
    dendritic maps at the reference rate (trained here where the job has not)."""
    c, cfg = job.config, job.som_config
    training = c.training(False)
    ref = REFERENCE_RATE if REFERENCE_RATE in c.peak_rates else c.peak_rates[0]
    runs = [(rate, c.pool) for rate in c.peak_rates]
    runs += [(ref, p) for p in c.pools_compared if p != c.pool]
    conj = partial(simulate_conjunction, sp.weights_)
    rows = _spiking_rows(job, "spiking-conjunction", sp, conj, sp.winner, runs, tick=tick)
    drawn = PLAN.sequence(job.seed, "neurons")
    deployed: list[tuple[str, int, Any, Callable[..., SpikingRun], bool]] = []
    if c.spiking_branches:
        d = c.spiking_branches
        dm = dendritic.get(d) or DendriticMap(cfg, d).fit(training, seed=drawn)
        net = partial(simulate_dendritic, dm.u_, dm.v_, dm.gain, dm.threshold)
        deployed.append(("spiking-dendritic", d, dm, net, True))
    if c.spiking_sparse_branches:
        d = c.spiking_sparse_branches
        sm = sparse.get(d) or SparseDendriticMap(cfg, d).fit(training, seed=drawn)
        branch_weights = (sm.c_ * sm.mask_).reshape(sm.n_units, int(np.prod(cfg.x_shape)), -1)
        net = partial(simulate_conjunction, branch_weights)
        deployed.append(("spiking-sparse-dendritic", d, sm, net, False))
    for name, d, model, simulate, dend in deployed:
        got = _spiking_rows(
            job, name, model, simulate, model.winner, [(ref, c.pool)], dendritic=dend, tick=tick
        )
        rows += [{**r, "branches": d} for r in got]
    return rows


class NeuronsExperiment(SeedRuns[NeuronsConfig]):
    """Dendritic neurons with first-order synapses, a basis-function network and spiking
    networks against the Sigma-Pi map, on the same seeds (the chapter's section 7.1): one job
    per seed and task (2-D on the first ``seeds_2d`` seeds)."""

    name = "neurons"
    summary = "the transformation in dendritic, basis-function and spiking neurons"
    config_type = NeuronsConfig
    quick = QUICK
    seeds = (100, 101, 102, 103, 104)
    quick_seeds = (100,)
    quick_time = "about 1-2.5 min on two busy cores"
    default_out = "neurons"
    unit = "step"

    def check(self, config: NeuronsConfig) -> int:
        """One job's memory: the largest map's, the spiking runs' and the online phase's
        pairs, as codes."""
        som = config.som_config_2d if config.preset_2d else config.som_config
        online = [(config.som_config, config.pairs)]
        online += [(config.som_config_2d, config.pairs_2d)] if config.preset_2d else []
        codes = max(n * (int(np.prod(c.x_shape)) + int(np.prod(c.y_shape))) * 8 for c, n in online)
        return job_memory(som, config.n_test) + config.spiking_cost()[1] + codes

    def jobs(
        self, config: NeuronsConfig, seeds: tuple[int, ...], shared: object
    ) -> list[tuple[str, NeuronsJob]]:
        tasks = {"1d": seeds, "2d": seeds[: config.seeds_2d] if config.preset_2d else ()}
        return [(f"seed {s} {t}", NeuronsJob(s, t, config)) for t, of in tasks.items() for s in of]

    def steps(self, job: NeuronsJob) -> int:
        """The job's steps: each map trained and each scored, each spiking run."""
        c = job.config
        if job.task == "2d":
            return 2 * (2 + len(c.branches_2d) + len(c.sparse_branches_2d))
        spiking = len(c.peak_rates) + sum(p != c.pool for p in c.pools_compared)
        spiking += bool(c.spiking_branches) + bool(c.spiking_sparse_branches)
        return 2 * (2 + len(c.branches) + len(c.sparse_branches)) + spiking

    def desc(self, job: NeuronsJob) -> str:
        return f"neurons seed {job.seed} {job.task}"

    def describe(self, key: str, value: Row) -> str:
        return f"{key}: " + ", ".join(
            f"{r['name']} {r['view_consistency']:.3f}" for r in value["maps"]
        )

    def seed_run(self, job: NeuronsJob, tick: Tick | None) -> Row:
        """Every map of one seed and task: ``{"maps": [rows], "spiking": [rows], "branches":
        summary of the middle dendritic map's branches}`` (rows: ``name``, ``task``, the
        :data:`METRICS`, ``folded``, ``synapses``, physiology medians in 1-D)."""
        return _neurons_job(job, tick)

    def collect(
        self, config: NeuronsConfig, seeds: tuple[int, ...], values: list[Any]
    ) -> NeuronsResult:
        runs = {kind: [r for v in values for r in v[kind]] for kind in ("maps", "spiking")}
        rest = [{k: x for k, x in v["branches"].items() if not isinstance(x, list)} for v in values]
        return NeuronsResult(config, seeds, runs, [values[0]["branches"], *rest[1:]], 0.0)


NEURONS = register(NeuronsExperiment())
