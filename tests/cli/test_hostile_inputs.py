"""Hostile inputs, round four: no silent wrong result, every check before the work, bounded
sizes and widths, one line for a mistake wherever it is raised (a worker too). (Outputs and
locks: test_hostile_outputs.py; rounds two and three: test_hardening_*.py, test_hostile.py.)"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from test_hardening_sweep import _main, _one_line_2

import sigmapi
from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.errors import ConfigError, DataError, ResourceError

SRC = Path(__file__).resolve().parents[2] / "src"
os.environ.setdefault("MUJOCO_GL", "egl")  # before mujoco is imported: headless rendering


def _cli(*args, env=None):
    return subprocess.run(
        [sys.executable, "-m", "sigmapi.cli", *map(str, args)], capture_output=True, text=True,
        timeout=300, env={**os.environ, "PYTHONPATH": str(SRC), **(env or {})},
    )  # fmt: skip


def _small(**kw):
    return SOMConfig(map_shape=(4,), x_shape=(5,), y_shape=(5,), iterations=300, seed=3,
                     ordering="none", **kw)  # fmt: skip


# ---------------------------------------------------------------- silent wrong results


@pytest.mark.parametrize(
    ("goal", "match"),
    [
        ((float("nan"), 0.5), "got nan"),
        ((0.5, float("inf")), "got inf"),
        ("center", "2 numbers"),
        ((0.5,), "2 numbers"),
        ((0.95, 0.5), r"in \[0.1, 0.9\]"),
    ],
)
def test_robot_dock_refuses_a_goal_it_could_never_dock_at(goal, match):
    gym = pytest.importorskip("gymnasium")
    pytest.importorskip("mujoco")
    with pytest.raises(ConfigError, match=match):
        gym.make("sigmapi/RobotDock-v0", goal=goal)


def test_a_goal_radius_too_wide_for_the_default_goal_names_the_radius():
    gym = pytest.importorskip("gymnasium")
    pytest.importorskip("mujoco")
    with pytest.raises(ConfigError, match="goal_radius must be small enough") as info:
        gym.make("sigmapi/RobotDock-v0", goal_radius=0.39)
    assert "goal must" not in str(info.value)


def _refined_halfway(tmp_path, cfg, views):
    class Stop(Exception):
        pass

    saved = {}

    def cb(model):
        if model.refined_ > 0 and not saved:
            saved["path"] = model.save(tmp_path / "half.npz")
            raise Stop

    with pytest.raises(Stop):
        SigmaPiSOM(cfg).fit(views, callback=cb)
    return sigmapi.load(saved["path"])


def test_a_refinement_on_given_rows_resumes_to_the_same_weights_or_is_refused(tmp_path):
    cfg = _small(refine_rounds=2, refine_pairs=300, backend="reference")
    b = SigmaPiSOM(cfg).sampler.sample(1700, np.random.default_rng(3))
    views = (b.x0, b.y0, b.x1, b.y1)
    full = SigmaPiSOM(cfg).fit(views)
    assert full.refine_rounds_done_ == 2 and full.refined_ == 2 * 1700
    half = _refined_halfway(tmp_path, cfg, views)
    assert 0 < half.refined_ < 2 * 1700 and half.refine_rounds_done_ < 2
    with pytest.raises(DataError, match="pass the same 1,700 rows"):
        half.refine()  # the built-in task's pairs would give other weights
    with pytest.raises(DataError, match="pass the same 1,700 rows"):
        half.refine(tuple(v[:900] for v in views))
    half.refine(views)
    np.testing.assert_array_equal(half.weights_, full.weights_)
    assert half.refine_rounds_done_ == 2


def test_a_refinement_on_a_stream_is_refused_without_its_pairs(tmp_path):
    cfg = _small(refine_rounds=2, refine_pairs=300, backend="reference")
    f = SigmaPiSOM(cfg).sampler.stream(1201, 4, np.random.default_rng(1))
    model = SigmaPiSOM(cfg).fit_stream((f.x, f.y))
    assert model.refine_rounds_done_ == 2  # rounds of 1200 pairs, not of refine_pairs
    back = sigmapi.load(model.save(tmp_path / "s.npz"))
    assert back.refine_rounds_done_ == 2 and back.refine_total == 2 * 1200
    with pytest.raises(DataError, match="consecutive pairs"):
        back.refine(tuple(v[:10] for v in (f.x[:-1], f.y[:-1], f.x[1:], f.y[1:])))


def test_a_sweep_grid_point_train_would_refuse_is_refused_before_any_work(tmp_path, capsys):
    spec = tmp_path / "s.toml"
    spec.write_text('preset = "tiny-1d"\nseeds = [0]\n[set]\niterations = 60\n'
                    "[grid]\nmap_shape = [[9], [3, 3]]\n")  # fmt: skip
    rc, err = _main(capsys, "sweep", spec, "--out", tmp_path / "o", "--quiet")
    _one_line_2(rc, err, "map_shape (3, 3) has 2 axes")
    assert not (tmp_path / "o").exists()


# ---------------------------------------------------------------- checks before the work


def test_reach_refuses_a_block_longer_than_the_episodes(tmp_path, capsys):
    rc, err = _main(capsys, "reach", "--quick", "--episodes", "10", "--final-episodes", "5",
                    "--block", "20", "--out", tmp_path / "o", "--quiet")  # fmt: skip
    _one_line_2(rc, err, "block must be <= episodes")


@pytest.mark.parametrize("gl", ["bogus", "osmesa-not-here"])
def test_a_bad_mujoco_gl_is_one_line_before_the_run(tmp_path, gl):
    pytest.importorskip("mujoco")
    r = _cli("robot", "--quick", "--out", tmp_path / "o", "--quiet", env={"MUJOCO_GL": gl})
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "MUJOCO_GL" in r.stderr and r.stderr.count("\n") == 1, r.stderr
    assert not (tmp_path / "o" / "result.json").exists()


@pytest.mark.parametrize("value", ["0", "-1"])
def test_a_bad_numba_thread_count_is_one_line_even_for_presets(value):
    r = _cli("presets", env={"NUMBA_NUM_THREADS": value})
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert "NUMBA_NUM_THREADS must be an int >= 1" in r.stderr and r.stderr.count("\n") == 1
    lib = subprocess.run([sys.executable, "-c", "import sigmapi"], capture_output=True,
                         text=True, env={**os.environ, "PYTHONPATH": str(SRC),
                                         "NUMBA_NUM_THREADS": value}, timeout=120)  # fmt: skip
    assert "ConfigError: NUMBA_NUM_THREADS" in lib.stderr


# ---------------------------------------------------------------- sizes and memory


def test_the_ordered_start_is_in_the_memory_estimate():
    plain = SigmaPiSOM(SOMConfig(map_shape=(100_000,), x_shape=(9,), y_shape=(9,),
                                 ordering="none"))  # fmt: skip
    ordered = SigmaPiSOM(SOMConfig(map_shape=(100_000,), x_shape=(9,), y_shape=(9,),
                                   ordering="crossview"))  # fmt: skip
    # (units, pairs, d) offsets and (units, pairs) distances, profile and temporaries
    assert ordered.memory_estimate() - plain.memory_estimate() >= 100_000 * 1000 * 8 * 4


def test_a_million_unit_ordered_map_is_refused_before_it_allocates():
    model = SigmaPiSOM(SOMConfig(map_shape=(1_000_000,), x_shape=(9,), y_shape=(9,),
                                 ordering="crossview", iterations=10))  # fmt: skip
    if model.memory_estimate() < 40e9:
        pytest.fail(f"estimate {model.memory_estimate():,} misses the ordered start")
    from sigmapi import _memory

    if (_memory.available() or 0) > model.memory_estimate():
        pytest.skip("this machine holds it")
    with pytest.raises(ResourceError):
        model.fit()


@pytest.mark.parametrize("shape", [(10**20,), (2**20, 2**20)])
def test_absurd_shapes_are_one_error_not_an_overflow(shape):
    with pytest.raises(ConfigError, match="at most"):
        SOMConfig(map_shape=shape, x_shape=(9,), y_shape=(9,))


def test_sampler_stream_with_a_dwell_past_the_frames_allocates_only_the_frames():
    sampler = SigmaPiSOM(_small()).sampler
    frames = sampler.stream(301, 10**12, np.random.default_rng(0))
    assert frames.x.shape == (301, 5) and bool(np.all(frames.z == frames.z[0]))
    with pytest.raises(ResourceError, match="n=1,000,000,000,000"):
        sampler.stream(10**12, 3, np.random.default_rng(0))


def test_fit_on_huge_stride_zero_views_draws_only_the_rows_it_uses():
    # round four refused 10^12 rows (their permutation's memory); round five: a pass that
    # uses 300 of them draws those 300 (sigmapi.model._train.PERMUTED_ROWS), at once
    x = np.lib.stride_tricks.as_strided(np.ones(5), shape=(10**12, 5), strides=(0, 8))
    start = time.perf_counter()
    assert SigmaPiSOM(_small()).fit((x, x, x, x)).t_ == 300
    assert time.perf_counter() - start < 2.0


def test_a_stream_run_too_large_is_refused_before_the_pairs_job(tmp_path, capsys):
    rc, err = _main(capsys, "stream", "--quick", "--set", "iterations=100000000000",
                    "--out", tmp_path / "o", "--quiet")  # fmt: skip
    _one_line_2(rc, err, "one stream job needs about")


def test_robot_recordings_of_the_main_process_are_checked_first(tmp_path, capsys):
    pytest.importorskip("mujoco")
    for flag, word in (
        (["--grid", "300"], "memory"),
        (["--eval-pairs", str(10**11)], "eval_pairs must be an int in [1, 1000000]"),
        (["--grid", "3000"], "grid must be"),
        (["--grid", "0"], "grid must"),
    ):
        rc, err = _main(capsys, "robot", "--quick", *flag, "--out", tmp_path / "o", "--quiet",
                        "--force")  # fmt: skip
        _one_line_2(rc, err, word)


def test_robot_dock_of_a_huge_grid_is_a_resource_error():
    gym = pytest.importorskip("gymnasium")
    pytest.importorskip("mujoco")
    with pytest.raises(ResourceError, match="grid=1000000"):
        gym.make("sigmapi/RobotDock-v0", grid=10**6)


# ---------------------------------------------------------------- widths


@pytest.mark.parametrize(
    "change",
    [
        {"code_width": 1e155},
        {"ordering_sigma": 1e155},
        {"refine_sigma": 1e155},
        {"sigma": [[0.0, 1e155], [1.0, 1.0]]},
    ],
)
def test_every_width_is_bounded(change):
    with pytest.raises(ConfigError, match="1e\\+06"):
        _small(**change)


def test_environment_widths_are_bounded():
    from sigmapi.codes import PopulationCode

    with pytest.raises(ConfigError, match="1e\\+06"):
        PopulationCode((9,), width=1e200)
    from sigmapi.experiments.robot.config import RobotConfig

    with pytest.raises(ConfigError, match="feature_width"):
        RobotConfig().replace(feature_width=1e200)


# ---------------------------------------------------------------- learn_gated


@pytest.mark.parametrize("backend", sigmapi.kernels.BACKENDS)
def test_learn_gated_refuses_sigma_zero_and_ragged_gates_on_every_backend(backend):
    model = SigmaPiSOM(_small(backend=backend)).fit()
    b = model.sampler.sample(10, np.random.default_rng(0))
    views = (b.x0, b.y0, b.x1, b.y1)
    with pytest.raises(ConfigError, match="sigma must be"):
        model.learn_gated(views, np.ones((10, 4)), sigma=0.0)
    with pytest.raises(ConfigError, match="sigma must be"):
        model.learn_gated(views, np.ones((10, 4)), sigma=1e200)
    ragged = [[1.0] * 4] * 9 + [[1.0, 1.0]]
    with pytest.raises(DataError, match="gates must be"):
        model.learn_gated(views, ragged)
    with pytest.raises(DataError, match="gates must"):
        model.learn_gated(views, None)


# ---------------------------------------------------------------- one error path for jobs


def test_a_worker_error_is_raised_as_its_own_class_naming_the_job():
    from sigmapi.executor import job_error

    e = job_error("robot job 0/map", "sigmapi.errors.ResourceError: a model needs 9 TB")
    assert type(e) is ResourceError and str(e) == "robot job 0/map: a model needs 9 TB"
    e = job_error("reward job 1", "numpy._core._exceptions._ArrayMemoryError: Unable to allo")
    assert isinstance(e, ResourceError) and "reward job 1" in str(e)
    e = job_error("stream job x", "ZeroDivisionError: division by zero")
    assert type(e) is RuntimeError and "stream job x failed" in str(e)


def _failing_job(arg):
    raise ConfigError(f"bad setting {arg}")


@pytest.mark.parametrize("workers", [1, 2])
def test_run_all_raises_the_jobs_own_error(workers):
    from sigmapi.executor import Executor
    from sigmapi.experiments.base import run_all

    with pytest.raises(ConfigError, match=r"^toy job [ab]: bad setting [12]$"):
        run_all(_failing_job, [("a", 1), ("b", 2)], executor=Executor(workers=workers),
                per_job=1 << 20, progress=None, desc="toy")  # fmt: skip


def test_an_error_in_an_experiments_job_is_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    from sigmapi.experiments.stream import run as stream

    def boom(self, job, tick):
        raise ResourceError("the job's own mistake")

    monkeypatch.setattr(stream.StreamExperiment, "seed_run", boom)
    rc, err = _main(
        capsys, "stream", "--quick", "--out", tmp_path / "o", "--quiet", "--workers", "1"
    )  # in this process: the patched job runs
    _one_line_2(rc, err, "stream job seed 0 pairs: the job's own mistake")


# ---------------------------------------------------------------- SIGTERM


def test_sigterm_stops_a_parallel_sweep_at_once(tmp_path):
    import signal
    import time

    spec = tmp_path / "s.toml"
    spec.write_text('preset = "tiny-1d"\nseeds = [0, 1]\nn_test = 50\n[set]\n'
                    'iterations = 400000\nbackend = "reference"\n')  # fmt: skip
    out = tmp_path / "o"
    proc = subprocess.Popen(
        [sys.executable, "-m", "sigmapi.cli", "sweep", str(spec), "--out", str(out), "--quiet",
         "--workers", "2"], stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": str(SRC)},
    )  # fmt: skip
    deadline = time.monotonic() + 120
    while not (out / "results.csv").exists() and time.monotonic() < deadline:
        time.sleep(0.2)
    time.sleep(3)  # the workers start and train
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and "terminated" in err, err
    assert time.monotonic() - t0 < 10  # before: the runs in flight ran to their end (140 s)


# ---------------------------------------------------------------- minor


def test_load_onto_an_unknown_backend_blames_the_argument(tmp_path):
    path = SigmaPiSOM(_small()).fit().save(tmp_path / "m.npz")
    with pytest.raises(ConfigError, match="backend must be one of") as info:
        sigmapi.load(path, backend="bogus")
    assert str(path) not in str(info.value)


def test_encode_views_refuses_mismatched_rows():
    model = SigmaPiSOM(_small())
    p = np.full(3, 0.5)
    with pytest.raises(DataError, match="same number of rows"):
        model.encode_views(p, np.full(4, 0.5), p, p)


def test_train_out_naming_a_folder_writes_no_file_named_like_it(tmp_path, capsys):
    target = tmp_path / "newdir"
    rc, err = _main(capsys, "train", "--preset", "tiny-1d", "--set", "iterations=100",
                    "--out", f"{target}/", "--quiet")  # fmt: skip
    _one_line_2(rc, err, "names a folder")
    assert not target.exists()


def test_a_byte_order_mark_in_a_spec_or_config_is_read(tmp_path):
    from sigmapi.config import load_config_file
    from sigmapi.experiments.sweep.run import SweepSpec

    spec = tmp_path / "s.toml"
    spec.write_bytes(b'\xef\xbb\xbfpreset = "tiny-1d"\nseeds = [0]\n')
    assert SweepSpec.read(spec).preset == "tiny-1d"
    cfg = tmp_path / "c.toml"
    cfg.write_bytes(b"\xef\xbb\xbfiterations = 1234\n")
    assert load_config_file(cfg).iterations == 1234


def test_gate_messages_name_parameters_that_exist():
    from sigmapi.agents.gated import Gating
    from sigmapi.rules.gating import reward_gate, surprise

    with pytest.raises(ConfigError, match=r"^scale must be"):
        surprise(1.0, "positive", scale=0.0)
    with pytest.raises(ConfigError, match=r"^surprise_mode must be"):
        reward_gate(1.0, [1.0], surprise_mode="bogus")
    with pytest.raises(ConfigError, match=r"^feedback_mode must be"):
        reward_gate(1.0, [1.0], feedback_mode="bogus")
    with pytest.raises(ConfigError, match=r"^scale must be"):
        Gating(scale=-1.0)
    with pytest.raises(ConfigError, match=r"^sigma must be"):
        Gating(sigma=0.0)


def test_a_fixed_output_name_taken_by_a_folder_is_found_before_the_run(tmp_path, capsys):
    out = tmp_path / "o"
    (out / "compare.txt").mkdir(parents=True)
    rc, err = _main(capsys, "compare", "--quick", "--out", out, "--force", "--quiet")
    _one_line_2(rc, err, "compare.txt", "is a folder")


DOCS_EXT = Path(__file__).resolve().parents[2] / "docs" / "_ext"


@pytest.mark.parametrize(
    "content",
    ['{"bytes": 5}', "[1, 2]", '{"bytes": {"v2": "x"}}', "[" * 100_000 + "]" * 100_000, "{bad"],
)
def test_the_docs_extension_names_the_file_on_hostile_json(tmp_path, monkeypatch, content):
    pytest.importorskip("sphinx")
    monkeypatch.syspath_prepend(str(DOCS_EXT))
    import sigmapi_results
    from sphinx.errors import ExtensionError

    monkeypatch.setattr(sigmapi_results, "RESULTS", tmp_path)
    (tmp_path / "files.json").write_text(content)
    sigmapi_results._load_cached.cache_clear()
    with pytest.raises(ExtensionError, match=r"files\.json"):
        sigmapi_results.TABLES["files"]()


def test_learn_gated_without_views_is_a_data_error():
    model = SigmaPiSOM(_small()).fit()
    with pytest.raises(DataError, match="needs views"):
        model.learn_gated(None, np.ones((1, 4)))


def test_a_table_of_a_million_rows_is_refused_before_parsing(tmp_path):
    import time

    from sigmapi.experiments.sweep.table import read_table

    p = tmp_path / "results.csv"
    p.write_bytes(b"run_id,run_key\n" + b"a,b\n" * 1_000_000)
    t0 = time.process_time()
    with pytest.raises(ConfigError, match="over 200,000 rows"):
        read_table(p)
    assert time.process_time() - t0 < 2.0


def test_sampler_sizes_are_checked_before_allocating():
    sampler = SigmaPiSOM(_small()).sampler
    for draw in (sampler.sample, sampler.sample_z):
        with pytest.raises(ResourceError, match="n=1,000,000,000,000"):
            draw(10**12, np.random.default_rng(0))
