"""Hardening of a sweep's outputs: it never reports another spec's results or deletes yours; every
size is bounded; everything checkable is checked before any work (out folders, budgets,
--set values, user-given sizes); one line and exit 2, never a traceback."""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
import time

import pytest

TINY = ["--preset", "tiny-1d", "--set", "iterations=3000", "--backend", "reference", "--quiet"]


# ---------------------------------------------------------------------------- round three
# a sweep never reports another spec's results or deletes yours; every size bounded;
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
        random.Random(0).randbytes(4000),  # random bytes (seeded: the same test id in every run)
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
    # round five: each of these sizes has an upper bound now, refused before the estimate
    rc, err = _main(capsys, *args, "--quiet")
    _one_line_2(rc, err, f"{args[-2].lstrip('-').replace('-', '_')} must be an int in [", args[-1])


def test_a_huge_world_is_refused_by_the_memory_check():
    import gymnasium

    from sigmapi.errors import ResourceError

    with pytest.raises(ResourceError, match="grid=100000"):
        gymnasium.make("sigmapi/GazeReach-v0", grid=100000)
