"""Every figure in docs/, regenerated from the current code by one command.

    python docs/make_figures.py                 # all of them (the reward figure reruns its
                                                # benchmark: about 16 minutes on two cores)
    python docs/make_figures.py fig8-1d fig8    # some of them
    python docs/make_figures.py --list          # what makes each, and what it reads

Each figure is written into docs/ and recorded in docs/figures.json: the command that made it,
its inputs and the PNG's sha256. The inputs are what decides the picture: for a map's figure
the preset's resolved config, the seed and what the figure shows of the trained map (its
polarity and the winners of the four pairs); for a figure drawn from a results file that
file's sha256; for an environment's picture its id and reset seed.
``tests/docs/test_doc_figures.py`` fails when a committed figure no longer matches its record (a
preset or results file changed, the PNG was replaced by hand) and, for the 1-D map (the 2-D ones
in the slow tests), when today's code trains a map that the figure does not show.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
RECORD = DOCS / "figures.json"


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@dataclass(frozen=True)
class Recipe:
    """How one figure is made: ``make(path) -> inputs``, and the command a reader would run."""

    command: str
    make: Callable[[Path], dict[str, Any]]
    sources: tuple[str, ...] = field(default=())
    """Results files (repository paths) the figure is drawn from."""


# ----------------------------------------------------------------------------- a map's figure
def map_facts(preset: str, seed: int) -> tuple[Any, dict[str, Any]]:
    """The map of ``preset`` and ``seed`` trained by today's code, and what its Fig. 8 shows
    of it (without drawing): the inputs a map figure records."""
    import sigmapi
    from sigmapi.viz.figures import draw_figure

    cfg = sigmapi.load_preset(preset)
    model = sigmapi.SigmaPiSOM(cfg, seed=seed).fit()
    with tempfile.TemporaryDirectory() as tmp:
        facts = draw_figure("fig8", model, Path(tmp) / "f.png", label=f"{preset}, seed {seed}")
    shown = {"polarity": facts["polarity"], "winners": [int(w) for w in facts["winners"]]}
    return model, {"preset": preset, "seed": seed, "config": cfg.to_dict(), "shows": shown}


def _map_figure(preset: str, seed: int) -> Callable[[Path], dict[str, Any]]:
    def make(path: Path) -> dict[str, Any]:
        from sigmapi.viz.figures import draw_figure

        model, inputs = map_facts(preset, seed)
        draw_figure("fig8", model, path, label=f"{preset}, seed {seed}")
        return inputs

    return make


# ----------------------------------------------------------------------------- from results
def _from_json(source: str, draw: Callable[[dict[str, Any]], Any]) -> Callable[[Path], dict]:
    def make(path: Path) -> dict[str, Any]:
        data = json.loads((ROOT / source).read_text("utf-8"))
        draw(data).savefig(path, dpi=120)
        return {"source": source}

    return make


def _compare(data: dict[str, Any]) -> Any:
    from sigmapi.experiments.compare.figures import compare_figure

    return compare_figure(data)


def _stream(data: dict[str, Any]) -> Any:
    from sigmapi.experiments.stream.figures import stream_figure

    return stream_figure(data)


def _reward(path: Path) -> dict[str, Any]:
    """The reward figure holds every unit of every seed's maps, which reward.json does not:
    it is the figure of the benchmark's own run, and the run rewrites reward.json."""
    cmd = [sys.executable, "benchmarks/bench_reward.py", "--figure", str(path)]
    subprocess.run(cmd, cwd=ROOT, check=True)
    return {"source": "benchmarks/results/reward.json"}


# ----------------------------------------------------------------------------- runs and worlds
def _sweep(path: Path) -> dict[str, Any]:
    spec = "docs/sweep-example.toml"
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "sigmapi.cli", "sweep", spec, "--out", tmp, "--force",
               "--quiet"]  # fmt: skip
        subprocess.run(cmd, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        shutil.copyfile(Path(tmp) / "sweep.png", path)
    return {"spec": spec, "spec_sha256": sha256(ROOT / spec)}


def _render(env_id: str, seed: int) -> Callable[[Path], dict[str, Any]]:
    def make(path: Path) -> dict[str, Any]:
        import gymnasium as gym
        import matplotlib.image

        import sigmapi  # noqa: F401 (registers the environments)

        env = gym.make(env_id, render_mode="rgb_array")
        try:
            env.reset(seed=seed)
            matplotlib.image.imsave(path, env.render())
        finally:
            env.close()
        return {"env": env_id, "reset_seed": seed}

    return make


def _fig(preset: str, seed: int) -> str:
    return (f"sigmapi train --preset {preset} --seed {seed} --out m.npz && sigmapi figure fig8 "
            f"m.npz --label '{preset}, seed {seed}' --out FILE")  # fmt: skip


RECIPES: dict[str, Recipe] = {
    "fig8": Recipe(_fig("paper-2d", 100), _map_figure("paper-2d", 100)),
    "fig8-1d": Recipe(_fig("paper-1d", 0), _map_figure("paper-1d", 0)),
    "torus-fig8": Recipe(_fig("angles-2d", 0), _map_figure("angles-2d", 0)),
    "compare": Recipe("compare_figure(benchmarks/results/compare.json)",
                      _from_json("benchmarks/results/compare.json", _compare),
                      ("benchmarks/results/compare.json",)),
    "stream": Recipe("stream_figure(benchmarks/results/stream.json)",
                     _from_json("benchmarks/results/stream.json", _stream),
                     ("benchmarks/results/stream.json",)),
    "reward": Recipe("python benchmarks/bench_reward.py --figure docs/reward.png", _reward,
                     ("benchmarks/results/reward.json",)),
    "sweep-example": Recipe("sigmapi sweep docs/sweep-example.toml --out DIR (its sweep.png)",
                            _sweep),
    "reach-env": Recipe("gymnasium.make('sigmapi/GazeReach-v0', render_mode='rgb_array'), "
                        "reset(seed=0), render()", _render("sigmapi/GazeReach-v0", 0)),
    "robot-env": Recipe("gymnasium.make('sigmapi/RobotDock-v0', render_mode='rgb_array'), "
                        "reset(seed=0), render()", _render("sigmapi/RobotDock-v0", 0)),
}  # fmt: skip
"""Figure name (docs/NAME.png) -> how it is made."""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", help=f"figures to make (default: all): {list(RECIPES)}")
    parser.add_argument("--list", action="store_true", help="say what makes each figure")
    parser.add_argument("--record-existing", action="store_true",
                        help="record the named figures as they are, without making them: only "
                        "for a figure its command wrote together with its source (the reward "
                        "benchmark writes docs/reward.png and reward.json in one run)")  # fmt: skip
    args = parser.parse_args(argv)
    if args.list:
        for name, r in RECIPES.items():
            print(f"docs/{name}.png: {r.command}")
        return 0
    unknown = sorted(set(args.names) - set(RECIPES))
    if unknown:
        parser.error(f"unknown figures {unknown}; choose from {list(RECIPES)}")
    record = json.loads(RECORD.read_text("utf-8")) if RECORD.is_file() else {}
    for name in args.names or list(RECIPES):
        recipe, path = RECIPES[name], DOCS / f"{name}.png"
        print(f"docs/{name}.png: {recipe.command}", flush=True)
        if args.record_existing:
            if not recipe.sources:
                parser.error(f"{name} has no source file to record; make it instead")
            inputs = {"source": recipe.sources[0]}
        else:
            inputs = recipe.make(path)
        for source in recipe.sources:
            inputs[f"sha256 {source}"] = sha256(ROOT / source)
        record[name] = {"command": recipe.command, "inputs": inputs, "png_sha256": sha256(path)}
        RECORD.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n", "utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
