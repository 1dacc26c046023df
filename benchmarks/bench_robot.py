"""The simulated robot measured: env speed, pixels against projection, the map from its views.

Usage (from the repository root; needs ``pip install -e '.[robot]'``)::

    python benchmarks/bench_robot.py speed [--baseline-src OLD/src]   # ~2 min on 2 cores
    python benchmarks/bench_robot.py pixels                           # 1,000 scenes, ~10 s
    python benchmarks/bench_robot.py map                              # 15 maps, ~6 min
    python benchmarks/bench_robot.py docking                          # the acceptance run
    python benchmarks/bench_robot.py docking --quick                  # sigmapi robot --quick
    python benchmarks/bench_robot.py docking --seeds 0,1,2 --tag tuning

Each writes one JSON file in ``benchmarks/results/``:

- ``robot-speed.json``: steps per second of ``sigmapi/RobotDock-v0`` under a random policy
  (the scripted reach included when the base docks), without rendering, rendering both
  cameras every step (``render_mode="rgb_array"``, ``env.render()``) and with the retina read
  from the rendered head camera (``retina="pixels"``), and the episode loop of the map's
  learner (``run_episodes`` on the map state, the agent learning). Wall and CPU seconds (the
  machine is shared: CPU time is the steadier number), the median and the best of
  ``--repeats`` runs, each in a fresh process; with ``--baseline-src`` the same on another
  checkout (e.g. the commit before a speed change), the code bases alternating, and the
  ratios.
- ``robot-pixels.json``: the ball's retinal position from the rendered head camera (the red
  blob's centroid) against the camera's exact projection of its centre, over ``--scenes``
  random scenes (ball placed, head after a saccade): RMS, mean, 99th percentile and largest
  distance in pixels, and the time to render a head-camera frame.
- ``robot-map.json``: the map learned from the robot's own view pairs (the experiment's
  ``learn_map``: 10,000 pairs, 40,000 iterations, 8x8 map) on ``--seeds`` (default 100-104,
  not the tuning seeds 0-2) at each ``--moved-share``, scored against the true body-centred
  direction with ``sigmapi evaluate``'s metrics (order R^2, fold score, ...).
- ``robot-docking.json`` (``--quick``: ``robot-docking-quick.json``; ``--tag T``:
  ``robot-docking-T.json``): ``sigmapi robot --json`` run as a user runs it (default seeds
  100-104, none tuned on; ``--quick``: its own seed), its JSON, and its wall-clock and CPU
  seconds (the command and its worker processes).
"""

from __future__ import annotations

import argparse
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import commit, machine, run_child, write_result

ROOT = Path(__file__).resolve().parent
RESULTS = ROOT / "results"
SRC = ROOT.parent / "src"
MODES = ("no_render", "render", "pixels", "learner_map")


# ------------------------------------------------------------------ children (fresh processes)
def _child_speed(mode: str, steps: int) -> dict[str, Any]:
    import gymnasium as gym
    import numpy as np

    import sigmapi

    kwargs: dict[str, Any] = {"grid": 12}
    if mode == "render":
        kwargs["render_mode"] = "rgb_array"
    if mode == "pixels":
        kwargs["retina"] = "pixels"
    env = gym.make("sigmapi/RobotDock-v0", **kwargs)
    if mode == "learner_map":
        from sigmapi.agents import ActorCriticConfig, actor_critic_for, run_episodes
        from sigmapi.envs import make_state_env
        from sigmapi.envs.robot import RobotViews
        from sigmapi.experiments.robot.map import robot_som_config

        source = RobotViews(12)
        cfg = robot_som_config(source.x_code, (8, 8), 2000, 0)
        model = sigmapi.SigmaPiSOM(cfg).fit(source.sample_views(500, np.random.default_rng(0)))
        state = make_state_env(env, "map", model)
        agent = actor_critic_for(state, ActorCriticConfig(), seed=1)
        run_episodes(state, agent, [0])  # warm: numba, first render contexts
        t0, c0 = time.perf_counter(), time.process_time()
        done, first = 0, 1
        while done < steps:
            ep = run_episodes(state, agent, list(range(first, first + 20)))
            done, first = done + int(ep.steps.sum()), first + 20
    else:
        rng = np.random.default_rng(0)
        env.reset(seed=0)
        env.step(0)
        t0, c0 = time.perf_counter(), time.process_time()
        for _ in range(steps):
            _, _, terminated, truncated, _ = env.step(int(rng.integers(4)))
            if mode == "render":
                env.render()
            if terminated or truncated:
                env.reset()
        done = steps
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    env.close()
    return {"steps": done, "wall_s": wall, "cpu_s": cpu,
            "max_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}  # fmt: skip


def _child_pixels(scenes: int, seed: int) -> dict[str, Any]:
    import numpy as np

    from sigmapi.envs.robot import Frames, Scene

    frames = Frames(Scene())
    rng = np.random.default_rng(seed)
    errors, render_s, missed = [], 0.0, 0
    for _ in range(scenes):
        frames.place_still(rng.random(2))
        frames.saccade(rng)
        uv = frames.retinal_pixels("projection")
        t0 = time.perf_counter()
        blob = frames.retinal_pixels("pixels")
        render_s += time.perf_counter() - t0
        if blob is None:
            missed += 1
            continue
        errors.append(blob - uv)
    e = np.array(errors)
    d = np.sqrt((e**2).sum(axis=1))
    return {"scenes": scenes, "seed": seed, "blob_missing": missed,
            "rms_px": float(np.sqrt((d**2).mean())), "mean_px": e.mean(axis=0).tolist(),
            "p99_px": float(np.quantile(d, 0.99)), "max_px": float(d.max()),
            "head_frame_ms": 1e3 * render_s / scenes,
            "image_px": frames.scene.head_size}  # fmt: skip


def _child_map(seeds: list[int], moved: list[float]) -> dict[str, Any]:
    from sigmapi.experiments.robot.config import PLAN, RobotConfig
    from sigmapi.experiments.robot.map import evaluation_pairs, learn_map, score_map

    base = RobotConfig()
    evaluation = evaluation_pairs(base)
    rows = []
    for share in moved:
        cfg = base.replace(moved_share=share)
        for seed in seeds:
            t0 = time.perf_counter()
            views = PLAN.rng(seed, "views")
            model = learn_map(cfg, seed, views)  # the experiment's own map of this seed
            m = score_map(model, *evaluation)
            rows.append({"seed": seed, "moved_share": share,
                         "seconds": round(time.perf_counter() - t0, 1),
                         **{k: round(v, 4) if isinstance(v, float) else v
                            for k, v in m.items()}})  # fmt: skip
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    return {"rows": rows, "config": {k: v for k, v in base.to_dict().items()
                                     if k in ("grid", "code_width", "map_shape", "train_pairs",
                                              "iterations", "eval_pairs")}}  # fmt: skip


# ------------------------------------------------------------------ parents
def _ratio(a: float, b: float) -> float:
    return a / b


def _speed(args: argparse.Namespace) -> dict[str, Any]:
    bases = {"this": SRC}
    if args.baseline_src:
        bases["baseline"] = Path(args.baseline_src).resolve()
    runs: dict[str, dict[str, list[dict[str, Any]]]] = {b: {m: [] for m in MODES} for b in bases}
    for r in range(args.repeats):
        for mode in MODES:
            n = {"render": args.steps // 8, "pixels": args.steps // 3}.get(mode, args.steps)
            for name, src in bases.items():
                out = run_child(__file__, ["speed", mode, str(n)], src)
                runs[name][mode].append(out)
                rate = f"{out['steps'] / out['cpu_s']:.0f} per CPU s"
                print(f"repeat {r} {name} {mode}: {rate}", file=sys.stderr)
    summary: dict[str, Any] = {}
    for name in bases:
        summary[name] = {}
        for mode, outs in runs[name].items():
            steps = [o["steps"] for o in outs]
            cpu = [o["cpu_s"] for o in outs]
            wall = [o["wall_s"] for o in outs]
            per_cpu = list(map(_ratio, steps, cpu))
            summary[name][mode] = {
                "steps_per_s_wall": round(statistics.median(map(_ratio, steps, wall)), 1),
                "steps_per_s_cpu": round(statistics.median(per_cpu), 1),
                "steps_per_s_cpu_best": round(max(per_cpu), 1),
                "ms_per_step_cpu": round(1e3 / statistics.median(per_cpu), 3),
                "ms_per_step_cpu_best": round(1e3 / max(per_cpu), 3),
                "max_rss_mb": round(max(o["max_rss_mb"] for o in outs), 1),
            }
        this = summary[name]
        this["render_over_no_render_cpu"] = round(
            this["render"]["ms_per_step_cpu"] / this["no_render"]["ms_per_step_cpu"], 2
        )
    if "baseline" in bases:
        old, new = summary["baseline"], summary["this"]
        summary["speedup_over_baseline_cpu"] = {
            m: round(old[m]["ms_per_step_cpu"] / new[m]["ms_per_step_cpu"], 2) for m in MODES
        }
        summary["speedup_over_baseline_cpu_best"] = {
            m: round(old[m]["ms_per_step_cpu_best"] / new[m]["ms_per_step_cpu_best"], 2)
            for m in MODES
        }
        summary["baseline_commit"] = commit(bases["baseline"])
    return {"runs": runs, "summary": summary, "repeats": args.repeats, "steps": args.steps}


def _docking(args: argparse.Namespace) -> dict[str, Any]:
    exe = Path(sys.executable).with_name("sigmapi")
    cmd = [str(exe), "robot", "--json", "--quiet"]
    if args.quick:
        cmd.append("--quick")
    if args.seeds_given:
        cmd += ["--seeds", *args.seeds.split(",")]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        proc = subprocess.run([*cmd, "--out", out], capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr[-3000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"sigmapi_command": " ".join(["sigmapi", *cmd[1:], "--out", "DIR"]),
            "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
            "result": json.loads(proc.stdout)}  # fmt: skip


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        what, *rest = sys.argv[2:]
        if what == "speed":
            out = _child_speed(rest[0], int(rest[1]))
        elif what == "pixels":
            out = _child_pixels(int(rest[0]), int(rest[1]))
        else:
            out = _child_map([int(s) for s in rest[0].split(",")],
                             [float(m) for m in rest[1].split(",")])  # fmt: skip
        print(json.dumps(out))
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("speed", "pixels", "map", "docking"))
    parser.add_argument("--repeats", type=int, default=5, help="speed: runs per case")
    parser.add_argument("--steps", type=int, default=3000,
                        help="speed: steps a run (rendering: 1/8, pixels: 1/3)")  # fmt: skip
    parser.add_argument("--baseline-src", help="speed: another checkout's src/ to compare")
    parser.add_argument("--scenes", type=int, default=1000, help="pixels: random scenes")
    parser.add_argument("--seeds", default=None, help="map, docking: seeds (default 100-104)")
    parser.add_argument("--quick", action="store_true", help="docking: sigmapi robot --quick")
    parser.add_argument("--tag", help="docking: a name for the result file")
    parser.add_argument("--moved-share", default="0,0.1,0.3", help="map: moved shares")
    args = parser.parse_args()
    args.seeds_given = args.seeds is not None
    args.seeds = args.seeds or "100,101,102,103,104"
    t0 = time.perf_counter()
    if args.what == "speed":
        result = _speed(args)
    elif args.what == "pixels":
        result = run_child(__file__, ["pixels", str(args.scenes), "0"], SRC)
    elif args.what == "map":
        result = run_child(__file__, ["map", args.seeds, args.moved_share], SRC)
    else:
        result = _docking(args)
    result["command"] = " ".join(["python benchmarks/bench_robot.py", *sys.argv[1:]])
    result["seconds"] = round(time.perf_counter() - t0, 1)
    result["commit"] = commit(SRC)
    result["machine"] = machine()
    name = args.what
    if args.what == "docking" and (args.quick or args.tag):
        name += f"-{args.tag or 'quick'}"
    write_result(RESULTS / f"robot-{name}.json", result)


if __name__ == "__main__":
    main()
