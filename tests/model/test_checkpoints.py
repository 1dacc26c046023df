"""Checkpoints: a run killed with SIGKILL at random moments and resumed ends bit-identical."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import sigmapi
from sigmapi import SigmaPiSOM
from sigmapi.checkpoints import checkpoint_dir, find_resumable, list_checkpoints, write_checkpoint

ITER = 100_000  # long enough (about 8 s here) that five kills land before the run ends
ARGS = [
    "--preset",
    "tiny-1d",
    "--set",
    f"iterations={ITER}",
    "--backend",
    "reference",
    "--seed",
    "4",
]


def _cfg():
    return sigmapi.load_preset("tiny-1d").replace(iterations=ITER, backend="reference", seed=4)


def _train(out, *extra):
    cmd = [sys.executable, "-m", "sigmapi.cli", "train", *ARGS, "--out", str(out), "--quiet"]
    with open(out.with_suffix(".log"), "ab") as log:
        return subprocess.Popen([*cmd, *extra], stdout=log, stderr=log)


@pytest.mark.slow  # 80-160 s of killed and resumed runs: .ci/run's second step runs it
@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX signals")
def test_sigkill_at_random_moments_then_resume_equals_uninterrupted(tmp_path):
    out = tmp_path / "m.npz"
    rng = np.random.default_rng(12345)
    kills = 0
    finished = False
    for _ in range(40):
        proc = _train(out, "--checkpoint-every", "1500", "--resume")
        time.sleep(float(rng.uniform(0.3, 2.0)))
        if proc.poll() is not None:
            assert proc.returncode == 0, out.with_suffix(".log").read_text()
            finished = True
            break
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        kills += 1
        if kills >= 6:
            break
    if not finished:
        proc = _train(out, "--checkpoint-every", "1500", "--resume")
        proc.wait()
        assert proc.returncode == 0, out.with_suffix(".log").read_text()
    assert kills >= 5, f"only {kills} kills landed while training ran"
    assert out.is_file()
    resumed = sigmapi.load(out)
    whole = SigmaPiSOM(_cfg()).fit()
    assert resumed.t_ == ITER
    np.testing.assert_array_equal(resumed.weights_, whole.weights_)
    # the finished run removed its checkpoints and the temp files the kills left
    assert not checkpoint_dir(out).exists()


def test_damaged_newest_checkpoint_falls_back_to_previous(tmp_path):
    folder = tmp_path / "m.npz.ckpt"
    model = SigmaPiSOM(_cfg())
    for _ in range(3):
        model.partial_fit(iterations=1000)
        write_checkpoint(model, folder)
    newest = list_checkpoints(folder)[0][1]
    data = bytearray(newest.read_bytes())
    data[len(data) // 2] ^= 0xFF
    newest.write_bytes(bytes(data))
    found = find_resumable(folder, _cfg())
    assert found.model is not None and found.model.t_ == 2000
    assert len(found.skipped) == 1 and "step-000000003000" in found.skipped[0]


def test_resume_with_another_config_is_refused(tmp_path):
    out = tmp_path / "m.npz"
    model = SigmaPiSOM(_cfg())
    model.partial_fit(iterations=500)
    write_checkpoint(model, checkpoint_dir(out))
    r = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "train", *ARGS[:-1], "5", "--out", str(out),
         "--resume", "--checkpoint-every", "1500"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 2 and "another config" in r.stderr


def test_checkpoint_every_must_be_positive(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "train", *ARGS, "--out", str(tmp_path / "m.npz"),
         "--checkpoint-every", "0"],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert r.returncode == 2 and "--checkpoint-every must be" in r.stderr
