"""Run independent jobs in parallel: this machine's cores, or a Dask cluster.

A *job* is a picklable module-level function applied to one picklable argument. The
executor runs each job once and yields an :class:`Outcome` per job as it finishes; a job that
raises is recorded with its error and the others go on. ``sigmapi reproduce`` trains its seeds
through it and ``sigmapi sweep`` its grid.

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
    ``LocalCluster`` starts in about a second, and a scheduler address is all a user needs to
    move the same sweep onto a cluster (dask-jobqueue, Kubernetes, SSH).

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

from sigmapi.config import SOMConfig
from sigmapi.errors import UsageError

__all__ = [
    "ENGINES",
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
    """Bytes of memory available to new processes now (``MemAvailable``; 4 GiB if unknown)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return 4 << 30


def job_memory(cfg: SOMConfig, n_test: int = 10_000) -> int:
    """Peak bytes one training-and-evaluation job of ``cfg`` needs (an upper estimate).

    Weights ``K n_x n_y``: the kernel's state (float32 for the fast kernel, float64 for the
    reference) plus the float64 copy the estimator keeps for responses and saving, twice more
    while a model is exported; evaluation adds ``(n_test, K)`` float64 responses for a few
    test sets; 200 MiB for the interpreter, numpy and numba.
    """
    n = 1
    for s in (*cfg.map_shape, *cfg.x_shape, *cfg.y_shape):
        n *= int(s)
    k = 1
    for s in cfg.map_shape:
        k *= int(s)
    weights = n * (4 if cfg.backend != "reference" else 8) + 3 * n * 8
    evaluation = 4 * n_test * k * 8
    return weights + evaluation + 200 * _MIB


def plan_workers(
    workers: int | None, per_job: int, budget: int | None = None, n_jobs: int | None = None
) -> WorkerPlan:
    """Workers that fit: at most ``workers`` (default: the CPU count), ``budget // per_job``
    and ``n_jobs``; at least one.

    ``budget`` defaults to half of :func:`available_memory`.
    """
    cpus = os.cpu_count() or 1
    want = cpus if workers is None else workers
    if want < 1:
        raise UsageError(f"workers must be a positive int, got {want}; pass --workers 1 or more")
    budget = available_memory() // 2 if budget is None else budget
    fit = max(1, budget // max(per_job, 1))
    n = max(1, min(want, fit, n_jobs if n_jobs else want))
    reason = f"{n} at once ({want} asked, {cpus} cores"
    reason += f", {fit} fit in {budget / 2**30:.1f} GiB at {per_job / 2**30:.2f} GiB each)"
    if fit < want:
        reason += "; memory limits the parallel jobs"
    return WorkerPlan(n, reason)


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
    if engine not in ENGINES:
        raise UsageError(f"engine must be one of {list(ENGINES)}, got {engine!r}")
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
        raise UsageError(
            "engine 'dask' needs dask.distributed; install it with pip install 'sigmapi[sweep]'"
        ) from None
    cluster = None
    if address is None:
        cluster = LocalCluster(n_workers=max(1, workers), threads_per_worker=1, processes=True,
                               dashboard_address=None)  # fmt: skip
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
