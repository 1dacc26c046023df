"""Your own two-view data
======================

Train a Sigma-Pi map on two-view data you recorded yourself (positions in your units).

A setup records, for objects that stay put, two glimpses each: the retinal angle and the
gaze angle (degrees) before and after a saccade. Rescale them to [0, 1], turn them into the
model's codes with ``encode_views``, save them, and ``fit(views)``::

    python examples/own_data.py            # paper-1d sizes, 20,000 pairs, 5 seeds
    python examples/own_data.py --small    # a few seconds
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

import sigmapi

FIELD = 40.0
"""Retina and gaze both span -40..+40 degrees here; the object's body angle is their mean."""


def record(n: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Stand-in for your recording: ``n`` objects, two (retina, gaze) glimpses of each."""
    body = rng.uniform(-FIELD, FIELD, n)  # where each object is, never stored
    out = {}
    for view in "01":
        lo, hi = np.maximum(-FIELD, 2 * body - FIELD), np.minimum(FIELD, 2 * body + FIELD)
        gaze = rng.uniform(lo, hi)  # any gaze that keeps the object on the retina
        out[f"retina{view}"], out[f"gaze{view}"] = 2 * body - gaze, gaze
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    args = parser.parse_args()
    cfg = sigmapi.load_preset("paper-1d").replace(refine_rounds=0)  # as the README measured
    n, seeds = 20_000, range(5)
    if args.small:
        cfg = cfg.replace(map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=15_000,
                          winner_rule="argmax")  # fmt: skip
        n, seeds = 3000, range(2)

    deg = record(n, np.random.default_rng(0))
    with tempfile.TemporaryDirectory() as tmp:  # your data, as a file
        path = Path(tmp) / "glimpses.npz"
        np.savez(path, **deg)
        deg = dict(np.load(path))

    def unit(a: np.ndarray) -> np.ndarray:  # degrees -> fraction of the field
        return (a + FIELD) / (2 * FIELD)

    for seed in seeds:
        som = sigmapi.SigmaPiSOM(cfg, seed=seed)
        views = som.encode_views(unit(deg["retina0"]), unit(deg["gaze0"]),
                                 unit(deg["retina1"]), unit(deg["gaze1"]))  # fmt: skip
        m = sigmapi.evaluate(som.fit(views))
        print(f"seed {seed}: same winner {m.view_consistency:.3f}, z error {m.z_error:.3f} "
              f"grid spacings, order R^2 {m.order_r2:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
