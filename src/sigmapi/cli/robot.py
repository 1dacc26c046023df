"""``sigmapi robot``: the map learned on the simulated body, then docking on it.

Writes ``result.json`` and the figures to ``--out``; prints a table, or with ``--json`` one
JSON object (the map's metrics with the keys of ``sigmapi evaluate`` and ``success`` per
state). Needs ``pip install 'sigmapi[robot]'``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sigmapi.cli._common import add_dataclass_flags, add_workers_flag, dataclass_values
from sigmapi.errors import UsageError

__all__ = ["cmd_robot", "register"]


def _seeds(text: str) -> tuple[int, ...]:
    try:
        seeds = tuple(int(s) for s in text.split(",") if s.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected seeds such as 0,1,2, got {text!r}") from None
    if not seeds or min(seeds) < 0:
        raise argparse.ArgumentTypeError(f"seeds must be ints >= 0, got {text!r}")
    return seeds


def register(sub: Any) -> None:
    """Add the ``robot`` sub-command; its options are the fields of ``RobotConfig``."""
    p = sub.add_parser(
        "robot",
        help="the map learned on a simulated robot (MuJoCo), then docking on it",
        description="A simulated robot records view pairs from its saccades, learns the "
        "Sigma-Pi map, then an actor-critic docks on the map, the retina code, retina+gaze "
        "codes and the true z (upper bound).",
    )
    try:
        from sigmapi.experiments.robot import RobotConfig
    except ImportError:  # no MuJoCo: the command says so when it runs (cmd_robot)
        p.add_argument("rest", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
        p.set_defaults(func=cmd_robot)
        return
    add_dataclass_flags(p, RobotConfig)
    p.add_argument("--quick", action="store_true", help="a small run (minutes)")
    p.add_argument("--seeds", type=_seeds, help="seeds, e.g. 0,1,2 (default 0-4; --quick: 0)")
    p.add_argument("--out", required=True, help="folder for result.json and the figures")
    p.add_argument("--render", help="also write an animated GIF of one episode to this file")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_workers_flag(p, "seeds run")
    p.set_defaults(func=cmd_robot)


def cmd_robot(args: argparse.Namespace) -> int:
    try:
        from sigmapi.experiments.robot import QUICK, RobotConfig, run_robot, write_outputs
    except ImportError as exc:  # mujoco missing
        raise UsageError(
            f"sigmapi robot needs MuJoCo: pip install 'sigmapi[robot]' ({exc})"
        ) from None
    render = Path(args.render) if args.render else None
    if render is not None and render.suffix.lower() != ".gif":
        raise UsageError(f"--render must end in .gif, got {str(render)!r}")
    base = QUICK if args.quick else RobotConfig()
    cfg = base.replace(**dataclass_values(args, RobotConfig))
    seeds = args.seeds or ((0,) if args.quick else (0, 1, 2, 3, 4))
    workers = args.workers or min(len(seeds), 2)
    print(f"robot: {len(seeds)} seeds, {cfg.episodes} episodes per state", file=sys.stderr)
    result = run_robot(
        cfg, seeds=seeds, workers=workers,
        progress=lambda n, phase: print(f"robot: {phase}", file=sys.stderr),
    )  # fmt: skip
    paths = write_outputs(result, Path(args.out), render)
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        print(result.table())
    print(f"wrote {', '.join(map(str, paths))} ({result.seconds:.0f} s)", file=sys.stderr)
    return 0
