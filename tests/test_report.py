"""The reproduction report and the ``figure`` command, on tiny configs."""

from __future__ import annotations

import json
import sys
import types
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import pytest

from sigmapi import SigmaPiSOM, SOMConfig, report
from sigmapi.cli import main

TINY_1D = SOMConfig(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000)
TINY_2D = SOMConfig(map_shape=(3, 3), x_shape=(3, 3), y_shape=(3, 3), code_width=1.0,
                    iterations=1000)  # fmt: skip


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("report")
    results = report.reproduce(
        out, seeds=[0, 1], progress=False, n_test=300, save_models="all",
        presets=[("tiny-1d", TINY_1D), ("tiny-2d", TINY_2D)], sections=(),
    )  # fmt: skip
    return out, results


def test_report_has_every_figure_and_links_only_existing_files(run):
    out, _ = run
    text = (out / "report.html").read_text()
    links = report.linked_files(text)
    assert links, "the report links no files"
    for f in links:
        assert (out / f).is_file(), f"report links missing file {f}"
        assert not Path(f).is_absolute() and ".." not in Path(f).parts
    for preset in ("tiny-1d", "tiny-2d"):
        for name in report.FIGURES:
            assert f"{name}-{preset}.png" in links
    assert "metrics.json" in links


def test_metrics_json_holds_runs_curves_and_figure_facts(run):
    out, results = run
    data = json.loads((out / "metrics.json").read_text())
    assert data == json.loads(json.dumps(results))
    res = data["presets"]["tiny-1d"]
    assert [r["seed"] for r in res["runs"]] == [0, 1]
    assert set(report.METRIC_KEYS) <= set(res["mean"]) and set(report.METRIC_KEYS) <= set(res["sd"])
    assert res["runs"][0]["curve"]["t"][-1] == TINY_1D.iterations
    assert "polarity" in res["figures"]["fig8"]
    assert (out / "tiny-2d-seed1.npz").is_file()


def test_metrics_table_sits_beside_reference_figures(tmp_path):
    out = tmp_path / "r"
    report.reproduce(out, seeds=[0], progress=False, n_test=200, save_models="none",
                     presets=[("paper-1d", TINY_1D)], sections=())  # fmt: skip
    text = (out / "report.html").read_text()
    assert "0.870" in text and "0.988" in text and "0.320" in text  # ALGORITHM.md
    assert "floor 0.27" in text
    assert not list(out.glob("*.npz"))


def test_extra_sections_are_added_and_checked(tmp_path, monkeypatch):
    module = types.ModuleType("fake_section")

    def report_section(ctx: report.ReportContext) -> report.Section:
        assert ctx.models["tiny-1d"][0].t_ == TINY_1D.iterations
        (ctx.out / "extra.png").write_bytes(b"\x89PNG\r\n\x1a\n")
        return report.Section("Reaching", "<p>extra</p>", [("extra.png", "a caption")], {"n": 1})

    module.report_section = report_section  # type: ignore[attr-defined]
    monkeypatch.setitem(sys.modules, "fake_section", module)
    monkeypatch.setattr(report, "SECTION_MODULES", ("fake_section", "no_such_module_here"))
    monkeypatch.setattr(report, "FIGURES", ("weights",))
    out = tmp_path / "r"
    results = report.reproduce(out, seeds=[0], progress=False, n_test=100, save_models="none",
                               presets=[("tiny-1d", TINY_1D)])  # fmt: skip
    assert results["sections"] == {"Reaching": {"n": 1}}
    text = (out / "report.html").read_text()
    assert "<h2>Reaching</h2>" in text and "extra.png" in report.linked_files(text)

    def broken(ctx: report.ReportContext) -> report.Section:
        return report.Section("Broken", figures=[("missing.png", "never written")])

    module.report_section = broken  # type: ignore[attr-defined]
    with pytest.raises(RuntimeError, match=r"missing\.png"):
        report.reproduce(tmp_path / "r2", seeds=[0], progress=False, n_test=100,
                         save_models="none", presets=[("tiny-1d", TINY_1D)])  # fmt: skip


def test_linked_files_ignores_urls_and_anchors():
    text = (
        "<img src='a.png'><a href=\"b c.json\">x</a><a href='https://x.org/y.png'>"
        "<a href='#top'><img src='a.png'><a href='mailto:me@x.org'>"
    )
    assert report.linked_files(text) == ["a.png", "b c.json"]


def test_quick_run_uses_one_seed_and_short_presets(monkeypatch, tmp_path):
    seen = {}

    def fake(out, seeds, quick, progress, save_models):
        seen.update(seeds=seeds, quick=quick, models=save_models)
        return {"presets": {}, "total_seconds": 0.0}

    monkeypatch.setattr(report, "reproduce", fake)
    assert main(["reproduce", "--quick", "--quiet", "--out", str(tmp_path / "q")]) == 0
    assert seen == {"seeds": [0], "quick": True, "models": "shown"}
    for name, cfg in report._presets(quick=True):
        assert cfg.iterations <= report.QUICK_ITERATIONS.get(name, cfg.iterations)


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
