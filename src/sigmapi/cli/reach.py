"""``sigmapi reach``: train the actor-critic on each state representation and compare them.

Prints a table (or, with ``--json``, one JSON object whose key ``success`` maps each state to
its final success rate averaged over seeds) and writes the figure of learning curves and
value functions to ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sigmapi.cli._common import check_output
from sigmapi.errors import ConfigError, UsageError
from sigmapi.kernels import BACKENDS
from sigmapi.reach.plots import reach_figure
from sigmapi.reach.runner import ReachConfig, run_with_progress
from sigmapi.reach.wrappers import STATES

__all = ["cmd_reach", "register"]


def _shape(text: str) -> tuple[int, ...]:
    try:
        shape = tuple(int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a grid such as 8x8 or 10, got {text!r}"
        ) from None
    if not shape or any(n < 1 for n in shape):
        raise argparse.ArgumentTypeError(f"grid sizes must be positive, got {text!r}")
    return shape


def register(sub: Any) -> None:
    """Add the ``reach`` sub-command to the ``sigmapi`` parser's sub-parsers."""
    d = ReachConfig()
    p = sub.add_parser(
        "reach",
        help="learn to reach with an actor-critic on the learned map vs. other states",
        description="Gaze-and-reach task: the same actor-critic on the learned Sigma-Pi map, "
        "the retina code, retina+gaze codes, and the true z (upper bound).",
    )
    p.add_argument(
        "--dim", type=int, choices=[1, 2], default=d.dim, help=f"task dimension (default {d.dim})"
    )
    p.add_argument(
        "--grid",
        type=int,
        default=d.grid,
        help=f"units per axis of the retina/gaze codes (default {d.grid})",
    )
    p.add_argument(
        "--map-shape", type=_shape, help="map grid, e.g. 7x7 (default 7x7 in 2-D, 12 in 1-D)"
    )
    p.add_argument(
        "--map-pairs",
        type=int,
        default=d.map_pairs,
        help=f"saccade view pairs the map learns from (default {d.map_pairs})",
    )
    p.add_argument(
        "--model",
        help="use this trained model file (sigmapi train) instead of learning a map per seed",
    )
    p.add_argument(
        "--backend",
        choices=["auto", *BACKENDS],
        default=d.backend,
        help=f"kernel for learning the map (default {d.backend})",
    )
    p.add_argument(
        "--episodes",
        type=int,
        default=d.episodes,
        help=f"episodes per seed and state (default {d.episodes})",
    )
    p.add_argument(
        "--seeds", type=int, default=d.seeds, help=f"number of seeds (default {d.seeds})"
    )
    p.add_argument("--seed", type=int, default=d.seed, help=f"root seed (default {d.seed})")
    p.add_argument(
        "--saccade-rate",
        type=float,
        default=d.saccade_rate,
        help=f"saccade probability per step (default {d.saccade_rate:g})",
    )
    p.add_argument(
        "--max-steps",
        type=int,
        default=d.max_steps,
        help=f"time limit per episode (default {d.max_steps})",
    )
    p.add_argument(
        "--features",
        choices=["response", "bump"],
        default=d.features,
        help=f"map features (default {d.features})",
    )
    p.add_argument(
        "--feature-width",
        type=float,
        default=d.feature_width,
        help=f"width of bump features and true-z code, grid units (default {d.feature_width:g})",
    )
    p.add_argument(
        "--block",
        type=int,
        default=d.block,
        help=f"episodes per point of the curves (default {d.block})",
    )
    p.add_argument(
        "--final-episodes",
        type=int,
        default=d.final_episodes,
        help=f"last episodes the final success rate averages (default {d.final_episodes})",
    )
    p.add_argument(
        "--states", default=",".join(STATES), help=f"comma-separated subset of {','.join(STATES)}"
    )
    p.add_argument("--out", default="reach.png", help="figure file to write (default reach.png)")
    p.add_argument(
        "--save-json",
        help="also write the full result (curves, per-seed rates, config) to this JSON file",
    )
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_reach)


def cmd_reach(args: argparse.Namespace) -> int:
    out = check_output(args.out, args.force, "figure file")
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"--out must end in .png, .pdf or .svg, got {str(out)!r}")
    save_json = check_output(args.save_json, args.force, "JSON file") if args.save_json else None
    map_shape = args.map_shape or ((7, 7) if args.dim == 2 else (12,))
    if len(map_shape) != args.dim:
        raise UsageError(
            f"--map-shape must have {args.dim} axes for --dim {args.dim}, "
            f"got {'x'.join(map(str, map_shape))}"
        )
    states = tuple(s.strip() for s in args.states.split(",") if s.strip())
    if args.model is not None:
        if not Path(args.model).is_file():
            raise UsageError(
                f"model file {args.model!r} does not exist; train one with `sigmapi train`"
            )
    try:
        cfg = ReachConfig(
            dim=args.dim, grid=args.grid, map_shape=map_shape, map_pairs=args.map_pairs,
            backend=args.backend, model_path=args.model, features=args.features,
            feature_width=args.feature_width, episodes=args.episodes, seeds=args.seeds,
            seed=args.seed, saccade_rate=args.saccade_rate, max_steps=args.max_steps,
            block=args.block, final_episodes=args.final_episodes, states=states,
        )  # fmt: skip
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    result = run_with_progress(cfg, disable=args.quiet or None)
    fig = reach_figure(result)
    fig.savefig(out, dpi=120)
    summary = result.to_dict()
    if save_json is not None:
        save_json.write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    if args.json:
        print(json.dumps(summary))
    else:
        per_seed = result.final_success_per_seed()
        print(
            f"final success rate over the last {cfg.final_episodes} of {cfg.episodes} "
            f"episodes, {cfg.seeds} seeds:"
        )
        lost = result.final_lost()
        for s, v in result.final_success().items():
            seeds = " ".join(f"{x:.3f}" for x in per_seed[s])
            print(f"  {s:12s} {v:.3f}   per seed: {seeds}   (lost {lost[s]:.3f})")
        if summary["ratio_map_to_true_z"] is not None:
            print(f"  map / true_z = {summary['ratio_map_to_true_z']:.3f}")
    print(f"wrote {out} ({result.seconds:.0f} s)", file=sys.stderr)
    return 0
