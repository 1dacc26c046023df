"""What a newcomer meets first says what is true: the estimator's default, the console's
words beside the report's, every experiment's ``--quick``, and no debris from a failed run."""

from __future__ import annotations

import dataclasses

import pytest

import sigmapi
from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.cli import main
from sigmapi.experiments import REGISTRY
from sigmapi.experiments.reproduce.results import (
    PresetResult,
    ReproduceOptions,
    ReproduceResult,
    SeedRun,
)


def test_the_default_config_is_what_the_docstrings_say():
    default = SOMConfig()
    authors = sigmapi.load_preset("paper-1d-authors")
    paper = sigmapi.load_preset("paper-1d")
    # the authors' sizes and schedule with sigmapi's ordered start ...
    assert dataclasses.replace(authors, ordering="crossview") == default
    assert authors.ordering == "none" and default.ordering == "crossview"
    # ... and no refinement, which paper-1d adds
    assert default.refine_rounds == 0 and paper.refine_rounds > 0
    assert dataclasses.replace(paper, refine_rounds=0, refine_pairs=default.refine_pairs) == default
    for doc in (SigmaPiSOM.__doc__, SOMConfig.__doc__):
        assert "ordered start" in doc and "no refinement" in doc
        assert "paper-1d-authors" in doc


def test_the_console_says_what_a_fold_flag_means_beside_ordered():
    som = SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=300, seed=0).fit()
    flagged = dataclasses.replace(sigmapi.evaluate(som, n_test=100), order_r2=0.99, folded=True)
    run = SeedRun(seed=3, train_seconds=0.0, backend=som.backend, metrics=flagged, curve={})
    preset = PresetResult(som.config, [run], reference={}, z_error_floor=None, shown_seed=3)
    result = ReproduceResult(ReproduceOptions(seeds=(3,), progress=False), {"tiny": preset})
    text = result.table()
    assert "tiny: 1 of 1 ordered (order R^2 >= 0.95); the fold detector flags seed 3 " in text
    assert "also mark a coarse map" in text
    clean = dataclasses.replace(run, metrics=dataclasses.replace(flagged, folded=False))
    result.presets["tiny"] = dataclasses.replace(preset, runs=[clean])
    assert "fold detector" not in result.table()


def test_every_experiment_takes_quick_but_those_whose_input_sets_their_size():
    missing = sorted(name for name, e in REGISTRY.items() if e.quick is None)
    assert missing == ["physiology", "sweep"]  # the model file; the spec
    from sigmapi.experiments.chain.run import QUICK

    assert QUICK.som_config.iterations < sigmapi.load_preset("paper-1d").iterations


def test_a_command_that_fails_for_a_missing_extra_leaves_no_empty_folder(
    tmp_path, monkeypatch, capsys
):
    from sigmapi.experiments.compare import run as compare

    monkeypatch.setattr(compare, "installed", lambda: set())
    out = tmp_path / "new" / "report"
    assert main(["compare", "--quick", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "pip install 'sigmapi[baselines]'" in err and len(err.strip().splitlines()) == 1
    assert not out.exists() and not (tmp_path / "new").exists()
    # a folder that was there before stays
    keep = tmp_path / "keep"
    keep.mkdir()
    assert main(["compare", "--quick", "--out", str(keep)]) == 2
    assert keep.is_dir() and list(keep.iterdir()) == []


@pytest.mark.parametrize("argv", [["chain", "--quick", "--help"]])
def test_chain_help_shows_quick(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 0
    assert "--quick" in capsys.readouterr().out


def test_the_curves_title_fits_the_figure_and_the_caption_states_the_gap(model_1d, curves):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from sigmapi.viz import figures

    label = "paper-1d, seeds 0, 1, 2, 3, 4, 5, 6, 7, 8, 9"
    fig, facts = figures._draw_curves(model_1d, figures.DrawInputs(curves * 10, label=label))
    FigureCanvasAgg(fig)
    renderer = fig.canvas.get_renderer()
    texts = [*fig.texts, *(ax.title for ax in fig.axes)]
    titles = [t for t in texts if "Learning curves" in t.get_text()]
    assert titles, "no title drawn"
    width, height = fig.bbox.width, fig.bbox.height
    for t in titles:
        box = t.get_window_extent(renderer)
        assert box.x0 >= 0 and box.x1 <= width and box.y1 <= height, (t.get_text(), box)
    run = figures.RunInfo("paper-1d", model_1d.config, (0, 1), 0, curve_test=1000)
    decoding = {"seed": 0, "z_error_curve_table": 0.34, "z_error_table": 0.30,
                "z_error_curve": 0.35}  # fmt: skip
    gap = {"z_error": 0.05, "view_consistency": -0.01, "n_test": 10_000, "decoding": decoding}
    text = figures.caption("curves", run, {**facts, "table_gap": gap})
    assert "last points lie +0.050 in z error and -0.010 in view consistency" in text
    assert "10,000 test and calibration z's" in text and "differ from it by sampling" not in text
    assert "scores z error 0.340 against the table's 0.300 (its curve ends at 0.350)" in text
    assert "the smaller decoding table makes 80% of that seed's gap" in text
    close = {**decoding, "z_error_curve": 0.31}
    text = figures.caption("curves", run, {**facts, "table_gap": {**gap, "decoding": close}})
    assert "within 0.02 of the table" in text and "decoding table makes" not in text
