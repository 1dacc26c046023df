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

from sigmapi.cli._common import (
    add_dataclass_flags,
    add_workers_flag,
    check_output,
    dataclass_values,
)
from sigmapi.errors import UsageError
from sigmapi.reach.config import ReachConfig
from sigmapi.reach.experiment import run_with_progress

__all = ["cmd_reach", "register"]


def register(sub: Any) -> None:
    """Add the ``reach`` sub-command to the ``sigmapi`` parser's sub-parsers.

    Its options are the fields of :class:`~sigmapi.reach.ReachConfig` (``--map-shape 7x7``,
    ``--states map,true_z``, ...) plus the outputs below.
    """
    p = sub.add_parser(
        "reach",
        help="learn to reach with an actor-critic on the learned map vs. other states",
        description="Gaze-and-reach task: the same actor-critic on the learned Sigma-Pi map, "
        "the retina code, retina+gaze codes, and the true z (upper bound).",
    )
    add_dataclass_flags(p, ReachConfig, aliases={"model_path": "--model"})
    p.add_argument("--out", default="reach.png", help="figure file to write (default reach.png)")
    p.add_argument(
        "--save-json",
        help="also write the full result (curves, per-seed rates, config) to this JSON file",
    )
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_workers_flag(p, "seeds run")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_reach)


def cmd_reach(args: argparse.Namespace) -> int:
    from sigmapi.reach.plots import reach_figure  # matplotlib: only when drawing

    out = check_output(args.out, args.force, "figure file")
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"--out must end in .png, .pdf or .svg, got {str(out)!r}")
    save_json = check_output(args.save_json, args.force, "JSON file") if args.save_json else None
    values = dataclass_values(args, ReachConfig)
    dim = values.get("dim", ReachConfig.dim)
    if "map_shape" not in values:  # the default map follows the task's dimension
        values["map_shape"] = ReachConfig.map_shape if dim == 2 else (12,)
    if len(values["map_shape"]) != dim:
        raise UsageError(
            f"--map-shape must have {dim} axes for --dim {dim}, "
            f"got {'x'.join(map(str, values['map_shape']))}"
        )
    if "model_path" in values and not Path(values["model_path"]).is_file():
        raise UsageError(
            f"model file {values['model_path']!r} does not exist; train one with `sigmapi train`"
        )
    cfg = ReachConfig(**values)
    result = run_with_progress(cfg, disable=args.quiet or None, workers=args.workers)
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
