"""Hostile user, round five: no command writes over its own input, no NaN counts as a success,
every size bounded before the work, user text is data. (Rounds two to four:
test_hardening_*.py, test_hostile.py, test_hostile_inputs.py, test_hostile_outputs.py.)"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import time
import typing

import numpy as np
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


# ---------------------------------------------------------------- every size bounded


def _numeric(hint):
    """Whether a field of type ``hint`` holds numbers (an int, a float, or a tuple of them)."""
    args = [a for a in (typing.get_args(hint) or (hint,)) if a is not type(None)]
    if typing.get_origin(hint) is tuple:
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
    return any(a in (int, float) for a in args)


def _fields():
    from sigmapi.cli.experiment import _parts
    from sigmapi.experiments import REGISTRY

    for name in sorted(REGISTRY):
        for cls in _parts(REGISTRY[name]).values():
            hints = typing.get_type_hints(cls)
            for f in dataclasses.fields(cls):
                if _numeric(hints[f.name]):
                    yield name, cls, f


def test_every_numeric_field_of_every_experiment_has_an_upper_bound_or_says_why():
    unbounded = []
    fields = list(_fields())
    assert len(fields) > 60  # the walk sees the configs' fields (icub and neurons alone: 35)
    for name, cls, f in fields:
        b = f.metadata.get("bounds")
        if b is None or (b.kind in ("int", "number", "ints", "numbers") and b.hi is None):
            if b is None or not b.why:
                unbounded.append(f"{name}: {cls.__name__}.{f.name}")
    assert not unbounded, "no upper bound (declare one, or say why): " + ", ".join(unbounded)


def test_every_declared_bound_is_in_the_help():
    from sigmapi.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    for name, _, f in _fields():
        text = " ".join(sub.choices[name].format_help().split())
        assert " ".join(f.metadata["bounds"].describe().split()) in text, (name, f.name)


@pytest.mark.parametrize(
    ("command", "flag", "value", "name", "bound"),
    [
        ("icub", "--frame-scenes", "100000000", "frame_scenes", "[1, 20000]"),
        ("icub", "--eval-pairs", "100000000000", "eval_pairs", "[1, 100000]"),
        ("icub", "--code-width", "1e300", "code_width", "<= 1e+06"),
        ("icub", "--head-width", "1e300", "head_width", "<= 1e+06"),
        ("icub", "--iterations", "10000000000", "iterations", "[1, 100000000]"),
        ("icub", "--babbles", "10000000000", "babbles", "[50, 1000000]"),
        ("icub", "--epochs", "10000000000", "epochs", "[1, 10000]"),
        ("icub", "--reaches", "10000000000", "reaches", "[1, 100000]"),
        ("icub", "--servo-steps", "10000000000", "servo_steps", "[0, 100]"),
        ("icub", "--train-pairs", "10000000000", "train_pairs", "[1, 1000000]"),
        ("icub", "--map-shape", "100000x100000", "map_shape", "[1, 64]"),
        ("neurons", "--windows-ms", "1000000000", "windows_ms", "[1, 5000]"),
        ("neurons", "--peak-rates", "1000000000", "peak_rates", "[1, 2000]"),
        ("neurons", "--pairs", "10000000000", "pairs", "[0, 10000000]"),
        ("neurons", "--pairs-2d", "10000000000", "pairs_2d", "[0, 10000000]"),
        ("neurons", "--spike-test", "10000000000", "spike_test", "[10, 100000]"),
        ("neurons", "--seeds-2d", "10000000000", "seeds_2d", "[0, 1000]"),
        ("neurons", "--branches", "10000000000", "branches", "[1, 1000]"),
        ("neurons", "--sparse-branches", "10000000000", "sparse_branches", "[1, 10000]"),
        ("neurons", "--pools-compared", "10000000000", "pools_compared", "[1, 1000]"),
        ("neurons", "--basis-stride-2d", "10000000000", "basis_stride_2d", "[1, 100]"),
        ("neurons", "--spiking-branches", "10000000000", "spiking_branches", "[0, 1000]"),
        ("neurons", "--n-test", "10000000000", "n_test", "[100, 1000000]"),
        ("neurons", "--spike-gain", "1e300", "spike_gain", "(0, 100]"),
        ("neurons", "--spike-inhibition", "1e300", "spike_inhibition", "[0, 100]"),
        ("reach", "--episodes", "10000000000", "episodes", "[1, 1000000]"),
        ("reproduce", "--seeds-2d", "10000000000", "seeds_2d", "[1, 1000]"),
        ("stream", "--dwells", "10000000000", "dwells", "[1, 100000]"),
        (
            "compare",
            "--baseline-iterations",
            "10000000000",
            "baseline_iterations",
            "[1, 100000000]",
        ),
    ],
)
def test_every_size_is_refused_before_work_naming_its_bound(
    tmp_path, capsys, command, flag, value, name, bound
):
    rc, err = _fast(capsys, command, f"{flag}={value}", "--out", tmp_path / "o", "--quiet")
    shown = "1e+300" if value == "1e300" else value.split("x")[0]
    _one_line_2(rc, err, f"{name} must be", bound, f"got {shown}")
    assert not (tmp_path / "o").exists()  # refused before the folder is made


def test_a_spiking_run_too_long_for_its_bounds_is_refused_before_work(tmp_path, capsys):
    args = ["--windows-ms=5000", "--peak-rates=2000", "--pool=1000", "--spike-test=100000"]
    rc, err = _fast(capsys, "neurons", *args, "--quiet")
    _one_line_2(rc, err, "windows_ms x peak_rates x pool x spike_test", "at most 1e+10", "fewer")


# ---------------------------------------------------------------- user text is data


@pytest.mark.parametrize("label", ["$\\frac{$", "$x$ and $", "100$ \\alpha"])
def test_a_label_is_plain_text_not_mathtext(tmp_path, capsys, model_file, label):
    out = tmp_path / "net.png"
    rc, err = _main(capsys, "figure", "net", model_file, "--out", out, "--label", label)
    assert rc == 0, err
    assert out.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize(("label", "word"), [("x" * 100_000, "at most 200"), ("a\nb", "one line")])
def test_a_long_or_multiline_label_is_refused_at_once(tmp_path, capsys, model_file, label, word):
    rc, err = _fast(
        capsys, "figure", "net", model_file, "--out", tmp_path / "f.png", "--label", label
    )
    _one_line_2(rc, err, "--label must be", word)
    assert len(err) < 400 and not (tmp_path / "f.png").exists()


def test_curves_of_a_file_claiming_a_huge_history_are_refused_before_replay(
    tmp_path, capsys, model_file
):
    from sigmapi import load

    model = load(model_file)
    model.t_ = 10**12  # what a hostile file may claim
    path = tmp_path / "claims.npz"
    model.save(path)
    rc, err = _fast(capsys, "figure", "curves", path, "--out", tmp_path / "c.png", "--quiet")
    _one_line_2(rc, err, "1,000,000,000,000 iterations", "at most 100,000,000")


# ---------------------------------------------------------------- last round's leftovers


@pytest.mark.parametrize("gl", ["", "glfw"])
@pytest.mark.parametrize("command", [("icub", "--quick"), ("robot", "--quick", "--render=r.gif")])
def test_an_empty_or_displayless_mujoco_gl_is_one_line_before_the_run(tmp_path, gl, command):
    pytest.importorskip("mujoco")
    env = {**os.environ, "MUJOCO_GL": gl, "DISPLAY": "", "PYTHONPATH": os.environ["PYTHONPATH"]}
    start = time.perf_counter()
    r = subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", *command, "--out", "o", "--quiet"],
        capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path,
    )  # fmt: skip
    assert time.perf_counter() - start < 20  # a fresh interpreter imports MuJoCo
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "MUJOCO_GL" in r.stderr and r.stderr.count("\n") == 1, r.stderr
    assert not (tmp_path / "o" / "result.json").exists()


def test_complex_gates_are_refused_not_cut_to_their_real_part():
    from sigmapi.errors import DataError

    model = SigmaPiSOM(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=200, seed=0).fit()
    b = model.sampler.sample(10, np.random.default_rng(0))
    before = model.weights_.copy()
    with pytest.raises(DataError, match=r"gates must be .* real numbers"):
        model.learn_gated((b.x0, b.y0, b.x1, b.y1), np.full((10, 4), 0.5 + 0.5j))
    np.testing.assert_array_equal(model.weights_, before)


@pytest.mark.parametrize(
    ("content", "word"),
    [
        (bytes(range(256)) * 8, "unreadable"),  # bytes of no text, no line end among the first
        (b"\xff\xfe\x00garbage\n", "unreadable"),  # no UTF-8 in its first line
        (b"", "is empty"),
    ],
    ids=["binary", "no-utf8", "empty"],
)
def test_a_garbage_table_is_called_unreadable_not_empty(tmp_path, capsys, content, word):
    from test_hostile_outputs import SPEC

    out = tmp_path / "o"
    out.mkdir()
    (out / "results.csv").write_bytes(content)
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    rc, err = _fast(capsys, "sweep", spec, "--out", out, "--quiet")
    _one_line_2(rc, err, "results.csv", word)
    if content:
        assert "empty" not in err
    assert (out / "results.csv").read_bytes() == content


def test_fit_over_1e8_stride_zero_rows_is_quick():
    x = np.lib.stride_tricks.as_strided(np.ones(5), shape=(10**8, 5), strides=(0, 8))
    model = SigmaPiSOM(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=300, seed=0)
    start = time.perf_counter()
    assert model.fit((x, x, x, x)).t_ == 300  # was 79 s: a permutation of 10^8 rows
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize("path", [b"m.npz", 3, None, ["m.npz"]])
def test_load_of_no_file_name_is_a_config_error(path):
    import sigmapi
    from sigmapi.errors import ConfigError

    with pytest.raises(ConfigError, match="path must be a file name"):
        sigmapi.load(path)


def test_cost_before_fit_or_of_no_batch_is_a_project_error():
    from sigmapi.errors import DataError, NotFittedError

    model = SigmaPiSOM(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=200, seed=0)
    batch = model.sampler.sample(10, np.random.default_rng(0))
    for arg in (batch, None):
        with pytest.raises(NotFittedError, match="not fitted"):
            model.cost(arg)
    model.fit()
    with pytest.raises(DataError, match=r"batch must be a sigmapi\.tasks\.Batch"):
        model.cost(None)
    assert np.isfinite(model.cost(batch))


def test_set_params_inside_a_callback_is_refused_and_works_after():
    from sigmapi.errors import ConfigError

    model = SigmaPiSOM(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=200, seed=0)
    with pytest.raises(ConfigError, match="set_params must not run inside a callback"):
        model.fit(callback=lambda m: m.set_params(map_shape=(6,)))
    assert model.set_params(map_shape=(6,)).fit().map_shape == (6,)
