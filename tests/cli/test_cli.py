"""The command line, run as a user would run it (subprocess)."""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys

import pytest

from sigmapi import SigmaPiSOM

TINY = ["--preset", "tiny-1d", "--set", "iterations=2000", "--backend", "reference"]


def run(*args: str, cwd=None) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", *args], capture_output=True, text=True, cwd=cwd,
        timeout=300,
    )  # fmt: skip


def test_train_then_evaluate_json(tmp_path):
    out = tmp_path / "m.npz"
    r = run("train", *TINY, "--seed", "3", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert out.is_file()
    r = run("evaluate", str(out), "--json", "--n-test", "500")
    assert r.returncode == 0, r.stderr
    metrics = json.loads(r.stdout)
    for key in ("view_consistency", "view_within_one", "z_error", "order_r2", "usage"):
        assert isinstance(metrics[key], float)
    assert 0 <= metrics["view_consistency"] <= metrics["view_within_one"] <= 1


HEAVY = ("numba", "matplotlib", "sklearn", "mujoco", "dask")
"""What the command line must not import to list its commands or say its version."""


def test_help_version_and_presets_import_nothing_heavy_and_work_without_numba():
    code = (
        "import sys\n"
        "from sigmapi.cli import main\n"
        "for argv in (['--version'], ['--help'], ['presets']):\n"
        "    try:\n"
        "        main(argv)\n"
        "    except SystemExit as exc:\n"
        "        assert exc.code == 0, (argv, exc.code)\n"
        f"    print('imported:', argv[0], sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    lines = [line for line in r.stdout.splitlines() if line.startswith("imported:")]
    assert lines == [f"imported: {a} []" for a in ("--version", "--help", "presets")], r.stdout
    no_numba = "import sys; sys.modules['numba'] = None; from sigmapi.cli import main; "
    for argv in (["--help"], ["presets"], ["reach", "--help"]):
        r = subprocess.run([sys.executable, "-c", no_numba + f"sys.exit(main({argv!r}))"],
                           capture_output=True, text=True, timeout=120)  # fmt: skip
        assert r.returncode == 0, (argv, r.stderr)
        assert "usage: sigmapi" in r.stdout or "paper-1d" in r.stdout, argv


def test_presets_lists_paper_1d():
    r = run("presets")
    assert r.returncode == 0 and "paper-1d" in r.stdout


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["train", "--preset", "nope", "--out", "x.npz"], "unknown preset 'nope'"),
        (["train", *TINY, "--set", "iterations=-5", "--out", "x.npz"], "iterations must be"),
        (["train", *TINY, "--set", "color=red", "--out", "x.npz"], "unknown config key 'color'"),
        (["train", *TINY, "--set", "novalue", "--out", "x.npz"], "must be KEY=VALUE"),
        (["train", *TINY, "--set", "iterations", "5000", "--out", "x.npz"],
         "--set takes KEY=VALUE as one word, got --set iterations 5000; write --set "
         "iterations=5000"),
        (["compare", "--quick", "--set", "iterations", "5000"], "write --set iterations=5000"),
        (["train", *TINY, "--set", "map_shape=4x4", "--out", "x.npz"],
         "--set: map_shape (4, 4) has 2 axes, but the task is 1-D (x_shape (9,)"),
        (["train", *TINY, "--config", "c2.toml", "--out", "x.npz"],
         "--config: map_shape (3, 3) has 2 axes, but the task is 1-D"),
        (["train", *TINY, "--config", "missing.toml", "--out", "x.npz"], "does not exist"),
        (["train", *TINY, "--out", "no/such/dir/x.npz"], "does not exist"),
        (["evaluate", "missing.npz"], "does not exist"),
        (["evaluate", "bad.npz"], "not a sigmapi model file"),
        (["train"], "required"),
        (["train", *TINY, "--out", "/proc/sigmapi-test.npz"], "cannot access"),
        (["frobnicate"], "invalid choice"),
        (["train", *TINY, "--out", "fifo", "--force"], "not a regular file"),
        # absurd sizes and values (issue 15): refused before anything is allocated or trained
        (["train", *TINY, "--set", "map_shape=[1000,1000]", "--set", "x_shape=[200,200]",
          "--set", "y_shape=[200,200]", "--out", "x.npz"], "PB of memory"),
        (["train", *TINY, "--set", "init_scale=1e308", "--out", "x.npz"], "init_scale must be"),
        (["train", *TINY, "--set", "code_width=0.01", "--out", "x.npz"], "code_width must be"),
        (["train", *TINY, "--set", "extra={d=1979-05-27}", "--out", "x.npz"], "as strings"),
        (["evaluate", "good.npz", "--n-test", "10000000000"], "needs about"),
        (["figure", "fig8", "good.npz", "--out", "f.png", "--seed", "-1"], "--seed must be"),
        (["reach", "--grid", "300"], "needs about"),
        (["reproduce", "--quick", "--dpi", "5", "--out", "r"], "dpi must be an int in [20,"),
        (["reproduce", "--quick", "--seeds", "2", "2"], "seeds must be distinct, got [2, 2]"),
        (["reproduce", "--quick", "--models", "some"], "invalid choice: 'some'"),
        (["chain", "--code", "spikes"], "invalid choice: 'spikes'"),
        (["chain", "--out", "bad.npz"], "is a file; give a folder"),
        (["sweep", "missing.toml", "--out", "o"], "does not exist"),
        (["sweep", "s.toml", "--out", "o", "--address", "tcp://h:1"], "address names a Dask"),
        (["figure", "net", "good.npz", "--out", "f.png", "--dpi", "5"], "--dpi must be"),
    ],
)  # fmt: skip
def test_user_mistakes_exit_2_with_one_line(tmp_path, args, needle):
    (tmp_path / "bad.npz").write_text("not a model")
    (tmp_path / "s.toml").write_text('preset = "tiny-1d"\n')
    (tmp_path / "c2.toml").write_text("map_shape = [3, 3]\n")
    os.mkfifo(tmp_path / "fifo")
    if "good.npz" in args:
        small = SigmaPiSOM(map_shape=(3,), x_shape=(4,), y_shape=(4,), backend="reference")
        small.fit(iterations=20).save(tmp_path / "good.npz")
    r = run(*args, cwd=tmp_path)
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, r.stderr
    assert needle in lines[0]
    assert "Traceback" not in r.stderr


def test_existing_output_needs_force(tmp_path):
    out = tmp_path / "m.npz"
    out.write_text("keep me")
    r = run("train", *TINY, "--out", str(out))
    assert r.returncode == 2 and "--force" in r.stderr
    assert out.read_text() == "keep me"


def test_config_file_overrides_preset(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("iterations = 1500\nmap_shape = [5]\n")
    out = tmp_path / "m.npz"
    r = run("train", *TINY[:2], "--config", str(cfg), "--backend", "reference", "--out", str(out))
    assert r.returncode == 0, r.stderr
    import sigmapi

    m = sigmapi.load(out)
    assert m.t_ == 1500 and m.map_shape == (5,)


def test_train_warns_in_one_line_when_the_map_looks_folded(tmp_path):
    # tiny-1d seed 7 with the paper's start folds (order R^2 0.02) without starving a unit;
    # the default ordering procedure orders the same seed and gives no warning
    bad = run("train", "--preset", "tiny-1d", "--seed", "7", "--set", 'ordering="none"',
              "--out", str(tmp_path / "bad.npz"))  # fmt: skip
    assert bad.returncode == 0, bad.stderr
    warning = [ln for ln in bad.stderr.splitlines() if "looks folded" in ln]
    assert len(warning) == 1 and "units >= 3 apart" in warning[0]
    assert 'ordering="crossview"' in warning[0]
    good = run("train", "--preset", "tiny-1d", "--seed", "7", "--out", str(tmp_path / "g.npz"))
    assert good.returncode == 0 and "looks folded" not in good.stderr


@pytest.mark.parametrize("command", ["reproduce", "reach", "sweep"])
def test_workers_must_be_positive_one_line_exit_2(command, tmp_path):
    spec = [str(tmp_path / "spec.toml"), "--out", str(tmp_path / "o")]
    extra = spec if command == "sweep" else []
    r = run(command, *extra, "--workers", "0")
    assert r.returncode == 2
    assert r.stderr.strip().endswith("argument --workers: must be a positive int, got '0'")
    assert r.stderr.count("\n") == 1


def test_set_takes_a_grid_as_the_options_and_the_errors_write_it():
    from sigmapi.config import apply_overrides, load_preset

    base = load_preset("tiny-1d")
    for text in ("7", "[7]", "(7,)", "( 7 , )"):
        assert apply_overrides(base, [f"map_shape={text}"]).map_shape == (7,), text
    two = load_preset("paper-2d")
    for text in ("6x5", "6X5", "[6, 5]", "(6, 5)"):
        assert apply_overrides(two, [f"map_shape={text}"]).map_shape == (6, 5), text
    assert apply_overrides(base, ["ordering=none"]).ordering == "none"  # text stays text


def _helps() -> dict[str, str]:
    """Every sub-command's ``--help``, as argparse prints it."""
    from sigmapi.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {"": parser.format_help(), **{n: p.format_help() for n, p in sub.choices.items()}}


def test_help_texts_show_no_sphinx_markup_and_no_unmeasured_durations():
    role = re.compile(r":[a-z]+:`|``|`~")
    for name, text in _helps().items():
        assert not role.search(text), (name, role.search(text))
        assert "see --help of the API" not in text, name
        assert "few minutes" not in text and "few seconds" not in text, name


def test_compare_help_shows_the_config_defaults():
    import dataclasses

    from sigmapi.experiments.compare.run import CompareConfig

    text = " ".join(_helps()["compare"].split())
    for f in dataclasses.fields(CompareConfig):
        if isinstance(f.default, int) and not isinstance(f.default, bool):  # bounds, then it
            assert re.search(rf"\((an int in \[\d+, \d+\]; )?default {f.default}\)", text), f.name
        elif isinstance(f.default, str):
            assert f"(default {f.default})" in text, f.name


def test_train_help_states_the_presets_lengths_as_they_are():
    from sigmapi.config import load_preset

    text = " ".join(_helps()["train"].split())
    assert f"paper-1d: the paper's 1-D task, {load_preset('paper-1d').iterations:,} iter" in text
    assert f"({load_preset('tiny-1d').iterations:,} iterations)" in text


def test_train_help_shows_the_bounds_declared_on_the_config_fields(capsys):
    """``sigmapi train --help`` lists each config key with the bounds its field declares: the
    same bounds the one validator checks."""
    import dataclasses

    from sigmapi import SOMConfig
    from sigmapi.cli import main
    from sigmapi.errors import ConfigError

    with pytest.raises(SystemExit):
        main(["train", "--help"])
    out = capsys.readouterr().out
    for f in dataclasses.fields(SOMConfig):
        if "bounds" in f.metadata:
            assert f"  {f.name}" in out and f.metadata["bounds"].describe() in out, f.name
    assert "iterations      an int >= 1" in out and "kernel_tol      a number in [0, 1)" in out
    with pytest.raises(ConfigError, match=r"^iterations must be an int >= 1, got 0; the paper"):
        SOMConfig(iterations=0)
