"""Shared fixtures: small configs that train in seconds on the reference kernel."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

import sigmapi
from sigmapi import SigmaPiSOM, SOMConfig
from sigmapi.analysis.curves import LearningCurve, checkpoints

# command lines run by the tests (subprocesses, other working folders) import the sigmapi
# under test, not whichever one is installed
_SRC = str(Path(sigmapi.__file__).resolve().parents[1])
os.environ["PYTHONPATH"] = os.pathsep.join(
    [_SRC, *[p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]]
)


@pytest.fixture
def small_1d() -> SOMConfig:
    """A 7 + 7 input, 7-unit 1-D run of 3,000 iterations on the reference kernel.

    The paper's procedure (``ordering="none"``), so the pinned values stay those of its streams.
    """
    return SOMConfig(
        map_shape=(7,), x_shape=(7,), y_shape=(7,), iterations=3000,
        sigma=((0.0, 3.0), (0.11, 1.5), (2 / 3, 1e-5)), backend="reference", seed=0,
        ordering="none",
    )  # fmt: skip


@pytest.fixture
def small_2d() -> SOMConfig:
    """A 4x4 map on 5x5 inputs, 1,500 iterations on the reference kernel (the paper's start)."""
    return SOMConfig(
        map_shape=(4, 4), x_shape=(5, 5), y_shape=(5, 5), code_width=1.0, iterations=1500,
        sigma=((0.0, 2.0), (0.5, 1e-5)), backend="reference", seed=0,
        ordering="none",
    )  # fmt: skip


@pytest.fixture(scope="module")
def model_1d() -> SigmaPiSOM:
    """A 5-unit 1-D map trained for 2,000 iterations (default backend)."""
    return SigmaPiSOM(map_shape=(5,), x_shape=(5,), y_shape=(5,), iterations=2000, seed=0).fit()


@pytest.fixture(scope="module")
def model_2d() -> SigmaPiSOM:
    """A 3x4 map on 4x4 inputs trained for 1,000 iterations."""
    return SigmaPiSOM(
        map_shape=(3, 4), x_shape=(4, 4), y_shape=(4, 4), code_width=1.0, iterations=1000, seed=0
    ).fit()


@pytest.fixture(scope="module")
def curves(model_1d: SigmaPiSOM) -> list[dict[str, list[float]]]:
    """Learning curves of model_1d's run at 5 checkpoints."""
    som = SigmaPiSOM(model_1d.config)
    curve = LearningCurve(at=checkpoints(2000, 5), n_test=100)
    som.fit(callback=curve)
    return [curve.to_dict()]
