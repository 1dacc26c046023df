"""Shared fixtures: small configs that train in seconds on the reference kernel."""

from __future__ import annotations

import os

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

from sigmapi import SOMConfig


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
