"""The report's learning-curves and Fig. 8 figures: the refinement on its own axis, the rule's
ceiling as a line, and captions computed from the data."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import pytest

from sigmapi.viz import plots


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def test_learning_curves_draw_the_refinement_on_its_own_axis_and_the_ceiling(model_1d):
    from sigmapi import SigmaPiSOM
    from sigmapi.analysis.curves import LearningCurve, checkpoints

    som = SigmaPiSOM(model_1d.config.replace(refine_rounds=2, refine_pairs=1000))
    curve = LearningCurve(at=checkpoints(2000, 3), n_test=100)
    som.fit(callback=curve)
    ax = plots.plot_learning_curves([curve.to_dict()], ceiling={"view_consistency": 0.9})
    panels = ax.child_axes
    refine = [p for p in panels if p.get_xscale() == "linear"]
    assert len(refine) == 4 and refine[-1].get_xlabel() == "refinement pairs"
    # the refinement starts from the last training record: x = 0, then one point per round
    xs = [list(line.get_xdata()) for line in refine[0].get_lines() if len(line.get_xdata()) > 2]
    assert [0.0, 1000.0, 2000.0] in xs
    train_x = [x for line in panels[0].get_lines() for x in line.get_xdata()]
    assert max(train_x) == 2000  # the training axis ends at the last training iteration
    labels = [line.get_label() for p in panels for line in p.get_lines()]
    assert "the rule's ceiling (fixed point) 0.900" in labels
    assert not plots.has_refinement([{"t": [1.0], "refined": [0.0]}])


def test_fig8_caption_counts_the_same_winner_and_gives_the_distance_a_scale():
    from sigmapi import SOMConfig
    from sigmapi.viz.figures import RunInfo, caption

    cfg = SOMConfig(map_shape=(15,), x_shape=(15,), y_shape=(15,), refine_rounds=3)
    run = RunInfo("paper-1d", cfg, (0, 1), 1, why="the worst-ordered of its 2 seeds")
    facts = {"z": [0.57], "polarity": "reversed (mirrored)", "polarity_r2": 0.99,
             "invariance_spread": 0.32, "winners": [5, 5, 6, 5], "same_winner": 3,
             "within_one": 4, "refined_pairs": 300_000}  # fmt: skip
    text = caption("fig8", run, facts)
    assert "on the refined map (after 300,000 refinement pairs)" in text
    assert "The same unit wins 3 of the 4 pairs (4 of 4 within one unit of it; hard winners " \
           "5, 5, 6, 5)" in text  # fmt: skip
    assert (
        "each response scaled to unit length, is 0.32 (0 = the same shape, 1.41 = no unit" in text
    )
    assert "seed 1: the worst-ordered of its 2 seeds" in text
    text = caption("fig8", run, {**facts, "same_winner": 4, "winners": [5, 5, 5, 5]})
    assert "The same unit wins all 4 pairs" in text
