"""Hostile user, round five: no command writes over its own input, no NaN counts as a success,
every size bounded before the work, user text is data. (Rounds two to four:
test_hardening_*.py, test_hostile.py, test_hostile_inputs.py, test_hostile_outputs.py.)"""

from __future__ import annotations

import os
import time

import pytest
from test_hardening_sweep import _main, _one_line_2

from sigmapi import SigmaPiSOM

os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported: headless rendering


def _fast(capsys, *args):
    """``sigmapi ARGS``: ``(rc, stderr)``, asserted to take under 2 s."""
    start = time.perf_counter()
    rc, err = _main(capsys, *args)
    assert time.perf_counter() - start < 2.0, (args, err)
    return rc, err


@pytest.fixture(scope="module")
def model_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("model") / "m.npz"
    SigmaPiSOM(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=200, seed=0).fit().save(path)
    return path


# ---------------------------------------------------------------- no output is an input


def _same_file(tmp_path, model_file, how):
    """``(input, output)``: a copy of the model, and the same file as an output ``how``."""
    src = tmp_path / "x.npz"
    src.write_bytes(model_file.read_bytes())
    if how == "itself":
        return src, src
    out = tmp_path / f"{how}.npz"
    if how == "symlink":
        out.symlink_to(src.name)
    else:
        os.link(src, out)
    return src, out


@pytest.mark.parametrize("how", ["itself", "symlink", "hardlink"])
@pytest.mark.parametrize("force", [(), ("--force",)])
@pytest.mark.parametrize(
    "command",
    [
        ("export", "{inp}", "--format", "onnx", "--out", "{out}"),
        ("figure", "curves", "{inp}", "--out", "{out}", "--quiet"),
        ("train", "--preset", "tiny-1d", "--config", "{inp}", "--out", "{out}", "--quiet"),
    ],
)
def test_no_command_writes_over_its_input(tmp_path, capsys, model_file, how, force, command):
    src, out = _same_file(tmp_path, model_file, how)
    before = src.read_bytes()
    args = [a.format(inp=src, out=out) for a in command]
    rc, err = _fast(capsys, *args, *force)
    _one_line_2(rc, err, "--out", "is the input", "--force or not", "another --out")
    assert src.read_bytes() == before


def test_an_experiment_folder_holding_its_input_is_refused(tmp_path, capsys, model_file):
    out = tmp_path / "o"
    out.mkdir()
    (out / "m.npz").write_bytes(model_file.read_bytes())
    for force in ((), ("--force",)):
        rc, err = _fast(capsys, "physiology", out / "m.npz", "--out", out, "--quiet", *force)
        _one_line_2(rc, err, "--out folder", "holds the input model", "another --out")
    assert sorted(p.name for p in out.iterdir()) == ["m.npz"]
    link = tmp_path / "elsewhere.npz"  # a link outside to the input inside: the same refusal
    link.symlink_to(out / "m.npz")
    rc, err = _fast(capsys, "physiology", link, "--out", out, "--force", "--quiet")
    _one_line_2(rc, err, "holds the input model")


def test_a_different_file_is_still_written(tmp_path, capsys, model_file):
    out = tmp_path / "m.onnx"
    pytest.importorskip("onnx")
    rc, err = _main(capsys, "export", model_file, "--format", "onnx", "--out", out)
    assert rc == 0, err
    assert out.stat().st_size > 0
