"""The job executor: the same outcomes on one worker, a process pool and a Dask cluster."""

from __future__ import annotations

import os

import pytest

from sigmapi.config import SOMConfig
from sigmapi.errors import ConfigError
from sigmapi.executor import Executor, job_memory, plan_workers, run_jobs, worker_threads
from sigmapi.model.som import SigmaPiSOM


def _square_or_fail(v: int) -> int:
    if v == 3:
        raise ValueError("three is refused")
    return v * v


JOBS = [(f"job{v}", v) for v in range(5)]


def _collect(**kw):
    return {o.key: (o.value, o.error) for o in run_jobs(_square_or_fail, JOBS, **kw)}


def test_one_worker_runs_in_order_and_records_failures():
    outcomes = list(run_jobs(_square_or_fail, JOBS, workers=1))
    assert [o.key for o in outcomes] == [k for k, _ in JOBS]
    bad = outcomes[3]
    assert not bad.ok and bad.value is None and bad.error == "ValueError: three is refused"
    assert [o.value for o in outcomes if o.ok] == [0, 1, 4, 16]


def test_process_pool_gives_the_same_outcomes():
    assert _collect(workers=2) == _collect(workers=1)


def _numba_threads(_: int) -> int:
    import numba

    return int(numba.get_num_threads())


def test_pool_workers_share_the_cores_among_their_numba_threads(monkeypatch):
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    got = {o.value for o in run_jobs(_numba_threads, [("a", 0), ("b", 1)], workers=2)}
    assert got == {worker_threads(2)}
    cores = len(os.sched_getaffinity(0))
    assert worker_threads(2) == max(1, cores // 2) and worker_threads(1) == cores
    assert worker_threads(10 * cores) == 1


def test_dask_local_cluster_gives_the_same_outcomes():
    pytest.importorskip("distributed")
    assert _collect(workers=2, engine="dask") == _collect(workers=1)


def test_unknown_engine_is_refused():
    with pytest.raises(ConfigError, match="engine must be one of"):
        list(run_jobs(_square_or_fail, JOBS, engine="spark"))
    with pytest.raises(ConfigError, match="engine must be one of"):
        Executor(engine="spark")


def test_memory_budget_limits_the_workers():
    plan = plan_workers(8, per_job=3 << 30, budget=7 << 30)
    assert plan.workers == 2 and "memory limits" in plan.reason
    assert plan_workers(8, per_job=1 << 20, budget=1 << 30, n_jobs=3).workers == 3
    assert plan_workers(2, per_job=1 << 40, budget=1 << 30).workers == 1
    with pytest.raises(ConfigError, match="workers must be an int >= 1, got 0"):
        plan_workers(0, per_job=1)


def test_executor_holds_the_settings_and_plans_with_them():
    ex = Executor(workers=3, memory_budget=7 << 30)
    assert ex.plan(per_job=3 << 30, n_jobs=10).workers == 2
    assert ex.plan(per_job=1 << 20, n_jobs=0).workers == 1
    assert [o.value for o in ex.run(_square_or_fail, JOBS[:3], workers=1)] == [0, 1, 4]
    with pytest.raises(ConfigError, match="address names a Dask scheduler"):
        Executor(address="tcp://localhost:8786")
    with pytest.raises(ConfigError, match="workers must be an int >= 1"):
        Executor(workers=0)


def test_job_memory_grows_with_the_weights():
    small = SOMConfig(map_shape=(4,), x_shape=(5,), y_shape=(5,))
    paper_2d = SOMConfig(map_shape=(15, 15), x_shape=(15, 15), y_shape=(15, 15))
    weights = 225 * 225 * 225
    assert job_memory(paper_2d) - job_memory(small) >= weights * (4 + 8)
    assert job_memory(paper_2d) >= SigmaPiSOM(paper_2d).memory_estimate()
