"""Hardening of the command line: under signals (SIGTERM while saving, Ctrl-C while importing),
overwrites, finished runs, file modes and help texts. (One-line errors for absurd inputs:
test_cli.py and test_hardening_sweep.py.)"""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_hardening_sweep import TINY

import sigmapi


def _cli(*args, cwd=None, **kw):
    return subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", *args], capture_output=True, text=True,
        timeout=300, cwd=cwd, **kw,
    )  # fmt: skip


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
