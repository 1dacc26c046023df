"""Do two checkouts give the same experiment results? Tiny runs of reach (1-D and 2-D), reward,
robot, stream, chain and compare, through the experiment registry, in one process per checkout;
their ``to_dict()`` compared value by value (timings left out).

    python benchmarks/bench_same_results.py --baseline-src OLD/src

(``git archive COMMIT src | tar -x -C /tmp/old`` makes ``/tmp/old/src``.) Prints each
difference (a value, or a key only one side has, e.g. a renamed config field) and the number
of values that differ; writes nothing. The robot needs ``sigmapi[robot]`` (MuJoCo).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

SRC = Path(__file__).resolve().parents[1] / "src"

CHILD = r"""
import json, sys
from sigmapi.experiments import REGISTRY

def clean(d):
    if isinstance(d, dict):
        return {k: clean(v) for k, v in d.items() if "second" not in k}
    return [clean(v) for v in d] if isinstance(d, list) else d

def fields(name):
    return set(REGISTRY[name].config_type.__dataclass_fields__)

out = {}
R = REGISTRY["reach"]
tiny = dict(block=10, final_episodes=10, backend="reference")
cfg = R.config_type().replace(dim=1, grid=7, map_shape=(6,), iterations=500, episodes=20,
                              max_episode_steps=30, **tiny)
out["reach 1-D"] = R.run(cfg, seeds=[0, 3]).to_dict()
from sigmapi.config import list_presets
small = "small-2d" if "small-2d" in list_presets() else "none"  # the 7x7 schedule, as named
cfg = R.config_type().replace(grid=7, map_shape=(7, 7), iterations=400, episodes=10, block=5,
                              final_episodes=5, backend="reference", preset=small,
                              code_width=0.5)
out["reach 2-D"] = R.run(cfg, seeds=[1]).to_dict()
W = REGISTRY["reward"]
cfg = W.config_type().replace(iterations=400, episodes=8, block=4, final_episodes=4, n_test=200)
out["reward"] = W.run(cfg, seeds=[0, 2]).to_dict()
S = REGISTRY["stream"]
small = ("map_shape=[7]", "x_shape=[7]", "y_shape=[7]")
cfg = S.config_type(overrides=("iterations=2000", "refine_pairs=2000", *small), dwells=(1, 4))
out["stream"] = S.run(cfg, seeds=[0]).to_dict()
C = REGISTRY["chain"]
cfg = C.config_type(overrides=(*small, "iterations=1500", "refine_rounds=0"), train_pairs=500,
                    n_test=300)
out["chain"] = C.run(cfg, seeds=[0]).to_dict()
P = REGISTRY["compare"]
its = "som_iterations" if "som_iterations" in fields("compare") else "baseline_iterations"
cfg = P.config_type(overrides=(*small, "iterations=1500"), train_pairs=500, n_test=300,
                    methods=("kohonen", "kohonen two-view"), **{its: 1500})
out["compare"] = P.run(cfg, seeds=[0]).to_dict()
if "--robot" in sys.argv:
    B = REGISTRY["robot"]
    old = "map_pairs" in fields("robot")
    sizes = {"map_pairs": 300, "map_iterations": 600} if old else {"train_pairs": 300,
                                                                    "iterations": 600}
    cfg = B.quick.replace(**sizes, eval_pairs=200, episodes=6, final_episodes=3, block=3,
                          grid=6, map_shape=(4, 4), max_steps=30)
    out["robot"] = B.run(cfg, seeds=[0, 5]).to_dict()
print(json.dumps(clean(out), default=str))
"""


def _results(src: Path, robot: bool) -> dict[str, Any]:
    env = {**os.environ, "PYTHONPATH": str(src)}
    argv = [sys.executable, "-c", CHILD, *(["--robot"] if robot else [])]
    r = subprocess.run(argv, env=env, capture_output=True, text=True, check=False, cwd="/")
    if r.returncode != 0:
        sys.exit(f"the run of {src} failed:\n{r.stderr}")
    return json.loads(r.stdout.splitlines()[-1])


def _diff(a: Any, b: Any, path: str, out: list[str]) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if k not in a or k not in b:
                out.append(f"{path}/{k}: only in {'baseline' if k in a else 'this checkout'}")
            else:
                _diff(a[k], b[k], f"{path}/{k}", out)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _diff(x, y, f"{path}[{i}]", out)
    elif a != b and not (a != a and b != b):  # NaN equals NaN here
        out.append(f"{path}: {a!r} -> {b!r}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline-src", type=Path, required=True)
    ap.add_argument("--src", type=Path, default=SRC, help="the checkout's src (default: this one)")
    ap.add_argument("--no-robot", action="store_true", help="leave the robot out (no MuJoCo)")
    args = ap.parse_args()
    old = _results(args.baseline_src, not args.no_robot)
    new = _results(args.src, not args.no_robot)
    found: list[str] = []
    _diff(old, new, "", found)
    print("\n".join(found) if found else "no difference")
    values = sum(": only in" not in f for f in found)
    print(f"{values} values differ; {len(found) - values} keys on one side only")


if __name__ == "__main__":
    main()
