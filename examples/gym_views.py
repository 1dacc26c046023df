"""Views recorded in the Gymnasium environment
===========================================

Record views in the Gymnasium environment and train a Sigma-Pi map on them.

The body keeps still while the eye makes saccades: each saccade shows the same object at a
new retinal position under a new gaze, two views of one body-centred z, gathered without a
teacher (``info["z"]`` is never read). Paper-1d sizes (15 + 15 inputs, 15 units)::

    python examples/gym_views.py            # 20,000 recorded pairs, 5 seeds
    python examples/gym_views.py --small    # a few seconds
"""

from __future__ import annotations

import argparse

import gymnasium as gym

import sigmapi
from sigmapi.envs import collect_saccade_views


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    args = parser.parse_args()
    grid, pairs, seeds = 15, 20_000, range(5)
    cfg = sigmapi.load_preset("paper-1d").replace(refine_rounds=0)  # as the README measured
    if args.small:
        grid, pairs, seeds = 9, 3000, range(1)
        cfg = cfg.replace(map_shape=(9,), x_shape=(9,), y_shape=(9,), iterations=15_000,
                          winner_rule="argmax")  # fmt: skip
    # an episode starts with the object outside the goal region and the still body keeps it
    # there: a tiny goal region, so that the recording shows every z
    env = gym.make("sigmapi/GazeReach-v0", dim=1, grid=grid, code_width=cfg.code_width,
                   goal_radius=1e-3)  # fmt: skip
    views = collect_saccade_views(env, pairs, seed=0)  # (x0, y0, x1, y1) codes
    env.close()
    for seed in seeds:
        m = sigmapi.evaluate(sigmapi.SigmaPiSOM(cfg, seed=seed).fit(views))
        print(f"seed {seed}: same winner {m.view_consistency:.3f}, z error {m.z_error:.3f}, "
              f"order R^2 {m.order_r2:.3f}")  # fmt: skip


if __name__ == "__main__":
    main()
