"""The reward-gated map measured: ``sigmapi reward --json`` run as a user runs it.

Usage (from the repository root)::

    python benchmarks/bench_reward.py                      # seeds 900-909: reward.json
    python benchmarks/bench_reward.py --figure docs/reward.png
    python benchmarks/bench_reward.py --seeds 0,1,2,3,4 --tag tuning -- --gate-eps 0.1

Writes ``benchmarks/results/reward.json`` (``--tag T``: ``reward-T.json``): the command, its
JSON (``methods``: frozen, gated and shuffled maps with their final success, episodes to 80 %,
magnification near the goal and quality away from it), its wall-clock and CPU seconds (the
command and its worker processes), the load average, the commit. Arguments after ``--`` go
to ``sigmapi reward`` (e.g. a variant of the gate). ``--figure PATH``: keep the run's figure
there.
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _common import commit, machine, write_result

RESULTS = Path(__file__).resolve().parent / "results"
SRC = Path(__file__).resolve().parents[1] / "src"


def main() -> None:
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1 :] if "--" in argv else []
    own = argv[: argv.index("--")] if "--" in argv else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="900,901,902,903,904,905,906,907,908,909",
                        help="seeds of the run (default 900-909, none tuned on)")  # fmt: skip
    parser.add_argument("--tag", help="a name for the result file (reward-TAG.json)")
    parser.add_argument("--figure", help="copy the run's figure to this path")
    args = parser.parse_args(own)
    exe = Path(sys.executable).with_name("sigmapi")
    cmd = [str(exe), "reward", "--json", "--quiet", "--seeds", *args.seeds.split(","), *extra]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        proc = subprocess.run([*cmd, "--out", out], capture_output=True, text=True, check=False)
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(cmd)} failed:\n{proc.stderr[-3000:]}")
        if args.figure:
            shutil.copyfile(Path(out) / "reward.png", args.figure)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    name = f"reward-{args.tag}.json" if args.tag else "reward.json"
    write_result(RESULTS / name, {
        "command": " ".join(["python benchmarks/bench_reward.py", *argv]),
        "sigmapi_command": " ".join(["sigmapi", *cmd[1:], "--out", "DIR"]),
        "commit": commit(SRC), "machine": machine(), "wall_s": round(wall, 1),
        "cpu_s": round(cpu, 1), "result": json.loads(proc.stdout),
    })  # fmt: skip


if __name__ == "__main__":
    main()
