"""A body: the simulated robot
===========================

A body: the simulated robot records its own views, learns the map, then docks on it.

Needs the extra: ``pip install 'sigmapi[robot]'`` (MuJoCo). The robot keeps its base still
while its head makes saccades: two views of one ball, the retinal position (head camera) and
the neck angles, coded as population codes. The Sigma-Pi map learns the body-centred
direction from those pairs without being told it; then the authors' actor-critic learns to
dock the base at the table on the map's response, beside the true direction as a code (the
upper bound)::

    python examples/robot.py [--out robot.png]   # the experiment's map, 300 episodes per state
    python examples/robot.py --small              # seconds

``--out`` draws each map unit's preferred ball position on the table (a top view) beside the
learning curves.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import sigmapi
from sigmapi.agents import ActorCriticConfig, actor_critic_for, run_episodes
from sigmapi.envs import collect_saccade_views, make_state_env
from sigmapi.experiments.robot.config import RobotConfig
from sigmapi.experiments.robot.map import (
    evaluation_pairs,
    robot_som_config,
    score_map,
    unit_positions,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").partition("\n")[0])
    parser.add_argument("--small", action="store_true", help="a tiny run (for the tests)")
    parser.add_argument("--out", help="draw the map on the table and the curves to this file")
    args = parser.parse_args()
    grid, shape, pairs, iterations, episodes = 12, (8, 8), 10_000, 40_000, 300
    if args.small:
        grid, shape, pairs, iterations, episodes = 8, (4, 4), 1000, 4000, 30

    env = gym.make("sigmapi/RobotDock-v0", grid=grid)
    world = env.unwrapped  # a view source: its codes, and views of the still robot
    views = collect_saccade_views(env, pairs, seed=0)  # (x0, y0, x1, y1); z is never read
    cfg = robot_som_config(world.x_code, shape, iterations, seed=0)
    model = sigmapi.SigmaPiSOM(cfg).fit(views)
    calibration, test = evaluation_pairs(
        RobotConfig().replace(grid=grid, eval_pairs=500 if args.small else 3000)
    )
    m = score_map(model, calibration, test)
    print(f"map {shape[0]}x{shape[1]} from {pairs} view pairs: order R^2 {m['order_r2']:.3f}, "
          f"same winner {m['view_consistency']:.3f}, folded {m['folded']}")  # fmt: skip

    starts = np.random.default_rng(1).integers(0, 2**31 - 1, size=episodes)
    last, block = max(1, episodes // 3), max(1, episodes // 6)
    curves = {}
    for state in ("map", "true_z"):
        learner_env = make_state_env(gym.make("sigmapi/RobotDock-v0", grid=grid), state, model)
        agent = actor_critic_for(learner_env, ActorCriticConfig(), seed=2)
        ep = run_episodes(learner_env, agent, starts)
        print(f"docking on {state}: success {ep.success[-last:].mean():.2f} over the last "
              f"{last} of {episodes} episodes")  # fmt: skip
        rate = ep.success[: episodes // block * block].reshape(-1, block).mean(axis=1)
        curves[state] = {"episode": list(block * np.arange(1.0, len(rate) + 1)),
                         "success": list(rate), "success_sd": [0.0] * len(rate)}  # fmt: skip
    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from sigmapi.experiments.robot.figures import plot_curves, plot_unit_positions

        fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
        plot_unit_positions(unit_positions(model, calibration), shape, ax=left)
        plot_curves(curves, ax=right)
        fig.savefig(args.out, dpi=100, bbox_inches="tight")
        print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
