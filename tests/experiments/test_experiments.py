"""The reproduction report and the ``figure`` command, on tiny configs."""

from __future__ import annotations

import html
import importlib
import json
import re
import threading
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Literal

import matplotlib

matplotlib.use("Agg")

import pytest

from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.cli import main
from sigmapi.errors import ConfigError
from sigmapi.experiments import (
    REGISTRY,
    Experiment,
    ReportContext,
    ReproduceOptions,
    Section,
    paper_presets,
    read_result,
    register,
)
from sigmapi.experiments.base import KEY_VALUES
from sigmapi.experiments.reproduce.report_html import linked_files
from sigmapi.experiments.reproduce.results import METRIC_KEYS
from sigmapi.experiments.reproduce.run import QUICK_ITERATIONS, reproduce
from sigmapi.viz.figures import FIGURES

TINY_1D = SOMConfig(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000)
TINY_2D = SOMConfig(map_shape=(3, 3), x_shape=(3, 3), y_shape=(3, 3), code_width=1.0,
                    iterations=1000)  # fmt: skip
REFINED_1D = TINY_1D.replace(refine_rounds=2, refine_pairs=1000)
"""A tiny run with sigmapi's refinement after the training (two rounds)."""
AUTHORS_1D = TINY_1D.replace(ordering="none", iterations=1000)
"""The paper's random start on the same tiny task, shorter: some seeds twist."""


def _options(seeds=(0,), n_test=100, save_models="none", **kw) -> ReproduceOptions:
    return ReproduceOptions(seeds=seeds, progress=False, n_test=n_test, save_models=save_models,
                            **kw)  # fmt: skip


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("report")
    result = reproduce(
        out, _options(seeds=(0, 1, 2), n_test=300, save_models="all", seeds_2d=2),
        presets=[("paper-1d", REFINED_1D), ("paper-1d-authors", AUTHORS_1D),
                 ("tiny-2d", TINY_2D)], sections=(),
    )  # fmt: skip
    return out, result.to_dict()


def test_report_has_every_figure_and_links_only_existing_files(run):
    out, _ = run
    text = (out / "report.html").read_text()
    links = linked_files(text)
    assert links, "the report links no files"
    for f in links:
        assert (out / f).is_file(), f"report links missing file {f}"
        assert not Path(f).is_absolute() and ".." not in Path(f).parts
    for preset in ("paper-1d", "paper-1d-authors", "tiny-2d"):
        for name in FIGURES:
            assert f"{name}-{preset}.png" in links
    assert "metrics.json" in links
    assert "seeds [0, 1, 2] (tiny-2d: the first 2);" in text


def test_metrics_json_holds_runs_curves_and_figure_facts(run):
    out, results = run
    data = json.loads((out / "metrics.json").read_text())
    assert data == json.loads(json.dumps(results))
    res = data["presets"]["paper-1d"]
    assert [r["seed"] for r in res["runs"]] == [0, 1, 2]
    assert set(METRIC_KEYS) <= set(res["mean"]) and set(METRIC_KEYS) <= set(res["median"])
    curve = res["runs"][0]["curve"]
    trained = [t for t, r in zip(curve["t"], curve["refined"], strict=True) if r == 0]
    assert trained[-1] == REFINED_1D.iterations
    assert [r for r in curve["refined"] if r > 0] == [1000, 2000]  # one record per round
    assert "polarity" in res["figures"]["fig8"]
    # the 2-D preset trains the first seeds_2d seeds only
    assert data["presets"]["tiny-2d"]["seeds"] == [0, 1]
    assert (out / "tiny-2d-seed1.npz").is_file() and not (out / "tiny-2d-seed2.npz").exists()
    for run_ in res["runs"]:
        times = [run_[k] for k in ("train_seconds", "refine_seconds", "measure_seconds")]
        assert all(t >= 0 for t in times) and run_["cpu_seconds"] > 0


def test_unrefined_and_refined_maps_both_appear_and_differ(run):
    out, data = run
    res = data["presets"]["paper-1d"]
    for r in res["runs"]:  # the map at the end of the training, evaluated there
        assert r["unrefined"] is not None
        assert r["unrefined"]["view_consistency"] != r["view_consistency"]
    assert res["unrefined"]["median"] != res["median"]
    assert data["presets"]["paper-1d-authors"]["unrefined"] is None  # it does not refine
    text = (out / "report.html").read_text()
    assert "paper-1d<br>before refinement (same runs)" in text
    assert "paper-1d, before refinement" in text  # its rows in the per-seed table
    for stage in (res["median"], res["unrefined"]["median"]):
        assert f"{stage['view_consistency']:.3f} <small>(" in text  # median (worst seed)
    assert "median <small>(worst seed)</small>" in text


def test_the_ceiling_is_computed_drawn_and_tabulated(run):
    out, data = run
    res, authors = data["presets"]["paper-1d"], data["presets"]["paper-1d-authors"]
    ceiling = res["ceiling"]
    assert ceiling["preset"] == "paper-1d" and ceiling["seed"] == res["shown_seed"]
    assert ceiling["rounds"] >= 1 and 0.0 < ceiling["view_consistency"] <= 1.0
    assert authors["ceiling"] == ceiling  # the same task: its twin's ceiling
    facts = res["figures"]["curves"]
    assert facts["ceiling"]["view_consistency"] == ceiling["view_consistency"]
    assert facts["refinement_rounds"] == 2
    text = (out / "report.html").read_text()
    assert "the rule's ceiling<br>fixed point from paper-1d seed" in text
    assert f"<td>{ceiling['view_consistency']:.3f}</td>" in text
    assert "Dash-dot lines: the learning rule's ceiling" in html.unescape(text)


def test_figures_show_the_worst_ordered_seed_and_say_why(run):
    out, data = run
    text = (out / "report.html").read_text()
    for name in ("paper-1d", "paper-1d-authors"):
        res = data["presets"][name]
        r2 = {r["seed"]: r["order_r2"] for r in res["runs"]}
        assert res["shown_seed"] == min(r2, key=lambda s: (r2[s], s))
        assert res["shown_reason"].startswith("the worst-ordered of its 3 seeds")
        assert f"seed {res['shown_seed']}, {res['shown_reason']}" in html.unescape(text)
    authors = data["presets"]["paper-1d-authors"]
    assert "the comparison is about twisting" in authors["shown_reason"]
    twisted = any(r["order_r2"] < 0.95 for r in authors["runs"])
    assert ("twisted (order R²" in authors["shown_reason"]) == twisted


def test_figure_seed_picks_a_twisted_map_of_the_authors_procedure():
    from sigmapi.experiments.reproduce.results import SeedRun
    from sigmapi.experiments.reproduce.run import figure_seed
    from sigmapi.metrics import Metrics

    def seed_run(seed, r2):
        return SeedRun(seed, 1.0, "reference", Metrics(0.5, 0.9, 0.5, r2, 1.0, 100), {})

    runs = [seed_run(0, 0.99), seed_run(1, 0.41), seed_run(2, 0.98), seed_run(3, 0.41)]
    i, why = figure_seed(runs, AUTHORS_1D)
    assert i == 1 and "twisted (order R² 0.410 < 0.95; 2 of 4 seeds twisted)" in why
    assert "the comparison is about twisting" in why
    i, why = figure_seed(runs[::2], REFINED_1D)
    assert i == 1 and "still ordered" in why and "at least as ordered" in why
    i, why = figure_seed(runs[::2], AUTHORS_1D)
    assert i == 1 and "no seed twisted here" in why


def test_each_bullet_is_computed_for_its_own_preset(run):
    out, data = run
    text = html.unescape((out / "report.html").read_text())
    bullets = dict(re.findall(r"<li><b>([^<]+)</b>: (.*?)</li>", text))
    assert set(bullets) == {"paper-1d", "paper-1d-authors", "tiny-2d"}
    assert "then 2 refinement rounds of 1,000 pairs" in bullets["paper-1d"]
    assert "no refinement" in bullets["paper-1d-authors"]
    assert "ordering <code>none</code>" in bullets["paper-1d-authors"]
    for name, line in bullets.items():
        res = data["presets"][name]
        n = len(res["runs"])
        assert f"{res['ordered']} of {n} ordered" in line
        assert f"median view consistency {res['median']['view_consistency']:.3f}" in line


def test_metrics_table_sits_beside_reference_figures(tmp_path):
    out = tmp_path / "r"
    reproduce(out, _options(n_test=200), presets=[("paper-1d", TINY_1D)], sections=())
    text = (out / "report.html").read_text()
    assert "0.870" in text and "0.988" in text and "0.320" in text  # docs/algorithm.md
    assert "floor 0.27" in text
    assert not list(out.glob("*.npz"))


def test_sections_are_added_and_checked(tmp_path):
    def reaching(ctx: ReportContext) -> Section:
        assert ctx.models["tiny-1d"][0].t_ == TINY_1D.iterations
        (ctx.out / "extra.png").write_bytes(b"\x89PNG\r\n\x1a\n")
        return Section("Reaching", "<p>extra</p>", [("extra.png", "a caption")], {"n": 1})

    out = tmp_path / "r"
    result = reproduce(out, _options(), presets=[("tiny-1d", TINY_1D)], sections=[reaching])
    assert result.sections == {"Reaching": {"n": 1}}
    text = (out / "report.html").read_text()
    assert "<h2>Reaching</h2>" in text and "extra.png" in linked_files(text)

    def broken(ctx: ReportContext) -> Section:
        return Section("Broken", figures=[("missing.png", "never written")])

    with pytest.raises(RuntimeError, match=r"missing\.png"):
        reproduce(tmp_path / "r2", _options(), presets=[("tiny-1d", TINY_1D)], sections=[broken])


def test_sections_run_beside_the_figures_and_their_errors_reach_the_caller(tmp_path):
    started, drawn = threading.Event(), []

    def waiting(ctx: ReportContext) -> Section:
        started.set()
        with ctx.drawing:  # the report's figures are drawn holding the same lock
            drawn.append(threading.current_thread() is not threading.main_thread())
        return Section("Waiting")

    def failing(ctx: ReportContext) -> Section:
        raise ConfigError("the section refused")

    result = reproduce(
        tmp_path / "r", _options(), presets=[("tiny-1d", TINY_1D)], sections=[waiting]
    )
    assert started.is_set() and drawn == [True] and "Waiting" in result.sections
    with pytest.raises(ConfigError, match="the section refused"):
        reproduce(tmp_path / "r2", _options(), presets=[("tiny-1d", TINY_1D)], sections=[failing])


MEASURING_FIRST = """
from numba.core.registry import CPUDispatcher
from sigmapi.config import load_preset
from sigmapi.experiments.reproduce.training import _compile_measuring
from sigmapi.kernels import _refining, _rows, fast
cfg = load_preset("paper-2d").replace(map_shape=(3, 3), x_shape=(4, 4), y_shape=(4, 4),
                                      iterations=2000, refine_rounds=1, refine_pairs=500)
_compile_measuring(cfg)
done = sorted(name for mod in (fast, _refining, _rows) for name, f in vars(mod).items()
              if isinstance(f, CPUDispatcher) and f.signatures)
print(" ".join(done))
"""


def test_a_worker_can_compile_the_measuring_half_first_without_the_training():
    # two workers starting at once each compile one half (compile_once's measure_first)
    import subprocess
    import sys

    out = subprocess.run(
        [sys.executable, "-c", MEASURING_FIRST], capture_output=True, text=True, check=True
    ).stdout.split()
    assert "_settle_rows" in out and "_hard_sums" in out and "winners_rows_parallel" in out
    assert "_train" not in out and "_unit_chunk" not in out, out


def test_linked_files_ignores_urls_and_anchors():
    text = (
        "<img src='a.png'><a href=\"b c.json\">x</a><a href='https://x.org/y.png'>"
        "<a href='#top'><img src='a.png'><a href='mailto:me@x.org'>"
    )
    assert linked_files(text) == ["a.png", "b c.json"]


def test_quick_presets_are_short_and_quick_options_small():
    for name, cfg in paper_presets(quick=True):
        assert cfg.iterations <= QUICK_ITERATIONS.get(name, cfg.iterations)
    quick, full = ReproduceOptions(quick=True), ReproduceOptions()
    assert quick.test_size < full.test_size and quick.curve_test < full.curve_test
    with pytest.raises(ValueError, match="save_models must be one of"):
        ReproduceOptions(save_models="some")
    with pytest.raises(ConfigError, match="seeds_2d must be an int"):
        ReproduceOptions(seeds_2d=0)
    opts = ReproduceOptions(seeds=(4, 2, 7), seeds_2d=2)
    assert opts.seeds_of(TINY_1D) == (4, 2, 7) and opts.seeds_of(TINY_2D) == (4, 2)
    assert ReproduceOptions(seeds=(4, 2), seeds_2d=None).seeds_of(TINY_2D) == (4, 2)


def test_figure_command_writes_one_figure(tmp_path, capsys):
    model = SigmaPiSOM(TINY_1D, seed=0).fit()
    path = model.save(tmp_path / "m.npz")
    out = tmp_path / "inv.png"
    assert main(["figure", "invariance", str(path), "--out", str(out)]) == 0
    assert out.read_bytes().startswith(b"\x89PNG")
    assert main(["figure", "curves", str(path), "--out", str(tmp_path / "c.svg"), "--quiet"]) == 0
    assert (tmp_path / "c.svg").stat().st_size > 1000
    assert "differ" not in capsys.readouterr().err  # the replay is the same run


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["figure", "weights", "{tmp}/none.npz", "--out", "{tmp}/w.png"], "does not exist"),
        (["figure", "weights", "{tmp}/m.npz", "--out", "{tmp}/w.txt"], "must end in"),
        (["figure", "weights", "{tmp}/m.npz", "--out", "{tmp}/m.npz"], "is the input model"),
        (["reproduce", "--out", "{tmp}/m.npz"], "is a file"),
        (["reproduce", "--out", "{tmp}", "--seeds", "1", "1"], "distinct"),
    ],
)
def test_user_mistakes_give_one_line_and_exit_2(argv, message, tmp_path, capsys):
    SigmaPiSOM(TINY_1D, seed=0, iterations=1000).fit().save(tmp_path / "m.npz")
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    if argv[0] == "reproduce" and "--seeds" in argv:
        argv.append("--force")
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_unknown_figure_name_is_refused(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["figure", "nope", "m.npz", "--out", "x.png"])
    assert exc.value.code == 2
    assert "invalid choice" in capsys.readouterr().err


# ------------------------------------------------------------------ the protocol (base.py)


@pytest.mark.parametrize(
    ("seeds", "message"),
    [
        ((), "seeds must name at least one seed"),
        ([0, -1], "seeds must be a list of non-negative ints"),
        ([1.5], "seeds must be a list of non-negative ints"),
        ("012", "seeds must be a list of non-negative ints"),
        ([3, 3], "seeds must be distinct, got [3, 3]"),
    ],
)
def test_check_seeds_names_what_is_wrong(seeds, message):
    from sigmapi.experiments import check_seeds

    with pytest.raises(ConfigError, match=re.escape(message)):
        check_seeds(seeds)
    assert check_seeds([4, 0, 2]) == (4, 0, 2)


def test_register_refuses_bad_names_configs_and_taken_names():
    @dataclass(frozen=True)
    class Cfg:
        n: int = 1

    @dataclass
    class Mutable:
        n: int = 1

    class Toy:
        summary, config_type = "a toy", Cfg

        def __init__(self, name, config_type=Cfg):
            self.name, self.config_type = name, config_type

    with pytest.raises(ConfigError, match="experiment name must be lower-case words"):
        register(Toy("Bad Name"))
    with pytest.raises(ConfigError, match="must be a frozen dataclass"):
        register(Toy("toy", Mutable))
    toy = register(Toy("toy-taken"))
    try:
        assert register(toy) is toy  # registering it again is no change
        with pytest.raises(ConfigError, match="'toy-taken' is taken"):
            register(Toy("toy-taken"))
    finally:
        del REGISTRY["toy-taken"]


def test_experiments_are_registered_by_name_and_imported_on_first_use(tmp_path, monkeypatch):
    from sigmapi.experiments import ENTRIES

    for name, target, summary in ENTRIES:  # the line --help shows is the experiment's own
        assert REGISTRY.entries[name].target == target
        assert REGISTRY[name].summary == summary, name
    (tmp_path / "lazy_toy_experiment.py").write_text(
        "from dataclasses import dataclass\n"
        "from sigmapi.experiments import register\n"
        "@dataclass(frozen=True)\n"
        "class Cfg:\n"
        "    n: int = 1\n"
        "class Toy:\n"
        "    name, summary, config_type = 'lazy-toy', 'a toy', Cfg\n"
        "TOY = register(Toy())\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    REGISTRY.add("lazy-toy", "lazy_toy_experiment:TOY", "a toy")
    try:
        assert "lazy-toy" in REGISTRY and REGISTRY.loaded("lazy-toy") is None
        assert "lazy_toy_experiment" not in __import__("sys").modules  # listed, not imported
        toy = REGISTRY["lazy-toy"]
        assert toy.name == "lazy-toy" and REGISTRY.loaded("lazy-toy") is toy
        with pytest.raises(ConfigError, match="'lazy-toy' is taken by lazy_toy_experiment:TOY"):
            REGISTRY.add("lazy-toy", "elsewhere:TOY", "a toy")
        with pytest.raises(ConfigError, match="target of experiment 'x' must be 'module:object'"):
            REGISTRY.add("x", "no colon", "a toy")
    finally:
        del REGISTRY["lazy-toy"]


def test_write_result_is_atomic_json_that_reads_back(tmp_path):
    from sigmapi.experiments import write_result

    class Done:
        def to_dict(self):
            return {"methods": [{"name": "a", "z_error": 0.25}], "seeds": [0, 1]}

    path = write_result(Done(), tmp_path / "new")
    assert path == tmp_path / "new" / "result.json"
    assert read_result(tmp_path / "new") == read_result(path) == Done().to_dict()
    assert not [p for p in path.parent.iterdir() if p != path]  # no temp file left


# ------------------------------------------------------------------ the generated command line


@dataclass(frozen=True)
class ToyConfig:
    """The settings of a toy experiment (:class:`ToyExperiment`)."""

    label: str
    """A positional argument: a field without a default (see :func:`~sigmapi.evaluate`)."""
    scale: float = 1.0
    """A number, ``2.5`` say."""
    shape: tuple[int, ...] = (2, 3)
    """A grid."""
    kind: Literal["a", "b"] = "a"
    """A choice of two."""
    loud: bool = False
    """An on-switch."""
    overrides: tuple[str, ...] = field(default=(), metadata=KEY_VALUES)
    """``key=value`` pairs, one per change."""

    def __post_init__(self) -> None:
        if self.scale <= 0:
            raise ConfigError(f"scale must be a number > 0, got {self.scale}")


@dataclass
class ToyResult:
    config: ToyConfig
    seeds: tuple[int, ...]
    out: str | None

    def to_dict(self):
        return {"config": asdict(self.config), "seeds": list(self.seeds), "out": self.out}

    def table(self):
        return f"toy {self.config.label}: {len(self.seeds)} seeds"

    def figure(self, out_dir):
        path = Path(out_dir) / "toy.png"
        path.write_bytes(b"\x89PNG\r\n\x1a\n")
        return [path]


class ToyExperiment(Experiment[ToyConfig]):
    """A toy experiment that only echoes what it was given."""

    name = "toy-echo"
    summary = "echo the config and the seeds (a test)"
    config_type = ToyConfig
    quick = ToyConfig("quick", scale=0.5)
    seeds = (7, 8)
    quick_seeds = (9,)
    default_out = None

    def execute(self, config, run):
        assert run.executor is not None and run.progress is None  # the CLI gives one; --quiet
        assert run.out is None or run.out.is_dir()
        return ToyResult(config, run.seeds, None if run.out is None else str(run.out))


@pytest.fixture
def toy():
    experiment = register(ToyExperiment())
    yield experiment
    del REGISTRY[experiment.name]


def test_a_registered_experiment_gets_a_sub_command_with_a_flag_per_field(toy, tmp_path, capsys):
    out = tmp_path / "o"
    argv = ["toy-echo", "hello", "--scale", "2.5", "--shape", "4x5", "--kind", "b", "--loud",
            "--set", "a=[1,2]", "--set", "b=3", "--seeds", "3", "1", "--out", str(out),
            "--json", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["config"] == {"label": "hello", "scale": 2.5, "shape": [4, 5], "kind": "b",
                             "loud": True, "overrides": ["a=[1,2]", "b=3"]}  # fmt: skip
    assert got["seeds"] == [3, 1] and got["out"] == str(out)
    assert read_result(out) == got and (out / "toy.png").is_file()


def test_quick_defaults_and_mistakes_of_a_registered_experiment(toy, tmp_path, capsys, monkeypatch):
    assert main(["toy-echo", "x", "--quick", "--out", str(tmp_path / "q"), "--quiet"]) == 0
    assert capsys.readouterr().out.strip() == "toy x: 1 seeds"  # the quick seeds, (9,)
    assert read_result(tmp_path / "q")["config"]["scale"] == 0.5  # the quick config
    monkeypatch.chdir(tmp_path)
    assert main(["toy-echo", "x", "--quiet", "--json"]) == 0  # no --out: nothing written
    got = json.loads(capsys.readouterr().out)
    assert got["seeds"] == [7, 8] and got["out"] is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["q"]
    for argv, message in [
        (["--out", str(tmp_path / "q")], "is not empty; pass --force"),
        (["--scale", "-1", "--out", str(tmp_path / "e")], "scale must be a number > 0"),
        (["--seeds", "1", "1", "--out", str(tmp_path / "e")], "seeds must be distinct"),
    ]:
        assert main(["toy-echo", "x", *argv]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "e").exists()  # refused before anything was made
    with pytest.raises(SystemExit):
        main(["toy-echo", "x", "--kind", "c", "--out", str(tmp_path / "e")])


def test_every_registered_experiment_has_a_sub_command_and_plain_help(toy):
    from sigmapi.cli import build_parser
    from sigmapi.cli._common import field_docs

    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert {"chain", "compare", "reach", "reproduce", "sweep", "toy-echo"} <= set(REGISTRY)
    for name, experiment in REGISTRY.items():
        assert name in sub.choices, name
        text = sub.choices[name].format_help()
        parts = getattr(experiment.config_type, "PARTS", None) or {None: experiment.config_type}
        for cls in parts.values():  # a config of parts (reach): each part's fields are options
            assert set(field_docs(cls)) == {f.name for f in fields(cls)}, name  # a doc per field
            for f in fields(cls):
                assert f"--{f.name.replace('_', '-')}" in text or f.name in text, (name, f.name)
        for common in ("--seeds", "--out", "--json", "--workers", "--engine", "--quiet"):
            assert common in text, (name, common)
        assert ("--quick" in text) == (experiment.quick is not None), name
    for name, parser in sub.choices.items():
        text = parser.format_help()
        assert not re.search(r":[a-z]+:`|``", text), f"Sphinx markup in `sigmapi {name} --help`"
    toy_help = " ".join(sub.choices["toy-echo"].format_help().split())
    assert "(see evaluate)" in toy_help and "A number, 2.5 say (default 1.0)" in toy_help
    assert "(default: 7 8; --quick: 9)" in toy_help


def test_reproduce_through_the_command_line_writes_the_report_and_result_json(
    tmp_path, monkeypatch, capsys
):
    module = importlib.import_module("sigmapi.experiments.reproduce.run")

    monkeypatch.setattr(module, "paper_presets", lambda quick: [("tiny-1d", REFINED_1D)])
    monkeypatch.setattr(module, "SECTIONS", ())
    out = tmp_path / "r"
    argv = ["reproduce", "--seeds", "0", "1", "--out", str(out), "--models", "none",
            "--n-test", "200", "--workers", "1", "--quiet"]  # fmt: skip
    assert main(argv) == 0
    printed = capsys.readouterr().out  # the report's statistic, labelled
    assert printed.startswith("tiny-1d: median of 2 seeds: view_consistency ")
    assert "tiny-1d: median before refinement of 2 seeds: view_consistency " in printed
    assert "the rule's ceiling (fixed point of Eq. 7 from seed" in printed
    data = read_result(out)
    assert data == json.loads((out / "metrics.json").read_text())
    assert data["seeds"] == [0, 1] and data["n_test"] == 200
    assert (out / "report.html").is_file() and not list(out.glob("*.npz"))
    assert {f"{name}-tiny-1d.png" for name in FIGURES} <= {p.name for p in out.iterdir()}
