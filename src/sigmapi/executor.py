"""Run independent jobs in parallel: this machine's cores, or a Dask cluster.

A *job* is a picklable module-level function applied to one picklable argument. The
executor runs each job once and yields an :class:`Outcome` per job as it finishes; a job that
raises is recorded with its error and the others go on. Every experiment runs its per-seed
jobs through it (:mod:`sigmapi.experiments`); :class:`Executor` holds where they run.

Engines
-------
``"local"`` (default)
    A process pool of this machine (:class:`concurrent.futures.ProcessPoolExecutor`, spawned
    workers, so that no numba or BLAS threads are forked). One worker runs the jobs in this
    process, in order.
``"dask"``
    :mod:`dask.distributed`: the cluster at ``address`` (``tcp://host:8786``), or a local
    cluster of ``workers`` single-threaded processes started for the run. Dask was chosen over
    Ray because it is pure Python with a small install (``pip install 'sigmapi[sweep]'``), its
    ``LocalCluster`` starts quickly, and a scheduler address is all a user needs to move the
    same sweep onto a cluster (dask-jobqueue, Kubernetes, SSH).

Memory
------
Parallel jobs must fit in memory together. :func:`plan_workers` caps the number of workers at
``budget // per_job`` (``budget`` defaults to half the memory available now) and says so.
"""

from __future__ import annotations

import multiprocessing
import os
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from typing import Any

from sigmapi import _memory, _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.som import SigmaPiSOM

__all__ = [
    "ENGINES",
    "Executor",
    "Outcome",
    "WorkerPlan",
    "available_memory",
    "job_memory",
    "plan_workers",
    "run_jobs",
]

ENGINES = ("local", "dask")

_MIB = 1 << 20


@dataclass(frozen=True)
class Outcome:
    """One finished job: its key, its value (``None`` if it failed) and its error text."""

    key: str
    value: Any
    error: str | None
    seconds: float

    @property
    def ok(self) -> bool:
        return self.error is None


@dataclass(frozen=True)
class WorkerPlan:
    """How many jobs run at once, and why (one sentence for the user)."""

    workers: int
    reason: str


def available_memory() -> int:
    """Bytes of memory available to new processes now (4 GiB where the system does not say)."""
    have = _memory.available()
    return 4 << 30 if have is None else have


def job_memory(cfg: SOMConfig, n_test: int = 10_000) -> int:
    """Peak bytes one training-and-evaluation job of ``cfg`` needs (an upper estimate).

    The model's own estimate (:meth:`SigmaPiSOM.memory_estimate`: the weights in the
    kernel's precision and the float64 copies), the ``(n_test, K)`` float64 responses of
    evaluation for a few test sets, and 200 MiB for the interpreter, numpy and numba.
    """
    model = SigmaPiSOM(cfg)
    return model.memory_estimate() + 4 * n_test * model.n_units * 8 + 200 * _MIB


def plan_workers(
    workers: int | None, per_job: int, budget: int | None = None, n_jobs: int | None = None
) -> WorkerPlan:
    """Workers that fit: at most ``workers`` (default: the CPU count), ``budget // per_job``
    and ``n_jobs``; at least one.

    ``budget`` defaults to half of :func:`available_memory`.
    """
    cpus = os.cpu_count() or 1
    want = cpus if workers is None else _validate.integer("workers", workers, 1)
    budget = available_memory() // 2 if budget is None else budget
    fit = max(1, budget // max(per_job, 1))
    n = max(1, min(want, fit, n_jobs if n_jobs else want))
    reason = f"{n} at once ({want} asked, {cpus} cores"
    reason += f", {fit} fit in {budget / 2**30:.1f} GiB at {per_job / 2**30:.2f} GiB each)"
    if fit < want:
        reason += "; memory limits the parallel jobs"
    return WorkerPlan(n, reason)


@dataclass(frozen=True)
class Executor:
    """Where an experiment's jobs run: the engine, how many at once, and the memory they share.

    Experiments take one (``executor=None``: one job after another in this process) and call
    :meth:`plan` and :meth:`run`; the results do not depend on it.

    Examples
    --------
    >>> Executor(workers=2).plan(per_job=1 << 20, n_jobs=5).workers
    2
    """

    engine: str = "local"
    """``"local"``: a process pool of this machine; ``"dask"``: a Dask cluster."""
    workers: int | None = None
    """Jobs at once (None: one per core, as many as fit in the memory budget)."""
    address: str | None = None
    """Scheduler of a running Dask cluster, e.g. ``"tcp://10.0.0.5:8786"`` (engine ``"dask"``;
    None: a local cluster started for the run)."""
    memory_budget: int | None = None
    """Bytes the parallel jobs may use together (None: half of the memory available)."""

    def __post_init__(self) -> None:
        _validate.choice("engine", self.engine, ENGINES)
        if self.workers is not None:
            _validate.integer("workers", self.workers, 1)
        if self.memory_budget is not None:
            _validate.integer("memory_budget", self.memory_budget, 1, fix="in bytes")
        if self.address is not None and self.engine != "dask":
            raise ConfigError(
                f"address names a Dask scheduler, got {self.address!r} with engine "
                f"{self.engine!r}; use engine 'dask' with it"
            )

    def plan(self, per_job: int, n_jobs: int) -> WorkerPlan:
        """How many of ``n_jobs`` jobs of ``per_job`` bytes each run at once
        (:func:`plan_workers`)."""
        return plan_workers(self.workers, per_job, self.memory_budget, n_jobs=max(1, n_jobs))

    def run(
        self, fn: Callable[[Any], Any], jobs: Sequence[tuple[str, Any]], workers: int
    ) -> Iterator[Outcome]:
        """:func:`run_jobs` on this engine, ``workers`` at once (from :meth:`plan`)."""
        return run_jobs(fn, jobs, workers=workers, engine=self.engine, address=self.address)


def _call(fn: Callable[[Any], Any], arg: Any) -> tuple[Any, str | None, float]:
    """Run one job, catching its error: ``(value, error, seconds)``."""
    t0 = time.perf_counter()
    try:
        return fn(arg), None, time.perf_counter() - t0
    except Exception as e:  # a failed job is recorded, the others go on
        last = traceback.format_exception_only(type(e), e)[-1].strip()
        return None, last, time.perf_counter() - t0


def run_jobs(
    fn: Callable[[Any], Any],
    jobs: Sequence[tuple[str, Any]],
    *,
    workers: int = 1,
    engine: str = "local",
    address: str | None = None,
) -> Iterator[Outcome]:
    """Apply ``fn`` to each ``(key, arg)`` of ``jobs``; yield an :class:`Outcome` per job as
    it finishes (in order of completion; in job order with one local worker).

    ``fn`` and the args must be picklable (a module-level function) for ``workers > 1`` and
    for Dask. ``workers`` is the number of jobs at once (see :func:`plan_workers`).
    """
    _validate.choice("engine", engine, ENGINES)
    if engine == "dask":
        yield from _run_dask(fn, jobs, workers, address)
        return
    if workers <= 1 or len(jobs) <= 1:
        for key, arg in jobs:
            value, error, sec = _call(fn, arg)
            yield Outcome(key, value, error, sec)
        return
    ctx = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        pending: dict[Future[Any], str] = {pool.submit(_call, fn, arg): key for key, arg in jobs}
        try:
            while pending:
                done, _ = wait(pending, return_when=FIRST_COMPLETED)
                for fut in done:
                    key = pending.pop(fut)
                    value, error, sec = fut.result()
                    yield Outcome(key, value, error, sec)
        finally:
            for fut in pending:
                fut.cancel()


def _run_dask(
    fn: Callable[[Any], Any], jobs: Sequence[tuple[str, Any]], workers: int, address: str | None
) -> Iterator[Outcome]:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:  # pragma: no cover - depends on the install
        raise ConfigError(
            "engine 'dask' needs dask.distributed; install it with pip install 'sigmapi[sweep]'"
        ) from None
    cluster = None
    if address is None:
        cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1, processes=True,
                               dashboard_address=":0")  # fmt: skip
    try:
        with Client(address if address is not None else cluster) as client:
            futures = {client.submit(_call, fn, arg, key=f"sigmapi-{key}", pure=False): key
                       for key, arg in jobs}  # fmt: skip
            for fut in as_completed(futures):
                value, error, sec = fut.result()
                yield Outcome(futures[fut], value, error, sec)
    finally:
        if cluster is not None:
            cluster.close()
