"""``sigmapi reach``: train the actor-critic on each state representation and compare them.

Prints a table (or, with ``--json``, one JSON object whose key ``success`` maps each state to
its final success rate averaged over seeds) and writes the figure of learning curves and
value functions to ``--out``. The options are the fields of the reach config's parts
(:class:`~sigmapi.experiments.reach_config.ReachConfig`), plus ``--seeds N``: the run's seeds
are 0..N-1, the first N independent streams of the root ``--seed``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sigmapi.cli._common import (
    _positive_int,
    add_dataclass_flags,
    add_workers_flag,
    check_output,
    dataclass_values,
)
from sigmapi.errors import UsageError
from sigmapi.experiments.reach import REACH, run_with_progress
from sigmapi.experiments.reach_config import MapConfig, ReachConfig

__all__ = ["cmd_reach", "register"]

ALIASES: dict[str, dict[str, str]] = {
    "env": {"max_episode_steps": "--max-steps"},
    "map": {"model_path": "--model", "iterations": "--map-pairs", "preset": "--map-preset"},
}
"""Second spellings of some options per part (the first is the field's name), kept from the
flat config these options came from."""


def register(sub: Any) -> None:
    """Add the ``reach`` sub-command to the ``sigmapi`` parser's sub-parsers.

    Its options are the fields of the parts of
    :class:`~sigmapi.experiments.reach_config.ReachConfig` (``--map-shape 7x7``,
    ``--states map,true_z``, ...), ``--seeds N`` and the outputs below.
    """
    p = sub.add_parser(
        REACH.name,
        help=REACH.summary,
        description="Gaze-and-reach task: the same actor-critic on the learned Sigma-Pi map, "
        "the retina code, retina+gaze codes, and the true z (upper bound).",
    )
    for part, cls in ReachConfig.PARTS.items():
        add_dataclass_flags(p.add_argument_group(part), cls, aliases=ALIASES.get(part))
    p.add_argument("--seeds", type=_positive_int, default=len(REACH.default_seeds),
                   help="run seeds 0..N-1: the first N independent streams of the root --seed "
                   f"(default {len(REACH.default_seeds)})")  # fmt: skip
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
    out = check_output(args.out, args.force, "figure file")
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UsageError(f"--out must end in .png, .pdf or .svg, got {str(out)!r}")
    save_json = check_output(args.save_json, args.force, "JSON file") if args.save_json else None
    values = {part: dataclass_values(args, cls) for part, cls in ReachConfig.PARTS.items()}
    dim = values["env"].get("dim", ReachConfig().env.dim)
    if "map_shape" not in values["map"]:  # the default map follows the task's dimension
        values["map"]["map_shape"] = MapConfig.map_shape if dim == 2 else (12,)
    if len(values["map"]["map_shape"]) != dim:
        raise UsageError(
            f"--map-shape must have {dim} axes for --dim {dim}, "
            f"got {'x'.join(map(str, values['map']['map_shape']))}"
        )
    model = values["map"].get("model_path")
    if model is not None and not Path(model).is_file():
        raise UsageError(f"model file {model!r} does not exist; train one with `sigmapi train`")
    cfg = ReachConfig(**{part: cls(**values[part]) for part, cls in ReachConfig.PARTS.items()})
    seeds = range(args.seeds)
    result = run_with_progress(cfg, seeds, disable=args.quiet or None, workers=args.workers)
    result.save_figure(out)
    summary = result.to_dict()
    if save_json is not None:
        save_json.write_text(json.dumps(summary, indent=1) + "\n", encoding="utf-8")
    if args.json:
        print(json.dumps(summary))
    else:
        print(result.table())
    print(f"wrote {out} ({result.seconds:.0f} s)", file=sys.stderr)
    return 0
