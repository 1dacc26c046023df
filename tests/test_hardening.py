"""Issue 15's second hardening round: the model object (pickle, copies, threads), the command
line under signals, overwrites and finished runs. (Files: test_files.py; one-line errors for
absurd inputs: test_cli.py.)"""

from __future__ import annotations

import copy
import os
import pickle
import shutil
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import sigmapi
from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.kernels import BACKENDS

TINY = ["--preset", "tiny-1d", "--set", "iterations=3000", "--backend", "reference", "--quiet"]


def _cli(*args, cwd=None, **kw):
    return subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", *args], capture_output=True, text=True,
        timeout=300, cwd=cwd, **kw,
    )  # fmt: skip


def _cfg(backend="fast"):
    return SOMConfig(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=6000, seed=3,
                     backend=backend, ordering="none")  # fmt: skip


# ---------------------------------------------------------------------------- the model object


@pytest.mark.parametrize("backend", BACKENDS)
def test_pickle_and_deepcopy_carry_state_arrays_and_continue_bit_exact(backend):
    som = SigmaPiSOM(_cfg(backend)).fit(iterations=1500)
    data = pickle.dumps(som)
    assert b"sigmapi.kernels" not in data and b"numba" not in data  # arrays, not modules
    for twin in (pickle.loads(data), copy.deepcopy(som)):
        assert twin.t_ == som.t_ and twin.config == som.config and twin.backend == backend
        assert twin.seed_entropy == som.seed_entropy
        np.testing.assert_array_equal(twin.weights_, som.weights_)
        np.testing.assert_array_equal(
            twin.partial_fit(iterations=700).weights_,
            copy.deepcopy(som).partial_fit(iterations=700).weights_,
        )
    fresh = pickle.loads(pickle.dumps(SigmaPiSOM(_cfg(backend))))
    assert not fresh.is_fitted and fresh.seed_entropy == SigmaPiSOM(_cfg(backend)).seed_entropy


def test_copy_copy_does_not_share_the_weights():
    som = SigmaPiSOM(_cfg()).fit(iterations=1000)
    before = som.weights_.copy()
    twin = copy.copy(som)
    twin.partial_fit(iterations=500)
    assert twin.t_ == 1500 and som.t_ == 1000
    np.testing.assert_array_equal(som.weights_, before)
    assert not np.array_equal(twin.weights_, before)


@pytest.mark.parametrize("backend", BACKENDS)
def test_partial_fit_from_two_threads_loses_no_iteration(backend):
    som = SigmaPiSOM(_cfg(backend)).fit(iterations=0)
    threads = [
        threading.Thread(target=som.partial_fit, kwargs={"iterations": 2500}) for _ in range(2)
    ]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert som.t_ == 5000
    # each call ran whole, one after the other: the same as one run of 5,000 iterations
    np.testing.assert_array_equal(
        som.weights_, SigmaPiSOM(_cfg(backend)).fit(iterations=5000).weights_
    )


# ---------------------------------------------------------------------------- signals


SAVER = """
import signal, sys
from sigmapi import SigmaPiSOM
from sigmapi.cli import _terminate
signal.signal(signal.SIGTERM, _terminate)  # what sigmapi.cli.main installs
som = SigmaPiSOM(map_shape=(30,), x_shape=(120,), y_shape=(120,), backend="reference",
                 seed=0, ordering="none").fit(iterations=1)
print("saving", flush=True)
while True:
    som.save(sys.argv[1])
"""


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX signals")
def test_sigterm_during_save_leaves_no_temp_file(tmp_path):
    rng = np.random.default_rng(7)
    for i in range(5):
        out = tmp_path / f"m{i}.npz"
        proc = subprocess.Popen([sys.executable, "-c", SAVER, str(out)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE)  # fmt: skip
        assert proc.stdout.readline() == b"saving\n"
        time.sleep(float(rng.uniform(0.05, 0.4)))
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=60)
        assert proc.returncode != 0
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []
    assert sigmapi.load(tmp_path / "m0.npz").t_ == 1


def _has_numpy_loaded(pid):
    try:
        return "_multiarray_umath" in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs /proc")
def test_ctrl_c_while_the_command_line_imports_exits_130_quietly():
    for _ in range(3):
        proc = subprocess.Popen([sys.executable, "-m", "sigmapi.cli", "presets"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
        # wait until numpy's core is loaded: sigmapi's imports are under way (they end with
        # gymnasium, matplotlib and the sub-commands' modules, about 0.3 s on this machine)
        deadline = time.monotonic() + 30
        while not _has_numpy_loaded(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.002)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        if proc.returncode == 0:  # the imports had already finished: nothing to test
            continue
        assert proc.returncode == 130, err
        assert b"Traceback" not in err and len(err.decode().strip().splitlines()) == 1, err


# ---------------------------------------------------------------------------- the command line


def test_resume_never_overwrites_another_configs_output(tmp_path):
    out = tmp_path / "m.npz"
    assert _cli("train", *TINY, "--seed", "1", "--out", str(out)).returncode == 0
    before = out.read_bytes()
    r = _cli("train", *TINY, "--seed", "2", "--out", str(out), "--resume")
    assert r.returncode == 2 and "made with another config" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and out.read_bytes() == before
    # the same run, finished: nothing to do, nothing rewritten
    r = _cli("train", *TINY, "--seed", "1", "--out", str(out), "--resume")
    assert r.returncode == 0 and "complete" in r.stderr and out.read_bytes() == before
    out.write_text("not a model")
    r = _cli("train", *TINY, "--seed", "2", "--out", str(out), "--resume")
    assert r.returncode == 2 and "--force" in r.stderr
    r = _cli("train", *TINY, "--seed", "2", "--out", str(out), "--resume", "--force")
    assert r.returncode == 0 and sigmapi.load(out).config.seed == 2


def test_finished_runs_remove_their_checkpoints_unless_asked(tmp_path):
    out = tmp_path / "m.npz"
    args = [*TINY, "--checkpoint-every", "1000", "--out", str(out)]
    assert _cli("train", *args).returncode == 0
    assert out.is_file() and not (tmp_path / "m.npz.ckpt").exists()
    assert _cli("train", *args, "--force", "--keep-checkpoints").returncode == 0
    assert sorted(p.name for p in (tmp_path / "m.npz.ckpt").iterdir()) == [
        "step-000000001000.npz", "step-000000002000.npz",
    ]  # fmt: skip


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600)])
def test_cli_files_follow_the_umask_and_force_keeps_the_mode(tmp_path, umask, mode):
    out = tmp_path / "m.npz"

    def child():
        os.umask(umask)

    r = _cli("train", *TINY, "--out", str(out), "--compress", preexec_fn=child)
    assert r.returncode == 0, r.stderr
    assert stat.S_IMODE(out.stat().st_mode) == mode
    out.chmod(0o644)
    assert _cli("train", *TINY, "--out", str(out), "--force", preexec_fn=child).returncode == 0
    assert stat.S_IMODE(out.stat().st_mode) == 0o644


def test_train_help_names_the_default_run():
    r = _cli("train", "--help")
    assert "300,000 iterations" in r.stdout and "paper-1d" in r.stdout


def test_every_subcommand_help_opens_with_a_description():
    from sigmapi.cli import build_parser

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name, parser in sub.choices.items():
        assert parser.description and len(parser.description) > 10, name


# ---------------------------------------------------------------------------- round three
# issue 22: a sweep never reports another spec's results or deletes yours; every size bounded;
# everything checkable is checked before any work; one line and exit 2, never a traceback

SPEC3 = """
preset = "tiny-1d"
seeds = [0]
n_test = 50
[set]
iterations = 60
backend = "reference"
[grid]
code_width = [0.5, 1.0]
"""


def _main(capsys, *args):
    """``sigmapi ARGS`` in this process: ``(rc, stderr)``; argparse's exits count too."""
    from sigmapi.cli import main

    try:
        rc = main([str(a) for a in args])
    except SystemExit as exc:
        rc = exc.code
    return rc, capsys.readouterr().err


def _one_line_2(rc, err, *words):
    assert rc == 2, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, err


def _spec(tmp_path, text=SPEC3, name="spec.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    "change",
    [
        ("n_test = 50", "n_test = 60"),  # evaluation settings
        ("iterations = 60", "iterations = 80"),  # [set]
        ('preset = "tiny-1d"', 'preset = "paper-1d"'),  # another preset
        ("code_width = [0.5, 1.0]", "code_width = [0.5, 0.75]"),  # another grid
    ],
)
def test_sweep_refuses_a_table_of_another_spec_and_leaves_it_as_it_is(
    tmp_path, capsys, swept, change
):
    out = tmp_path / "o"
    shutil.copytree(swept, out)
    table = (out / "results.csv").read_bytes()
    other = _spec(tmp_path, SPEC3.replace(*change), "other.toml")
    rc, err = _main(capsys, "sweep", other, "--out", out, "--quiet")
    _one_line_2(rc, err, "another spec", "--add", "new --out")
    assert (out / "results.csv").read_bytes() == table


@pytest.fixture(scope="module")
def swept(tmp_path_factory):
    """A folder holding the finished sweep of :data:`SPEC3`."""
    from sigmapi.cli import main

    root = tmp_path_factory.mktemp("swept")
    assert main(["sweep", str(_spec(root)), "--out", str(root / "o"), "--quiet"]) == 0
    return root / "o"


def test_sweep_add_keeps_the_other_specs_rows_and_reports_only_its_own(tmp_path, capsys, swept):
    out = tmp_path / "o"
    shutil.copytree(swept, out)
    table = (out / "results.csv").read_bytes()
    # the same spec again: everything finished already, nothing rewritten
    rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out)
    assert rc == 0 and "2 finished already, 0 to run" in err
    assert (out / "results.csv").read_bytes() == table
    other = _spec(tmp_path, SPEC3.replace("seeds = [0]", "seeds = [1]"), "other.toml")
    rc, err = _main(capsys, "sweep", other, "--out", out, "--quiet", "--add", "--json")
    assert rc == 0, err
    assert (out / "results.csv").read_bytes().startswith(table)  # appended, not rewritten
    import json

    result = json.loads((out / "result.json").read_text())
    assert {r["seed"] for r in result["rows"]} == {1} and result["runs"] == 2


@pytest.mark.parametrize(
    "content",
    [
        b"name,score\nalice,3\n",  # an unrelated table
        os.urandom(4000),  # random bytes
        b"",  # empty
    ],
)
def test_sweep_never_replaces_a_file_that_is_no_table_of_its_own(tmp_path, capsys, content):
    out = tmp_path / "o"
    out.mkdir()
    (out / "results.csv").write_bytes(content)
    rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")
    _one_line_2(rc, err, "results.csv")
    assert (out / "results.csv").read_bytes() == content
    assert not (out / "sweep.png").exists()


def test_a_damaged_table_on_resume_is_one_line_before_anything_is_written(tmp_path, capsys, swept):
    out = tmp_path / "o"
    shutil.copytree(swept, out)
    good = (out / "results.csv").read_text()
    header, first, *_ = good.splitlines(keepends=True)
    cols = header.strip().split(",")
    emptied = first.split(",")
    emptied[cols.index("order_r2") + 1] = ""  # run_id holds a comma: one field more before
    for damaged in (
        header + first.replace('"{', '"' + "x" * 140_000 + "{", 1),  # a 140 kB field
        header + ",".join(emptied),  # an ok row without its metric
        header + first + "not,a,row\n",  # a short row
        header + first.replace(",ok,", ",maybe,"),  # an unknown status
    ):
        (out / "results.csv").write_text(damaged)
        png = (out / "sweep.png").stat().st_mtime_ns
        rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")
        _one_line_2(rc, err, "damaged")
        assert (out / "results.csv").read_text() == damaged
        assert (out / "sweep.png").stat().st_mtime_ns == png


def test_a_torn_last_row_is_dropped_and_run_again(tmp_path, capsys, swept):
    out = tmp_path / "o"
    shutil.copytree(swept, out)
    full = (out / "results.csv").read_text()
    lines = full.splitlines(keepends=True)
    (out / "results.csv").write_text("".join(lines[:-1]) + lines[-1][:25])  # killed mid-write
    rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out)
    assert rc == 0 and "1 finished already, 1 to run" in err, err
    from sigmapi.experiments.sweep.run import read_results

    rows = read_results(out / "results.csv")
    assert len(rows) == 2 and all(r["status"] == "ok" for r in rows)
    assert len((out / "results.csv").read_text().splitlines()) == 3


def test_grid_values_are_resolved_and_named_once():
    from sigmapi.experiments.sweep.run import SweepSpec

    a = SweepSpec.from_toml(SPEC3.replace("[0.5, 1.0]", "[0.5, 1, 1.0, 0.5]"))
    b = SweepSpec.from_toml(SPEC3)
    assert a.grid == b.grid == {"code_width": [0.5, 1.0]}
    assert [r.run_id for r in a.runs()] == [r.run_id for r in b.runs()]
    assert [r.run_key for r in a.runs()] == [r.run_key for r in b.runs()]
    assert len({r.run_key for r in b.runs()}) == 2


def test_a_million_run_spec_is_refused_at_once_in_little_memory():
    import tracemalloc

    from sigmapi.errors import ConfigError
    from sigmapi.experiments.sweep.run import SweepSpec

    grid = "\n".join(f"{k} = {v}" for k, v in {
        "iterations": list(range(1000, 1032)), "code_width": [0.5 + i / 100 for i in range(32)],
        "map_shape": [[i] for i in range(3, 35)], "eps": [0.01 + i / 1000 for i in range(32)],
    }.items())  # fmt: skip
    text = f'preset = "tiny-1d"\nseeds = [0]\n[grid]\n{grid}\n'
    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=r"1,048,576 runs.*split it"):
        SweepSpec.from_toml(text)
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert seconds < 2 and peak < 200 << 20


def test_sweep_checks_before_any_run(tmp_path, capsys):
    spec = _spec(tmp_path)
    rc, err = _main(capsys, "sweep", spec, "--out", tmp_path / "a", "--metric", "order_r3")
    _one_line_2(rc, err, "metric")
    assert not (tmp_path / "a" / "results.csv").exists()
    (tmp_path / "b" / "results.csv").mkdir(parents=True)  # the table is a folder
    rc, err = _main(capsys, "sweep", spec, "--out", tmp_path / "b", "--quiet")
    _one_line_2(rc, err, "not a file")
    (tmp_path / "c" / "result.json").mkdir(parents=True)  # what is written after the runs
    rc, err = _main(capsys, "sweep", spec, "--out", tmp_path / "c", "--quiet")
    _one_line_2(rc, err, "result.json")
    assert not (tmp_path / "c" / "results.csv").exists()
    bad = tmp_path / "latin1.toml"
    bad.write_bytes(SPEC3.encode() + b"# caf\xe9\n")
    _one_line_2(*_main(capsys, "sweep", bad, "--out", tmp_path / "d"), "UTF-8")


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes anywhere")
def test_a_read_only_out_folder_is_refused_before_any_run(tmp_path, capsys):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o555)
    try:
        rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")
    finally:
        out.chmod(0o755)
    _one_line_2(rc, err, "cannot write")


def _holder(*paths):
    """Another process holding the locks of ``paths`` (as a running command does)."""
    code = ("import contextlib, sys, time; from sigmapi._lock import output_lock\n"
            "with contextlib.ExitStack() as s:\n"
            " [s.enter_context(output_lock(p, 'x')) for p in sys.argv[1:]]\n"
            " print('held', flush=True); time.sleep(60)")  # fmt: skip
    proc = subprocess.Popen([sys.executable, "-c", code, *map(str, paths)],
                            stdout=subprocess.PIPE, text=True)  # fmt: skip
    assert proc.stdout.readline().strip() == "held"
    proc.stdout.close()
    return proc


def test_a_busy_out_is_refused_in_one_line(tmp_path, capsys):
    from sigmapi._lock import LOCK_NAME

    out, model = tmp_path / "o", tmp_path / "m.npz"
    out.mkdir()
    spec = _spec(tmp_path)
    holder = _holder(out, model)
    try:
        rc, err = _main(capsys, "sweep", spec, "--out", out, "--quiet")
        _one_line_2(rc, err, "in use by another sigmapi command", f"pid {holder.pid}")
        assert not (out / "results.csv").exists()
        rc, err = _main(capsys, "compare", "--quick", "--out", out, "--force", "--quiet")
        _one_line_2(rc, err, "in use")
        rc, err = _main(capsys, "train", *TINY, "--out", model)  # train --out too
        _one_line_2(rc, err, "in use")
        assert not model.exists()
    finally:
        holder.kill()
        holder.wait()
    # the holder's death frees them; a finished command leaves no lock file
    assert _main(capsys, "sweep", spec, "--out", out, "--quiet")[0] == 0
    assert not (out / LOCK_NAME).exists()


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="checks /proc")
def test_pool_workers_die_with_a_killed_parent(tmp_path):
    code = (
        "import multiprocessing, sys, threading, time\n"
        "from sigmapi.executor import run_jobs\n"
        "jobs = [(str(i), 120) for i in range(2)]\n"
        "threading.Thread(target=lambda: list(run_jobs(time.sleep, jobs, workers=2)),"
        " daemon=True).start()\n"
        "while len(multiprocessing.active_children()) < 2: time.sleep(0.05)\n"
        "time.sleep(0.5)\n"
        "print(' '.join(str(p.pid) for p in multiprocessing.active_children()), flush=True)\n"
        "time.sleep(120)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    pids = [int(p) for p in proc.stdout.readline().split()]
    proc.stdout.close()
    assert pids, "no workers started"
    proc.kill()
    proc.wait()

    def alive(pid):
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return False
        return state not in ("Z", "X")

    deadline = time.monotonic() + 10
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(p) for p in pids), "a worker outlived its parent"


@pytest.mark.parametrize(
    "address",
    ["garbage!!", "tcp://", "http://127.0.0.1:80", "ucx://127.0.0.1:8786",
     "tcp://127.0.0.1:99999", "tcp://:8786", "tcp://127.0.0.1:port"],
)  # fmt: skip
def test_a_malformed_address_is_one_line(tmp_path, capsys, address):
    rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", tmp_path / "o",
                    "--engine", "dask", "--address", address)  # fmt: skip
    _one_line_2(rc, err, "tcp://HOST:PORT")
    assert not (tmp_path / "o" / "results.csv").exists()


@pytest.mark.parametrize("greeting", [b"HTTP/1.1 400 Bad Request\r\n\r\n" * 4, None])
def test_a_listener_that_is_no_dask_scheduler_is_refused(tmp_path, capsys, greeting):
    import socket

    from sigmapi.errors import ConfigError
    from sigmapi.executor import probe_scheduler

    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve():
        conn, _ = server.accept()
        if greeting:
            conn.sendall(greeting)
        time.sleep(2)
        conn.close()

    threading.Thread(target=serve, daemon=True).start()
    try:
        t0 = time.perf_counter()
        with pytest.raises(ConfigError, match="Dask scheduler"):
            probe_scheduler(f"tcp://127.0.0.1:{port}", timeout=0.5)
        assert time.perf_counter() - t0 < 1.5
    finally:
        server.close()


def test_budgets_and_set_values_are_checked_in_one_line(tmp_path, capsys):
    spec = _spec(tmp_path)
    for budget in ("nan", "inf", "-1", "1e400"):
        rc, err = _main(capsys, "sweep", spec, "--out", tmp_path / "o", "--memory-budget", budget)
        _one_line_2(rc, err, "--memory-budget")
    rc, err = _main(capsys, "train", *TINY, "--out", tmp_path / "m.npz",
                    "--set", "iterations=50\nseed=3")  # fmt: skip
    _one_line_2(rc, err, "newline")
    huge = "iterations=" + "9" * 70_000
    rc, err = _main(capsys, "train", *TINY, "--out", tmp_path / "m.npz", "--set", huge)
    _one_line_2(rc, err, "at most")
    assert len(err) < 400
    rc, err = _main(capsys, "compare", "--quick", "--set", "iterations=5\nx=1", "--quiet")
    _one_line_2(rc, err, "newline")


@pytest.mark.parametrize(
    "args",
    [
        ("compare", "--quick", "--train-pairs", str(10**11)),
        ("compare", "--quick", "--n-test", str(10**13)),
        ("chain", "--train-pairs", str(10**11)),
        ("chain", "--n-test", str(10**13)),
        ("reach", "--episodes", str(10**12)),
    ],
)
def test_user_given_sizes_go_through_the_memory_check(capsys, args):
    rc, err = _main(capsys, *args, "--quiet")
    _one_line_2(rc, err, "memory", "available")


def test_a_huge_world_is_refused_by_the_memory_check():
    import gymnasium

    from sigmapi.errors import ResourceError

    with pytest.raises(ResourceError, match="grid=100000"):
        gymnasium.make("sigmapi/GazeReach-v0", grid=100000)


@pytest.mark.parametrize("ordering", ["none", "crossview"])
@pytest.mark.parametrize("which", [(0, 1), (2, 3)])
def test_views_scaled_by_1e300_are_a_data_error(ordering, which):
    from sigmapi.errors import DataError

    rng = np.random.default_rng(0)
    views = [rng.random((20, 5)) for _ in range(4)]
    for i in which:
        views[i] = views[i] * 1e300
    som = SigmaPiSOM(_cfg("reference").replace(ordering=ordering, iterations=50))
    with pytest.raises(DataError, match="scale your codes"):
        som.fit(tuple(views))


def test_empty_and_ragged_views_are_data_errors():
    from sigmapi.errors import DataError

    som = SigmaPiSOM(_cfg("reference"))
    with pytest.raises(DataError, match="px0 holds no positions"):
        som.encode_views([], [], [], [])
    with pytest.raises(DataError, match="rectangular"):
        som.encode_views([[0.1], [0.2, 0.3]], [0.1], [0.1], [0.1])
    with pytest.raises(DataError, match="rectangular"):
        som.fit(([[0.1] * 5, [0.2] * 4], [[0.1] * 5], [[0.1] * 5], [[0.1] * 5]))


def test_views_repeated_by_stride_0_are_checked_at_the_cost_of_their_data():
    from sigmapi.errors import DataError
    from sigmapi.model.views import check_views

    row = np.float32([0.1, 0.2, 0.3, 0.4, 0.5])
    big = np.broadcast_to(row, (10**12, 5))
    t0 = time.perf_counter()
    views = check_views((big,) * 4, (5,), (5,))
    assert time.perf_counter() - t0 < 1 and views[0].shape == (10**12, 5)
    assert views[0].dtype == np.float64 and 0 in views[0].strides  # no (B, n) copy
    bad = np.broadcast_to(np.float32([0.1, np.nan, 0.3, 0.4, 0.5]), (10**12, 5))
    with pytest.raises(DataError, match="finite"):
        check_views((big, big, bad, big), (5,), (5,))
