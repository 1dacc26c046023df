"""The estimator's run state (model/_run.py): one BLOCK with one home, one reset that a new
grid goes through, and a new backend that takes a refinement round over by replaying it."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.kernels import BACKENDS
from sigmapi.model import som as facade
from sigmapi.model._run import BLOCK

SRC = Path(__file__).resolve().parents[2] / "src" / "sigmapi"
SMALL = SOMConfig(map_shape=(6,), x_shape=(7,), y_shape=(7,), iterations=3000, seed=1,
                  refine_rounds=1, refine_pairs=1500, kernel_tol=0.0)  # fmt: skip


def test_block_has_one_home():
    homes = [
        f"{p.relative_to(SRC)}:{node.lineno}"
        for p in sorted(SRC.rglob("*.py"))
        for node in ast.walk(ast.parse(p.read_text("utf-8")))
        if isinstance(node, ast.Assign | ast.AnnAssign)
        for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
        if isinstance(t, ast.Name) and t.id == "BLOCK"
    ]
    assert len(homes) == 1 and homes[0].startswith("model/_run.py:"), homes
    assert facade.BLOCK is BLOCK == 1000


def test_a_new_grid_is_a_fresh_run():
    som = SigmaPiSOM(SMALL, backend="reference", refine_pairs=500).fit()
    assert som.refined_ == 500
    som.set_params(map_shape=(5,))
    assert not som.is_fitted
    som.partial_fit(iterations=10)
    assert som.t_ == 10 and som.refined_ == 0 and som.weights_.shape == (5, 7, 7)


class _Stop(Exception):
    pass


def _stop_in_the_round(model: SigmaPiSOM) -> None:
    if model.refined_ >= 1000:
        raise _Stop


def test_a_new_backend_replays_the_round_in_progress():
    if "fast" not in BACKENDS:
        pytest.skip("numba is not installed")
    cut = SigmaPiSOM(SMALL, backend="fast")
    with pytest.raises(_Stop):
        cut.fit(callback=_stop_in_the_round)
    assert cut.t_ == 3000 and cut.refined_ == 1000  # within the round: its sums in memory
    cut.set_params(backend="reference").refine()
    whole = SigmaPiSOM(SMALL, backend="fast", refine_rounds=0).fit()
    whole.set_params(backend="reference", refine_rounds=1).refine()
    assert cut.refined_ == whole.refined_ == 1500
    assert (cut.weights_ == whole.weights_).all()
