"""The reproduction report and the ``figure`` command, on tiny configs."""

from __future__ import annotations

import json
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import pytest

from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.cli import main
from sigmapi.experiments import (
    ReportContext,
    ReproduceOptions,
    Section,
    paper_presets,
    reproduce,
)
from sigmapi.experiments.report_html import linked_files
from sigmapi.experiments.reproduce import QUICK_ITERATIONS
from sigmapi.experiments.results import METRIC_KEYS
from sigmapi.figures import FIGURES

TINY_1D = SOMConfig(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000)
TINY_2D = SOMConfig(map_shape=(3, 3), x_shape=(3, 3), y_shape=(3, 3), code_width=1.0,
                    iterations=1000)  # fmt: skip


def _options(seeds=(0,), n_test=100, save_models="none") -> ReproduceOptions:
    return ReproduceOptions(seeds=seeds, progress=False, n_test=n_test, save_models=save_models)


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("report")
    result = reproduce(
        out, _options(seeds=(0, 1), n_test=300, save_models="all"),
        presets=[("tiny-1d", TINY_1D), ("tiny-2d", TINY_2D)], sections=(),
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
    for preset in ("tiny-1d", "tiny-2d"):
        for name in FIGURES:
            assert f"{name}-{preset}.png" in links
    assert "metrics.json" in links


def test_metrics_json_holds_runs_curves_and_figure_facts(run):
    out, results = run
    data = json.loads((out / "metrics.json").read_text())
    assert data == json.loads(json.dumps(results))
    res = data["presets"]["tiny-1d"]
    assert [r["seed"] for r in res["runs"]] == [0, 1]
    assert set(METRIC_KEYS) <= set(res["mean"]) and set(METRIC_KEYS) <= set(res["sd"])
    assert res["runs"][0]["curve"]["t"][-1] == TINY_1D.iterations
    assert "polarity" in res["figures"]["fig8"]
    assert (out / "tiny-2d-seed1.npz").is_file()


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
        (["figure", "weights", "{tmp}/m.npz", "--out", "{tmp}/m.npz"], "exists"),
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
    from sigmapi.errors import ConfigError
    from sigmapi.experiments import check_seeds

    with pytest.raises(ConfigError, match=re.escape(message)):
        check_seeds(seeds)
    assert check_seeds([4, 0, 2]) == (4, 0, 2)


def test_register_refuses_bad_names_configs_and_taken_names():
    from dataclasses import dataclass

    from sigmapi.errors import ConfigError
    from sigmapi.experiments import REGISTRY, register

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


def test_write_result_is_atomic_json_that_reads_back(tmp_path):
    from sigmapi.experiments import read_result, write_result

    class Done:
        def to_dict(self):
            return {"methods": [{"name": "a", "z_error": 0.25}], "seeds": [0, 1]}

    path = write_result(Done(), tmp_path / "new")
    assert path == tmp_path / "new" / "result.json"
    assert read_result(tmp_path / "new") == read_result(path) == Done().to_dict()
    assert not [p for p in path.parent.iterdir() if p != path]  # no temp file left
