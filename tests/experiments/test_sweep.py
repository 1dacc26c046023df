"""``sigmapi sweep``: the grid x seeds table, the same on every engine, resumable, checked specs."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from sigmapi.errors import ConfigError
from sigmapi.experiments.sweep.run import RESULTS, SweepSpec, read_results, run_sweep

SPEC = """
preset = "tiny-1d"
seeds = [0, 1]
n_test = 500
[set]
iterations = 1500
[grid]
code_width = [0.5, 1.0]
ordering = ["none", "crossview"]
"""


def _table(rows):
    skip = {"train_seconds", "total_seconds"}
    return {r["run_id"]: {k: str(v) for k, v in r.items() if k not in skip} for r in rows}


def test_spec_lists_the_cross_product_and_checks_every_point():
    spec = SweepSpec.from_toml(SPEC)
    runs = spec.runs()
    assert len(runs) == 2 * 2 * 2
    assert {(r.params["code_width"], r.params["ordering"], r.seed) for r in runs} == {
        (w, o, s) for w in (0.5, 1.0) for o in ("none", "crossview") for s in (0, 1)
    }
    assert all(r.config.iterations == 1500 and r.config.seed == r.seed for r in runs)
    with pytest.raises(ConfigError, match="grid point"):
        SweepSpec.from_toml(SPEC.replace('["none", "crossview"]', '["none", "sideways"]'))
    with pytest.raises(ConfigError, match="seeds must be a list of non-negative ints"):
        SweepSpec.from_toml(SPEC.replace("seeds = [0, 1]", "seeds = [-1]"))
    with pytest.raises(ConfigError, match="both in \\[set\\] and in \\[grid\\]"):
        SweepSpec.from_toml(SPEC.replace("iterations = 1500", "code_width = 2.0"))
    with pytest.raises(ConfigError, match="unknown key 'grids'"):
        SweepSpec.from_toml(SPEC.replace("[grid]", "[grids]"))


@pytest.mark.slow  # starts a Dask cluster: 20-30 s on a loaded machine
def test_local_pool_and_dask_cluster_give_the_same_table(tmp_path):
    pytest.importorskip("distributed")
    spec = SweepSpec.from_toml(SPEC)
    local = run_sweep(spec, tmp_path / "local", workers=2)
    dask = run_sweep(spec, tmp_path / "dask", engine="dask", workers=2)
    assert len(local) == 8 and all(r["status"] == "ok" for r in local)
    assert _table(local) == _table(dask)
    # the table on disk holds the same runs (appended as they finish)
    on_disk = read_results(tmp_path / "local" / RESULTS)
    assert sorted(r["run_id"] for r in on_disk) == sorted(r.run_id for r in spec.runs())
    assert _table(on_disk) == _table(local)


def test_killed_sweep_runs_only_the_missing_runs_when_started_again(tmp_path):
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(SPEC.replace("iterations = 1500", "iterations = 6000"))
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "sigmapi.cli", "sweep", str(spec_file), "--out", str(out),
           "--workers", "1"]  # fmt: skip
    log = tmp_path / "first.log"
    with log.open("w") as err:
        proc = subprocess.Popen(cmd, stderr=err, start_new_session=True)
        deadline = time.monotonic() + 120
        while len(read_results(out / RESULTS)) < 3 and time.monotonic() < deadline:
            assert proc.poll() is None, log.read_text()
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    before = read_results(out / RESULTS)
    assert 3 <= len(before) < 8, "the sweep should have been killed half-way"

    again = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"{len(before)} finished already, {8 - len(before)} to run" in again.stderr
    after = read_results(out / RESULTS)
    assert len(after) == 8 and all(r["status"] == "ok" for r in after)
    # the finished runs were not run again: their rows, seconds included, are unchanged
    kept = {r["run_id"]: r for r in after}
    assert all(kept[r["run_id"]] == r for r in before)
    assert Path(out / "sweep.png").stat().st_size > 0


def test_bad_spec_is_one_line_and_exit_2(tmp_path):
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(SPEC.replace('preset = "tiny-1d"', 'preset = "tiny-9d"'))
    r = subprocess.run([sys.executable, "-m", "sigmapi.cli", "sweep", str(spec_file), "--out",
                        str(tmp_path / "o")], capture_output=True, text=True)  # fmt: skip
    assert r.returncode == 2
    assert r.stderr.count("\n") == 1 and "unknown preset 'tiny-9d'" in r.stderr


@pytest.mark.slow  # starts a Dask cluster: 20-30 s on a loaded machine
def test_sweep_runs_on_an_existing_dask_cluster_by_address(tmp_path):
    distributed = pytest.importorskip("distributed")
    spec_file = tmp_path / "spec.toml"
    spec_file.write_text(SPEC.replace("seeds = [0, 1]", "seeds = [0]"))
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  dashboard_address=":0") as cluster:  # fmt: skip
        r = subprocess.run(
            [sys.executable, "-m", "sigmapi.cli", "sweep", str(spec_file), "--out",
             str(tmp_path / "o"), "--engine", "dask", "--address", cluster.scheduler_address],
            capture_output=True, text=True, timeout=300,
        )  # fmt: skip
    assert r.returncode == 0, r.stderr
    rows = read_results(tmp_path / "o" / RESULTS)
    assert len(rows) == 4 and all(row["status"] == "ok" for row in rows)
    local = run_sweep(SweepSpec.read(spec_file), tmp_path / "local", workers=1)
    assert _table(rows) == _table(local)


TINY_SPEC = (
    SPEC.replace("n_test = 500", "n_test = 50")
    .replace("iterations = 1500", 'iterations = 60\nbackend = "reference"')
    .replace('ordering = ["none", "crossview"]\n', "")
)


class _Killed(BaseException):
    """Stands for a SIGKILL between two runs (nothing after it runs)."""


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    out = tmp_path_factory.mktemp("whole")
    run_sweep(SweepSpec.from_toml(TINY_SPEC), out, workers=1)
    return _table(read_results(out / RESULTS))


@given(after=st.integers(0, 4), torn=st.integers(0, 120))
@settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
def test_a_sweep_killed_anywhere_and_resumed_gives_the_uninterrupted_table(
    tmp_path_factory, uninterrupted, after, torn
):
    """Killed after ``after`` runs, with ``torn`` bytes of a row half-written, then resumed."""
    spec = SweepSpec.from_toml(TINY_SPEC)
    out = tmp_path_factory.mktemp("killed")
    done = []

    def kill_after(ok, line):
        done.append(line)
        if len(done) == after:
            raise _Killed

    try:
        run_sweep(spec, out, workers=1, on_done=kill_after)
    except _Killed:
        pass
    whole = (out / RESULTS).read_bytes()
    lines = whole.splitlines(keepends=True)
    if torn and len(lines) > 1:  # the next row cut short, as a kill during its write leaves it
        with (out / RESULTS).open("ab") as f:
            f.write(lines[1][: min(torn, len(lines[1]) - 1)])
    rows = run_sweep(spec, out, workers=1)
    assert len(rows) == 4
    assert _table(read_results(out / RESULTS)) == uninterrupted
    assert (out / RESULTS).read_bytes().startswith(whole)  # the finished rows kept as written
