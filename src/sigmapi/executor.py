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

import ctypes
import multiprocessing
import os
import re
import signal
import socket
import struct
import sys
import threading
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass
from typing import Any, TypeVar

from sigmapi import _memory, _validate
from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError, install_hint
from sigmapi.model.som import SigmaPiSOM

__all__ = [
    "ENGINES",
    "Executor",
    "Outcome",
    "WorkerPlan",
    "available_memory",
    "die_with_parent",
    "job_memory",
    "parse_address",
    "plan_workers",
    "probe_scheduler",
    "run_jobs",
    "start_worker",
    "worker_threads",
]

ENGINES = ("local", "dask")

_MIB = 1 << 20

CONNECT_TIMEOUT_S = 5.0
"""Seconds to wait for a Dask scheduler to accept a connection and greet."""

_LABEL = r"[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
_HOST = rf"(?:{_LABEL}(?:\.{_LABEL})*|\[[0-9A-Fa-f:.]+\])"
_ADDRESS = re.compile(rf"(?:(tcp|tls)://)?({_HOST}):([0-9]{{1,5}})")


def parse_address(address: str) -> tuple[str, str, int]:
    """``(scheme, host, port)`` of a Dask scheduler address, ``tcp://HOST:PORT`` (or
    ``tls://``, or ``HOST:PORT``); anything else raises ConfigError naming the form.

    Examples
    --------
    >>> parse_address("tcp://10.0.0.5:8786")
    ('tcp', '10.0.0.5', 8786)
    """
    m = _ADDRESS.fullmatch(address) if isinstance(address, str) and len(address) < 300 else None
    port = int(m.group(3)) if m else 0
    if m is None or not 1 <= port <= 65535:
        shown = repr(address)[:80]
        raise ConfigError(
            f"address must be a Dask scheduler address tcp://HOST:PORT (or tls://HOST:PORT, "
            f"port 1-65535), got {shown}; e.g. tcp://10.0.0.5:8786, as the scheduler prints it"
        )
    return m.group(1) or "tcp", m.group(2).strip("[]"), port


def probe_scheduler(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Raise ConfigError unless something at ``address`` accepts a connection within
    ``timeout`` seconds and (``tcp``) greets as a Dask scheduler does: its first message, the
    handshake, is a small frame. Checked before Dask reads a stranger's bytes as a frame
    length (and asks for exabytes)."""
    scheme, host, port = parse_address(address)
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            if scheme != "tcp":
                return  # a TLS greeting needs the certificates: Dask checks it
            head = b""
            while len(head) < 8:
                chunk = sock.recv(8 - len(head))
                if not chunk:
                    break
                head += chunk
    except TimeoutError:
        raise ConfigError(
            f"the Dask scheduler at {address!r} did not answer within "
            f"{timeout:g} s; check the address and that the scheduler runs "
            "(dask scheduler prints its address)"
        ) from None
    except OSError as exc:
        raise ConfigError(
            f"cannot connect to a Dask scheduler at {address!r}: "
            f"{exc.strerror or exc}; check the address and that the scheduler "
            "runs"
        ) from None
    size = struct.unpack("<Q", head)[0] if len(head) == 8 else 0
    if not 0 < size < _MIB:
        raise ConfigError(
            f"{address!r} does not answer as a Dask scheduler (its first bytes are no Dask "
            "handshake); check the address and port"
        )


A = TypeVar("A")


@dataclass(frozen=True)
class Outcome:
    """One finished job: its key, its value (``None`` if it failed) and its error text."""

    key: str
    value: Any  # what the job's function returned: its caller knows the type
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
        if self.address is not None:
            parse_address(self.address)
            if self.engine != "dask":
                raise ConfigError(
                    f"address names a Dask scheduler, got {self.address!r} with engine "
                    f"{self.engine!r}; use engine 'dask' with it"
                )

    def check(self) -> None:
        """What can be checked before any job runs: that the engine's library is installed
        and the scheduler at :attr:`address` answers (:func:`probe_scheduler`)."""
        if self.engine != "dask":
            return
        try:
            import distributed  # noqa: F401
        except ImportError:  # pragma: no cover - depends on the install
            raise _no_dask() from None
        if self.address is not None:
            probe_scheduler(self.address)

    def plan(self, per_job: int, n_jobs: int) -> WorkerPlan:
        """How many of ``n_jobs`` jobs of ``per_job`` bytes each run at once
        (:func:`plan_workers`)."""
        return plan_workers(self.workers, per_job, self.memory_budget, n_jobs=max(1, n_jobs))

    def run(
        self, fn: Callable[[A], object], jobs: Sequence[tuple[str, A]], workers: int
    ) -> Iterator[Outcome]:
        """:func:`run_jobs` on this engine, ``workers`` at once (from :meth:`plan`)."""
        return run_jobs(fn, jobs, workers=workers, engine=self.engine, address=self.address)


def _call(fn: Callable[[A], object], arg: A) -> tuple[object, str | None, float]:
    """Run one job, catching its error: ``(value, error, seconds)``."""
    t0 = time.perf_counter()
    try:
        return fn(arg), None, time.perf_counter() - t0
    except Exception as e:  # a failed job is recorded, the others go on
        last = traceback.format_exception_only(type(e), e)[-1].strip()
        return None, last, time.perf_counter() - t0


def job_error(where: str, error: str) -> Exception:
    """The exception of a failed job (:attr:`Outcome.error`, ``"module.Class: message"``) to
    raise in the caller: a sigmapi error as its own class, so that the command line says it in
    one line as it would in this process; a ``MemoryError`` as a
    :class:`~sigmapi.errors.ResourceError`; anything else (a bug) as ``RuntimeError``.
    ``where`` names the job (e.g. ``"robot job 0"``) and leads the message."""
    from sigmapi import errors

    name, sep, message = error.partition(": ")
    cls_name = name.rpartition(".")[2]
    cls = getattr(errors, cls_name, None) if name.startswith(("sigmapi.", cls_name)) else None
    if sep and isinstance(cls, type) and issubclass(cls, errors.SigmapiError):
        return cls(f"{where}: {message}")
    if sep and cls_name.endswith("MemoryError"):
        return errors.ResourceError(
            f"{where}: out of memory ({message}); use a smaller "
            "setting or fewer jobs at once (--workers)"
        )
    return RuntimeError(f"{where} failed: {error}")


def run_jobs(
    fn: Callable[[A], object],
    jobs: Sequence[tuple[str, A]],
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
    pool = ProcessPoolExecutor(
        max_workers=workers,
        mp_context=ctx,
        initializer=start_worker,
        initargs=(os.getpid(), worker_threads(workers)),
    )
    pending: dict[Future[tuple[object, str | None, float]], str] = {}
    try:
        pending = {pool.submit(_call, fn, arg): key for key, arg in jobs}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                key = pending.pop(fut)
                value, error, sec = fut.result()
                yield Outcome(key, value, error, sec)
    except BaseException:  # SIGTERM, Ctrl-C, a caller that stops early: stop the jobs now
        _stop(pool, pending)
        raise
    pool.shutdown(wait=True)


def _stop(
    pool: ProcessPoolExecutor, pending: dict[Future[tuple[object, str | None, float]], str]
) -> None:
    """End a pool at once: cancel the jobs not started, end the workers running the others
    (a job is a pure function of its argument: nothing of it is lost but its time)."""
    for fut in pending:
        fut.cancel()
    for proc in list((getattr(pool, "_processes", None) or {}).values()):
        proc.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


_PR_SET_PDEATHSIG = 1


def worker_threads(workers: int) -> int:
    """numba threads per pool worker: the cores this process may use, shared among the
    ``workers`` (at least 1). Two workers of two threads each on two cores would make four
    threads that wait on each other's cores at every parallel call; measured on two cores,
    two paper-2d jobs at once took 17 % more CPU that way than with one thread each. Results
    do not depend on the thread count (``docs/``'s determinism guarantee)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        cores = os.cpu_count() or 1
    return max(1, cores // max(1, workers))


def start_worker(parent: int, threads: int) -> None:
    """A pool worker's start: end with the parent (:func:`die_with_parent`) and use at most
    ``threads`` numba threads (:func:`worker_threads`), unless the user set
    ``NUMBA_NUM_THREADS`` for the run."""
    die_with_parent(parent)
    if "NUMBA_NUM_THREADS" in os.environ:
        return
    os.environ["NUMBA_NUM_THREADS"] = str(threads)  # read by numba when it is first imported
    numba = sys.modules.get("numba")
    if numba is not None:  # already imported (by the parent's main module): its threads now
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))


def die_with_parent(parent: int) -> None:
    """Make this process (a pool worker) end when the process ``parent`` ends, SIGKILL
    included: the kernel's parent-death signal on Linux (``prctl(PR_SET_PDEATHSIG)``), else a
    daemon thread that polls the parent's pid each second."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:  # the parent died before the call
                    os._exit(1)
                return
        except (OSError, AttributeError):  # pragma: no cover - no prctl: poll instead
            pass

    def watch() -> None:  # pragma: no cover - not Linux
        while os.getppid() == parent:
            time.sleep(1.0)
        os._exit(1)

    threading.Thread(target=watch, name="sigmapi-parent-watch", daemon=True).start()


def _no_dask() -> ConfigError:
    return ConfigError(
        f"engine 'dask' needs dask.distributed (not installed here); {install_hint('sweep')}"
    )


def _run_dask(
    fn: Callable[[A], object], jobs: Sequence[tuple[str, A]], workers: int, address: str | None
) -> Iterator[Outcome]:
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:  # pragma: no cover - depends on the install
        raise _no_dask() from None
    cluster = None
    if address is not None:
        probe_scheduler(address)
    if address is None:
        cluster = LocalCluster(
            n_workers=max(1, workers), threads_per_worker=1, processes=True, dashboard_address=":0"
        )
    try:
        target = address if address is not None else cluster
        with Client(target, timeout=f"{CONNECT_TIMEOUT_S * 2:g}s") as client:
            futures = {
                client.submit(_call, fn, arg, key=f"sigmapi-{key}", pure=False): key
                for key, arg in jobs
            }
            for fut in as_completed(futures):
                value, error, sec = fut.result()
                yield Outcome(futures[fut], value, error, sec)
    finally:
        if cluster is not None:
            cluster.close()
