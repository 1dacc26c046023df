"""``sigmapi robot``: the map learned on the simulated body, then docking on it.

Writes ``result.json`` and the figures into ``--out``; prints a table, or with ``--json`` one
JSON object (the map's metrics with the keys of ``sigmapi evaluate`` and ``success`` per
state). The options are the fields of
:class:`~sigmapi.experiments.robot_config.RobotConfig`. MuJoCo (``pip install
'sigmapi[robot]'``) is imported when the command runs, not when the parser is built.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from sigmapi.cli._common import add_dataclass_flags, add_workers_flag, dataclass_values
from sigmapi.errors import UsageError
from sigmapi.executor import plan_workers
from sigmapi.experiments.robot import ROBOT, job_memory, run_with_progress
from sigmapi.experiments.robot_config import QUICK, RobotConfig

__all__ = ["cmd_robot", "register"]


def _seed(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"a seed is an int >= 0, got {text!r}")
    return value


def register(sub: Any) -> None:
    """Add the ``robot`` sub-command; its options are the fields of ``RobotConfig``."""
    p = sub.add_parser(
        ROBOT.name,
        help=ROBOT.summary,
        description="A simulated robot (MuJoCo) records view pairs from its saccades and "
        "learns the Sigma-Pi map; then an actor-critic docks on the map, the retina code, "
        "retina+gaze codes and the true z (upper bound).",
    )
    add_dataclass_flags(p, RobotConfig)
    p.add_argument("--quick", action="store_true", help="a small run (under 3 minutes)")
    p.add_argument("--seeds", type=_seed, nargs="+", help="the seeds (default "
                   f"{' '.join(map(str, ROBOT.default_seeds))}, none of them tuned on; --quick: "
                   f"{' '.join(map(str, ROBOT.quick_seeds))})")  # fmt: skip
    p.add_argument("--out", required=True, help="folder for result.json and the figures")
    p.add_argument("--render", help="also write an animated GIF of one episode to this file")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_workers_flag(p, "learners run")
    p.set_defaults(func=cmd_robot)


def cmd_robot(args: argparse.Namespace) -> int:
    render = Path(args.render) if args.render else None
    if render is not None and render.suffix.lower() != ".gif":
        raise UsageError(f"--render must end in .gif, got {str(render)!r}")
    try:
        from sigmapi.envs.robot import mujoco_module

        mujoco_module()
    except ImportError as exc:
        raise UsageError(str(exc)) from None
    from sigmapi.experiments.robot_plots import write_gif

    base = QUICK if args.quick else RobotConfig()
    cfg = base.replace(**dataclass_values(args, RobotConfig))
    seeds = args.seeds or (ROBOT.quick_seeds if args.quick else ROBOT.default_seeds)
    if len(set(seeds)) != len(seeds):
        raise UsageError(f"--seeds must be distinct, got {' '.join(map(str, seeds))}")
    n_jobs = len(seeds) * len(cfg.states)
    workers = plan_workers(args.workers, job_memory(cfg), n_jobs=n_jobs).workers
    result = run_with_progress(cfg, seeds, disable=args.quiet or None, workers=workers)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "result.json"
    path.write_text(json.dumps(result.to_dict(), indent=1) + "\n", encoding="utf-8")
    paths = [path, *result.figure(out)]
    if render is not None:
        paths.append(write_gif(result.film(), render))
    if args.json:
        print(json.dumps(result.to_dict()))
    else:
        print(result.table())
    print(f"wrote {', '.join(map(str, paths))} ({result.seconds:.0f} s)", file=sys.stderr)
    return 0
