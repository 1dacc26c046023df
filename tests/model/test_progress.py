"""Progress: bars on a terminal, one line per phase and per finished run in a log."""

from __future__ import annotations

import subprocess
import sys

from sigmapi.progress import counter, each, progress_callback


class _Model:
    def __init__(self) -> None:
        self.t_, self.sigma_ = 0, 1.0


def test_a_log_gets_one_line_per_phase_and_per_finished_run(capsys):
    # capsys: stderr is not a terminal, as in `sigmapi reproduce > log 2>&1`
    callback, bar = progress_callback(3000, "train tiny seed 0")
    model = _Model()
    with bar:
        for t in (1000, 2000, 3000):
            model.t_ = t
            callback(model)
    step, bar = counter(30, "reach", "episodes")
    with bar:
        for phase in ("map", "map", "retina"):
            step(10, phase)
    assert list(each([1, 2], "figures")) == [1, 2]
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("train tiny seed 0: 3,000 of 3,000 it in ")
    assert lines[1:4] == ["reach: map", "reach: retina", lines[3]]
    assert lines[3].startswith("reach: 30 of 30 episodes in ")
    assert lines[4].startswith("figures: 2 of 2 in ") and len(lines) == 5
    callback, bar = progress_callback(10, "quiet", disable=True)
    with bar:
        callback(model)
    assert capsys.readouterr().err == ""


def test_train_into_a_log_says_what_it_did(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", "train", "--preset", "tiny-1d", "--set",
         "iterations=2000", "--backend", "reference", "--out", str(tmp_path / "m.npz")],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert r.stderr.splitlines()[0].startswith("train tiny-1d: 2,000 of 2,000 it in ")
