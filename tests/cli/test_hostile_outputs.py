"""Hostile outputs: nothing a command writes replaces a file it does not own, follows a link,
or is left half written; the output lock never follows a link. (Round four of the hostile
user; rounds two and three: test_hardening_*.py, test_hostile.py.)"""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest
from test_hardening_sweep import SPEC3, _main, _one_line_2

from sigmapi._lock import lock_path, output_lock
from sigmapi._outputs import MARKER, check_file, check_folder, claim_folder, write_file
from sigmapi.errors import ConfigError, UsageError

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported: headless rendering

SPEC = SPEC3.replace("[0.5, 1.0]", "[0.5]")  # one run


def _spec(tmp_path, text=SPEC):
    p = tmp_path / "spec.toml"
    p.write_text(text)
    return p


# ---------------------------------------------------------------- an experiment's folder


@pytest.mark.parametrize(
    "files",
    [
        {"result.json": '{"experiment": "stream", "mine": 1}\n'},  # another experiment's result
        {"result.json": '{"my": "notes"}\n', "sweep.png": "my own picture"},  # a user's files
        {"notes.txt": "keep me"},
    ],
)
def test_sweep_never_replaces_files_it_did_not_write(tmp_path, capsys, files):
    out = tmp_path / "o"
    out.mkdir()
    for name, text in files.items():
        (out / name).write_text(text)
    rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")
    _one_line_2(rc, err, "not empty", "--force")
    for name, text in files.items():
        assert (out / name).read_text() == text
    assert not (out / "results.csv").exists() and not (out / MARKER).exists()


def test_sweep_refuses_a_folder_marked_for_another_experiment_even_with_force(tmp_path, capsys):
    out = tmp_path / "o"
    out.mkdir()
    (out / MARKER).write_text('{"experiment": "stream"}\n')
    (out / "result.json").write_text('{"stream": true}\n')
    for extra in ((), ("--force",)):
        rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet", *extra)
        _one_line_2(rc, err, "'stream'", "another --out")
    assert (out / "result.json").read_text() == '{"stream": true}\n'


def test_sweep_resumes_its_own_marked_folder_and_force_adopts_a_users(tmp_path, capsys):
    out = tmp_path / "o"
    assert _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")[0] == 0
    assert json.loads((out / MARKER).read_text()) == {"experiment": "sweep"}
    assert _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")[0] == 0
    mine = tmp_path / "m"
    mine.mkdir()
    (mine / "sweep.png").write_text("mine")
    assert _main(capsys, "sweep", _spec(tmp_path), "--out", mine, "--quiet", "--force")[0] == 0
    assert (mine / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_the_library_sweep_claims_its_folder_too(tmp_path):
    from sigmapi.experiments.sweep.run import SweepSpec, run_sweep

    out = tmp_path / "o"
    out.mkdir()
    (out / "result.json").write_text("{}")
    with pytest.raises(UsageError, match="not empty"):
        run_sweep(SweepSpec.read(_spec(tmp_path)), out)
    assert (out / "result.json").read_text() == "{}"


def test_another_experiment_refuses_a_sweep_folder(tmp_path, capsys):
    out = tmp_path / "o"
    assert _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")[0] == 0
    before = (out / "result.json").read_bytes()
    rc, err = _main(capsys, "chain", "--out", out, "--force", "--quiet", "--seeds", "0")
    _one_line_2(rc, err, "'sweep'")
    assert (out / "result.json").read_bytes() == before


# ---------------------------------------------------------------- the sweep's table


def test_a_linked_table_is_refused_and_its_target_untouched(tmp_path, capsys):
    target = tmp_path / "elsewhere.csv"
    target.write_text("keep,me\n")
    for i, link in enumerate((os.symlink, os.link)):
        out = tmp_path / f"o{i}"
        out.mkdir()
        link(target, out / "results.csv")
        rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")
        _one_line_2(rc, err, "results.csv")
        assert target.read_text() == "keep,me\n"


def test_two_folders_sharing_one_table_by_hard_link_are_refused(tmp_path, capsys):
    a = tmp_path / "a"
    assert _main(capsys, "sweep", _spec(tmp_path), "--out", a, "--quiet")[0] == 0
    b = tmp_path / "b"
    b.mkdir()
    os.link(a / "results.csv", b / "results.csv")
    before = (a / "results.csv").read_bytes()
    rc, err = _main(capsys, "sweep", _spec(tmp_path), "--out", a, "--quiet")
    _one_line_2(rc, err, "hard links")
    assert (a / "results.csv").read_bytes() == before


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only files")
def test_a_read_only_table_is_refused_before_the_runs(tmp_path, capsys):
    out = tmp_path / "o"
    assert _main(capsys, "sweep", _spec(tmp_path), "--out", out, "--quiet")[0] == 0
    (out / "results.csv").chmod(0o444)
    spec = _spec(tmp_path, SPEC.replace("[0.5]", "[0.5, 1.0]"))
    rc, err = _main(capsys, "sweep", spec, "--out", out, "--quiet", "--add")
    _one_line_2(rc, err, "cannot append")


def test_a_huge_table_is_refused_from_its_size(tmp_path, monkeypatch):
    from sigmapi.experiments.sweep import table as sweep_table

    p = tmp_path / "results.csv"
    p.write_bytes(b"x" * 2000)
    monkeypatch.setattr(sweep_table, "MAX_TABLE", 1000)
    with pytest.raises(ConfigError, match="over the 1,000"):
        sweep_table.read_table(p)


# ---------------------------------------------------------------- the one writer


def test_write_file_never_follows_a_link_and_refuses_without_force(tmp_path):
    target = tmp_path / "victim"
    target.write_text("precious")
    link = tmp_path / "out.gif"
    link.symlink_to(target)
    with pytest.raises(UsageError, match="symbolic link"):
        check_file(link, force=False)
    with pytest.raises(UsageError, match="symbolic link"):
        write_file(link, b"new", force=False)
    write_file(link, b"new", force=True)  # replaces the link itself
    assert target.read_text() == "precious"
    assert not link.is_symlink() and link.read_bytes() == b"new"
    with pytest.raises(UsageError, match="exists; pass --force"):
        check_file(link, force=False)


@pytest.mark.parametrize("name", ["missing/f.gif", "adir", "adir/"])
def test_check_file_refuses_missing_folders_and_folders(tmp_path, name):
    (tmp_path / "adir").mkdir()
    with pytest.raises(UsageError, match=r"does not exist|folder"):
        check_file(str(tmp_path / name), force=True)


def test_a_full_disk_leaves_the_old_file_and_no_temp(tmp_path, monkeypatch):
    p = tmp_path / "f.gif"
    p.write_bytes(b"old")

    def full(fh):
        fh.write(b"par")
        raise OSError(errno.ENOSPC, "No space left on device")

    with pytest.raises(OSError, match="No space"):
        write_file(p, full)
    assert p.read_bytes() == b"old" and sorted(os.listdir(tmp_path)) == ["f.gif"]
    q = tmp_path / "new.gif"
    with pytest.raises(OSError):
        write_file(q, full)
    assert not q.exists()  # no 0-byte file


def test_claim_folder_writes_the_marker_only_into_an_empty_folder(tmp_path):
    claim_folder(tmp_path, "stream", force=False)
    assert json.loads((tmp_path / MARKER).read_text()) == {"experiment": "stream"}
    with pytest.raises(UsageError, match="'stream'"):
        claim_folder(tmp_path, "reward", force=True)
    (tmp_path / MARKER).write_text("garbage")
    with pytest.raises(UsageError, match="not a sigmapi marker"):
        claim_folder(tmp_path, "stream", force=True)


# ---------------------------------------------------------------- robot --render


def _robot(tmp_path, capsys, *extra):
    return _main(capsys, "robot", "--quick", "--out", tmp_path / "r", "--quiet", *extra)


def test_render_over_an_existing_file_or_link_is_refused_before_the_run(tmp_path, capsys):
    pytest.importorskip("mujoco")
    gif = tmp_path / "film.gif"
    gif.write_bytes(b"GIF89a mine")
    rc, err = _robot(tmp_path, capsys, "--render", gif)
    _one_line_2(rc, err, "--render", "exists")
    assert gif.read_bytes() == b"GIF89a mine"
    victim = tmp_path / "victim"
    victim.write_text("precious")
    link = tmp_path / "l.gif"
    link.symlink_to(victim)
    rc, err = _robot(tmp_path, capsys, "--render", link)
    _one_line_2(rc, err, "symbolic link")
    assert victim.read_text() == "precious"
    assert not (tmp_path / "r" / "result.json").exists()


@pytest.mark.parametrize("where", ["nofolder/f.gif", "isdir.gif"])
def test_render_path_problems_are_found_before_the_run(tmp_path, capsys, where):
    pytest.importorskip("mujoco")
    (tmp_path / "isdir.gif").mkdir()
    rc, err = _robot(tmp_path, capsys, "--render", tmp_path / where)
    _one_line_2(rc, err, "--render")


def test_render_without_the_map_state_is_refused():
    from sigmapi.experiments.robot.config import RobotConfig

    with pytest.raises(ConfigError, match="add map to --states"):
        RobotConfig().replace(states=("retina",), render="f.gif")
    with pytest.raises(ConfigError, match="block must be <= episodes"):
        RobotConfig().replace(episodes=10, final_episodes=5, block=50)


# ---------------------------------------------------------------- the lock


def test_a_planted_lock_link_is_refused_and_its_target_untouched(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious data")
    model = tmp_path / "m.npz"
    lock_path(model).symlink_to(victim)
    with pytest.raises(UsageError, match="symbolic link") as info, output_lock(model, "--out"):
        pass
    assert str(lock_path(model)) in str(info.value)
    assert victim.read_text() == "precious data"


def test_train_refuses_a_planted_lock_link(tmp_path, capsys):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious data")
    model = tmp_path / "m.npz"
    lock_path(model).symlink_to(victim)
    rc, err = _main(capsys, "train", "--preset", "tiny-1d", "--set", "iterations=100",
                    "--out", model, "--quiet")  # fmt: skip
    _one_line_2(rc, err, "lock file")
    assert victim.read_text() == "precious data" and not model.exists()


def test_a_fifo_as_lock_is_named_and_nothing_leaks(tmp_path):
    model = tmp_path / "m.npz"
    os.mkfifo(lock_path(model))
    before = len(os.listdir("/proc/self/fd")) if Path("/proc/self/fd").is_dir() else None
    with pytest.raises(UsageError, match="not a regular file") as info, output_lock(model, "x"):
        pass
    assert str(lock_path(model)) in str(info.value)
    if before is not None:
        assert len(os.listdir("/proc/self/fd")) == before


def test_a_full_disk_while_locking_names_the_lock_and_leaves_none(tmp_path, monkeypatch):
    import sigmapi._lock as lk

    real = os.write

    def full(fd, data):
        if data.endswith(b"\n") and data.strip().isdigit():
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd, data)

    monkeypatch.setattr(lk.os, "write", full)
    model = tmp_path / "m.npz"
    with pytest.raises(UsageError, match="No space") as info, output_lock(model, "x"):
        pass
    assert str(lock_path(model)) in str(info.value)
    assert not lock_path(model).exists()


_AS_NOBODY = textwrap.dedent(
    """
    import os, sys
    from sigmapi._lock import lock_path, output_lock  # imported first: nobody may not read them
    from sigmapi.errors import UsageError
    os.setgid(65534); os.setuid(65534)
    folder, victim = sys.argv[1], sys.argv[2]
    lock = lock_path(os.path.join(folder, "m.npz"))
    os.symlink(victim, lock)
    try:
        with output_lock(os.path.join(folder, "m.npz"), "--out"):
            print("LOCKED")
    except UsageError as exc:
        print("REFUSED", exc)
    os.unlink(lock)
    other = os.path.join(folder, "theirs.npz")
    try:
        with output_lock(other, "--out"):
            print("LOCKED-OTHER")
    except UsageError as exc:
        print("REFUSED-OTHER", exc)
    """
)


@pytest.mark.skipif(not hasattr(os, "setuid"), reason="POSIX only")
def test_a_planted_lock_link_as_a_non_root_user_in_a_shared_folder():
    if os.geteuid() != 0:
        pytest.skip("needs root to switch to the user nobody (uid 65534) in a subprocess")
    shared = Path(tempfile.mkdtemp(prefix="sigmapi-shared-", dir="/tmp"))
    try:
        shared.chmod(0o1777)  # a shared folder like /tmp: sticky, everyone writes
        victim = shared / "root-owned.txt"
        victim.write_text("root's data")
        victim.chmod(0o666)  # writable by nobody: only O_NOFOLLOW protects it
        theirs = shared / ".theirs.npz.sigmapi.lock"
        theirs.write_text("")  # a lock file root owns
        theirs.chmod(0o666)
        src = Path(__file__).resolve().parents[2] / "src"
        env = {**os.environ, "PYTHONPATH": str(src)}
        run = subprocess.run([sys.executable, "-c", _AS_NOBODY, str(shared), str(victim)],
                             capture_output=True, text=True, env=env, timeout=120)  # fmt: skip
        if "PermissionError" in run.stderr or "Operation not permitted" in run.stderr:
            pytest.skip(f"cannot switch to uid 65534 here: {run.stderr[-200:]}")
        assert run.returncode == 0, run.stderr
        assert "REFUSED" in run.stdout and "symbolic link" in run.stdout, run.stdout
        assert "LOCKED\n" not in run.stdout
        # another user's lock: refused (by the kernel's protected_regular, or by its owner)
        assert "REFUSED-OTHER" in run.stdout and ".theirs.npz.sigmapi.lock" in run.stdout
        assert victim.read_text() == "root's data"
    finally:
        shutil.rmtree(shared, ignore_errors=True)


def test_an_output_folder_is_checked_once_for_existing_and_taking_files(tmp_path):
    from sigmapi.cli._common import check_output

    missing = tmp_path / "nope" / "x.json"
    for check in (lambda p: check_file(p, force=False), lambda p: check_output(p, False)):
        with pytest.raises(UsageError, match=r"folder '.*nope' of output file .* does not exist"):
            check(missing)
    check_folder(tmp_path / "x.json", "x")  # a folder that takes files passes
    if not Path("/proc").is_dir():
        pytest.skip("no /proc: no folder that refuses files even to root")
    with pytest.raises(UsageError, match=r"cannot write output file .*cannot access its folder"):
        check_output("/proc/sigmapi-test.json", False)
